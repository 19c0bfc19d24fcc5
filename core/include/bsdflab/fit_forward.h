// Deterministic forward model for fitting: physical parameters -> reflectance observables.
//
// The material (top to bottom): an exterior of real index n_e; one coherent thin film of
// Cauchy index n_f(lambda) = A + B / lambda^2 (lambda in nm, B in nm^2) and thickness d; a
// NON-SCATTERING slab of real index n_s > n_e, thickness h (um) and melanin-like absorption
// sigma_a(lambda) = sigma_550 (lambda / 550 nm)^-exponent (1/um); a Lambertian base of
// albedo rho. Interfaces are smooth and planar; the film is the core's Airy film
// (thin_film.h), unpolarised light averages s and p at each crossing, the slab adds
// intensities (incoherent), as in bsdflab.oracles.CoatedDiffuseOracle, which is the
// independent reference (tmm optics) that tests compare this model against.
//
// Observables per data row (c_i, c_o cosines of the incident / outgoing polar angles):
//   specular  R(c_i)                                 the film's mirror reflectance,
//   diffuse   pi f(c_i, c_o)                         reflectance factor of the base light,
//   total     R(c_i) + int f cos d omega             hemispherical (specular included).
// With the slab-side cosine mu(c) = sqrt(1 - (n_e/n_s)^2 (1 - c^2)), A(c) = exp(-tau/mu(c)),
// tau = sigma_a h, T(c) the film's transmittance from the exterior (= from the slab side
// for lossless media) and eta = n_s / n_e:
//   pi f  = T(c_i) A(c_i) rho A(c_o) T(c_o) / (eta^2 (1 - rho gamma)),
//   gamma = 2 int_0^mu_c mu e^{-2 tau/mu} d mu                      (total internal reflection)
//         + 2 (n_e/n_s)^2 int_0^1 c e^{-2 tau/mu(c)} (1 - T(c)) dc,  mu_c = sqrt(1 - 1/eta^2),
//   albedo = T(c_i) A(c_i) rho L / (eta^2 (1 - rho gamma)),  L = 2 int_0^1 c A(c) T(c) dc.
// Both integrals are Gauss-Legendre in the exterior cosine c, where the integrand is smooth
// (the critical-angle kink of the slab-side cosine maps to c = 0).
//
// Thickness spread: a measured spot averages many scales whose film thickness is normal
// with mean d and standard deviation s; every observable is averaged over that
// distribution by Gauss-Hermite quadrature (nodes d + sqrt(2) s x_k, clamped at 0 nm).
//
// All quadrature nodes come from the caller (numpy's leggauss / hermgauss), so the model
// has no hidden accuracy constants. Evaluation allocates nothing per row and is spread
// over threads by (parameter set, wavelength); it is thread-safe and const.
#pragma once
#include <cstddef>
#include <vector>

namespace bsdflab::fit {

enum Geometry : int { kSpecular = 0, kDiffuse = 1, kTotal = 2 };

// Columns of one parameter set, in this order.
enum Param : int {
    kThickness = 0,   // film thickness mean, nm
    kSpread,          // film thickness standard deviation, nm
    kCauchyA,         // film index A
    kCauchyB,         // film index B, nm^2
    kSubstrate,       // slab index n_s (> n_e)
    kExterior,        // exterior index n_e
    kSigma550,        // slab absorption at 550 nm, 1/um
    kExponent,        // absorption exponent (sigma_a ~ lambda^-exponent)
    kSlabUm,          // slab thickness, um
    kAlbedo,          // base albedo in [0, 1]
    kParamCount
};

struct Observation {
    int geometry;     // Geometry
    int wavelength;   // index into the model's wavelength list
    double cos_in, cos_out; // cos_out is used by diffuse rows only
};

class ForwardModel {
  public:
    // gh_x, gh_w: Gauss-Hermite nodes/weights (weight e^{-x^2}); gl_x, gl_w: Gauss-Legendre
    // on [-1, 1]. Throws std::invalid_argument on inconsistent inputs.
    ForwardModel(std::vector<double> wavelengths_nm, std::vector<Observation> rows, std::vector<double> gh_x,
                 std::vector<double> gh_w, std::vector<double> gl_x, std::vector<double> gl_w);

    std::size_t rows() const { return rows_.size(); }

    // params: (count, kParamCount) row-major; out: (count, rows()) row-major. A parameter
    // set outside the model's domain (non-finite, d < 0, s < 0, n_f <= 0, n_s <= n_e, ...)
    // gives NaN for all its rows. Threads over (set, wavelength); call without the GIL.
    void evaluate(const double *params, std::size_t count, double *out) const;

  private:
    void evaluate_wavelength(const double *p, std::size_t wl, double *out) const;

    std::vector<double> wavelengths_;
    std::vector<Observation> rows_;
    std::vector<std::vector<std::size_t>> rows_at_; // [wavelength] -> row indices
    std::vector<bool> hemisphere_at_;               // any diffuse/total row at that wavelength
    std::vector<double> gh_x_, gh_w_;               // weights normalised to sum 1
    std::vector<double> c_, c_w_;                   // Gauss-Legendre on [0, 1]
};

} // namespace bsdflab::fit
