// A deterministic solver for layered BSDFs: adding-doubling (van de Hulst 1980; Jakob et
// al. 2014, "A comprehensive framework for rendering layered materials") in a Fourier
// basis over the propagation-azimuth difference and Gauss-Legendre nodes in mu = |cos|.
//
// The stack is the PFMC model's (layered.h): boundaries 0..K (0 the top, K the base) and
// slabs 0..K-1, with the real index of every medium (media[0] the exterior, media[j+1]
// slab j). Every boundary is one of the core's own BSDFs, and the solver's operators come
// from its values: a non-delta boundary (rough dielectric / conductor, with or without a
// film, multiscatter or not; Lambertian) by a cosine transform of eval() over azimuth at
// every pair of node cosines; a delta boundary (smooth, with or without a film) by the
// weights sample() returns for its delta lobes. So the solver and the estimator share
// one definition of every interface.
//
// Radiance is expanded as sum_m L^m(mu) cos(m dphi) and sampled at nodes mu_j (weights
// w_j) on panels of (0, 1] cut at the critical cosines of every index step (the same
// node values in every medium; with a smooth interior interface between unequal indices,
// instead the same nodes in p = n sin(theta) in every medium: solve_snell). Order m of an operator acts as
//     (O L)_i = D_i L_i + sum_j K_ij W_j L_j,   W_j = pi (1 + [m = 0]) mu_j w_j,
// with its delta part D (unscattered beam, specular bounce) kept apart from its kernel K
// (a BSDF value f, without the cosine). Each (wavelength, order) is an independent task
// (threads); a slab comes from a single-scattering layer of depth <= thin_depth with a
// Richardson-corrected start (its O(delta^2) error removed), doubled to its depth; the
// adding equations join slabs and boundaries from the base up.
//
// What eval returns: reflection from above (wi.z > 0, wo.z > 0), f |cos theta_o| as
// Layered.eval, without the top's delta lobe: for a rough top, its own reflection is
// evaluated directly (exact) and the rest (light that entered the stack) by
// adding-doubling, the query directions entering through the top's transmission
// kernels; for a smooth top the query cosines are zero-weight extra nodes inside the
// first slab (Nystrom extension) and the top's transmittances are applied at the ends.
// Transmission through the stack (both ways) and reflection from below are solved for a
// transmissive stack with smooth top and base (two_sided()): the stack's four operators
// from the adding equations, every query cosine a zero-weight extra node inside the first
// or last slab, the Fresnel transmittances at the ends. A smooth top over a rough
// dielectric base (every_pair()): the same operators, the base's transmission kernels
// product-integrated against the radiance at the nodes at the exit (and at the entry of
// light from below), its own reflection from below evaluated directly; and a rough top
// over a smooth dielectric base (every_pair()), the top's kernels product-integrated the
// same way above, the base's query cosines extras (over a rough base, both lobes on
// common fine nodes). Other stacks return 0 there.
#pragma once
#include <memory>
#include <mutex>
#include <vector>
#include "bsdf.h"

namespace bsdflab {

struct ADSlab {
    double thickness = 0.0;       // um
    std::vector<double> sigma_a;  // 1/um per channel
    double sigma_s = 0.0;         // 1/um, grey
    double g = 0.0;               // Henyey-Greenstein asymmetry (0: isotropic)
};

struct ADSettings {
    int nodes = 16;                  // Gauss-Legendre nodes per panel
    int orders = 0;                  // Fourier orders (0: automatic, see orders())
    double thin_depth = 1.0 / 4096;  // optical depth of the doubling's start
    double order_tolerance = 1e-6;   // automatic orders: HG coefficients below this
    int azimuth_samples = 0;         // half-period samples of eval (0: automatic)
    bool film_lookup = false;        // boundaries' films from their cosine lookups (film_lookup.h)
    int spectral_stride = 1;         // rough top: what lies below it solved at every stride-th
                                     // channel (and the last), cubic in wavelength between
    double fine_step = 0.25;         // rough top: fine sub-panels of fine_step * alpha radians
};

class AddingDoubling {
  public:
    // boundaries: K + 1 core BSDFs (top first, base last); media: K + 2 real indices
    // (exterior, slab 0 .. slab K-1, the medium below the base or 0 when it is opaque).
    AddingDoubling(std::vector<double> wavelengths, std::vector<std::shared_ptr<const BSDF>> boundaries,
                   std::vector<double> media, std::vector<ADSlab> slabs, ADSettings settings);

    int channels() const { return static_cast<int>(wavelengths_.size()); }
    int orders() const { return orders_; }
    int azimuth_samples() const { return half_samples_; }
    const std::vector<double> &nodes() const { return mu_; }
    const std::vector<double> &weights() const { return w_; }
    // A transmissive stack whose every pair is solved (transmission both ways, reflection
    // from below): a smooth top and a smooth dielectric base around at least one slab.
    bool two_sided() const { return two_sided_; }
    // Whether every pair is solved: two_sided(), a transmissive stack with a smooth or
    // rough top and a rough dielectric base (its exits by product integration:
    // eval_rough_base), or one with a rough top and a smooth dielectric base (the top's:
    // eval_rough_top).
    bool every_pair() const { return two_sided_ || rough_base_exit_ || rough_top_exit_; }
    // Largest measured error of the film lookups used (-1: none).
    double film_lookup_error() const { return film_lookup_error_; }
    // f |cos theta_o| for n direction pairs (rows of 3), written to out (n x channels);
    // scattered_only leaves out a rough top's own reflection (what a table stores).
    void eval(const double *wi, const double *wo, std::size_t n, double *out,
              bool scattered_only = false) const;

    // The same solver with another top boundary (a rough top: e.g. another film
    // thickness). What lies below the top is solved once and shared between the two.
    std::shared_ptr<AddingDoubling> with_top(std::shared_ptr<const BSDF> top) const;

  private:
    struct Inner;  // the reflection of everything below a rough top, per (channel, order)
    // Two-sided queries (two_sided()): zero-weight extra cosines (inside the first slab for
    // directions above the stack, inside the last for directions below) and, per pair, the
    // stack operator it reads (0 Rt, 1 Td, 2 Rb, 3 Tu) at (row, col) among the extras.
    struct Queries {
        std::vector<double> cosines;
        std::vector<int> op, row, col;
    };
    void solve(const std::vector<double> &out_cos, const std::vector<double> &in_cos,
               std::vector<double> &values, const Queries *two_sided = nullptr) const;
    void eval_two_sided(const double *wi, const double *wo, std::size_t n, double *out) const;
    // solve's rough top over a delta reflection path: Y's delta part (YD, n per task) between
    // the top's kernels on its fine nodes, added to values, in blocks of fine nodes.
    void fine_delta_product(const std::vector<double> &fine_down, const std::vector<double> &mu_f,
                            const std::vector<double> &w_f, const std::vector<double> &B,
                            const std::vector<double> &YD, const std::vector<double> &out_cos,
                            const std::vector<double> &in_cos, std::vector<double> &values) const;
    // The pairs with wi.z < 0 or wo.z < 0 of a smooth or rough top over a rough dielectric
    // base (adding_doubling_exits.cpp): the stack's operators with a smooth top's refracted
    // query cosines as extras, the base's kernels product-integrated at the exit and the
    // entry (a rough top's too, the beam between the two lobes on common fine nodes).
    void eval_rough_base(const double *wi, const double *wo, std::size_t n, double *out,
                         bool scattered_only) const;
    // The pairs with wi.z < 0 or wo.z < 0 of a rough top over a smooth dielectric base
    // (adding_doubling_top_exits.cpp): the stack's operators with the base's refracted query
    // cosines as extras, the top's kernels product-integrated at the exit and the entry
    // above, its point values (the unscattered beam's) evaluated directly.
    void eval_rough_top(const double *wi, const double *wo, std::size_t n, double *out) const;
    // The solve of a stack with a smooth interior interface between unequal indices
    // (adding_doubling_snell.cpp): one node set in the Snell invariant p = n sin(theta),
    // the same p in every medium, so its transmission is diagonal (docs/solvers.md).
    // Query cosines (out_cos, in_cos) lie inside the first slab; a two-sided query's
    // `cosines` hold p values.
    void solve_snell(const std::vector<double> &out_cos, const std::vector<double> &in_cos,
                     std::vector<double> &values, const Queries *two_sided) const;
    // Whether the media on either side of boundary j have one index.
    bool index_matched(std::size_t j) const;
    // The quadrature weights W of order m on a grid of N cosines (0 on the extras).
    std::vector<double> order_weights(int m, std::size_t N) const;

    std::vector<double> wavelengths_;
    std::vector<std::shared_ptr<const BSDF>> boundaries_;
    std::vector<double> media_;
    std::vector<ADSlab> slabs_;
    ADSettings settings_;
    std::vector<double> breaks_;  // critical cosines cutting (0, 1] into panels
    std::vector<double> mu_, w_;  // nodes and weights on (0, 1]
    int orders_ = 1;
    int half_samples_ = 64;
    bool smooth_top_ = false;
    bool two_sided_ = false;
    bool rough_base_exit_ = false;  // every_pair() through a rough dielectric base
    bool rough_top_exit_ = false;   // every_pair() through a rough top (smooth dielectric base)
    bool delta_below_ = false;      // a delta boundary below the top (a delta reflection path)
    bool snell_ = false;  // a smooth interior interface between unequal indices (solve_snell)
    double n_max_ = 0.0;  // snell_: the densest slab's index, in which mu_ are the node cosines
    double film_lookup_error_ = -1.0;
    std::shared_ptr<Inner> inner_;
};

// Fourier orders after which Henyey-Greenstein's coefficients fall below `tolerance` of
// the largest (the pole of the phase function in complex azimuth bounds their decay).
int hg_orders_needed(double g, double tolerance);

} // namespace bsdflab
