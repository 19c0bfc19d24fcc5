// The named parts of AddingDoubling::solve (adding_doubling_solve.cpp), private to the
// solver: the boundaries' operators and the top's (adding_doubling_boundaries.cpp), a slab
// by doubling (adding_doubling_slab.cpp), adding from the base up and the stack's four
// operators (adding_doubling_adding.cpp), spectral interpolation of what lies below a rough
// top (adding_doubling_spectral.cpp), and the query values of one (channel, order)
// (adding_doubling_queries.cpp). One grid of N cosines throughout: the n nodes, then the
// zero-weight extras (adding_doubling_ops.h).
#pragma once
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>
#include "bsdflab/adding_doubling.h"
#include "bsdflab/adding_doubling_ops.h"

namespace bsdflab {

// The reflection of everything below a rough top, solved once per solver and shared with
// its with_top copies.
struct AddingDoubling::Inner {
    std::mutex mutex;
    bool ready = false;
    std::vector<ad::Op> R;  // [channel * orders + order], on the nodes
};

} // namespace bsdflab

namespace bsdflab::ad {

bool is_delta(const BSDF &b);
// A rough interface's alpha (0: not rough, or a pass-through).
double rough_alpha(const BSDF &b);
// Distinct values of v (sorted) and, per entry of v, its index among them.
std::vector<double> distinct(const std::vector<double> &v, std::vector<int> &index);
std::vector<double> signed_cos(const std::vector<double> &mu, double sign);
// An operator's kernel at (channel c, order m) from fourier_kernel's layout.
std::vector<double> kernel_at(const std::vector<double> &coef, std::size_t rows, std::size_t cols, int C,
                              int M, int c, int m);

// The sizes every part shares: channels C, orders M, half-period azimuth samples H, n
// nodes and N grid cosines.
struct Sizes {
    int C = 0, M = 0, H = 0, n = 0;
    std::size_t N = 0;
};

// -- boundary operators (adding_doubling_boundaries.cpp) --------------------------------

// A delta boundary's weights for `lobe` at every grid cosine (signed by `sign`), as [c][i].
std::vector<double> delta_table(const BSDF &b, const std::vector<double> &grid, double sign, uint32_t lobe,
                                int C);

// What the solve needs of boundary j >= 1 at one grid: kernels in fourier_kernel's layout
// (non-delta), or delta parts as [channel][cosine] (delta); the transmissions and the
// reflection from below only for an interior boundary.
struct BoundaryOperators {
    bool delta = false, interior = false;
    std::vector<double> Rt, Td, Rb, Tu;

    Op op(const std::vector<double> &a, const Sizes &s, int c, int m) const;
    LayerOperators layer(const Sizes &s, int c, int m) const;  // an interior boundary's four
};

// Boundary b's operators on `grid` (upward cosines); a smooth interior boundary between
// media of unequal index (index_matched false) is refused (std::invalid_argument): such
// stacks are solved by AddingDoubling::solve_snell (adding_doubling_snell.cpp) instead.
BoundaryOperators boundary_operators(const BSDF &b, bool interior, bool index_matched,
                                     const std::vector<double> &grid, const Sizes &s);

// The top, seen from the first slab: its reflection from below on the grid, and for a
// rough top its transmissions between the query cosines and the nodes.
struct TopOperators {
    bool smooth = false;
    std::vector<double> Rb;      // smooth: delta parts [channel][cosine]; rough: kernels N x N
    std::vector<double> Td, Tu;  // rough only: N x in_cos (down) and out_cos x N (up) kernels

    Op rb(const Sizes &s, int c, int m) const;
};

// A smooth top by its delta weights; a rough top's lobes, narrower than the nodes resolve,
// by product integration on fine nodes (sub-panels of fine_step * alpha radians) against
// the interpolant of what lies below.
TopOperators top_operators(const BSDF &top, bool smooth, const std::vector<double> &grid,
                           const std::vector<double> &mu, const std::vector<double> &w,
                           const std::vector<double> &breaks, const std::vector<double> &in_cos,
                           const std::vector<double> &out_cos, const ADSettings &settings, const Sizes &s);

// A rough top over grid extras (the pairs below a transmissive stack: inside cosines at
// the base): top_operators' kernels, with the reflection from below N x N. Its node rows
// are top_operators' (projected in the row); an extra's row is projected in its columns
// (a viewer extra reads the lobe against the smooth radiance at the nodes); between two
// extras it is 0: that unscattered beam meets the lobe at one direction, which the caller
// evaluates directly.
TopOperators rough_top_with_extras(const BSDF &top, const std::vector<double> &grid,
                                   const std::vector<double> &mu, const std::vector<double> &w,
                                   const std::vector<double> &breaks, const std::vector<double> &in_cos,
                                   const std::vector<double> &out_cos, const ADSettings &settings,
                                   const Sizes &s);

// -- a slab by doubling (adding_doubling_slab.cpp) ----------------------------------------

// Slab j's operators at every (channel, order): its phase function's coefficients on the
// grid (orders beyond its own are unscattered).
class SlabOperators {
  public:
    SlabOperators(const ADSlab &slab, const std::vector<double> &grid, const ADSettings &settings, int M);
    // All four operators (the slab is up-down symmetric).
    LayerOperators layer(int c, int m, const Grid &g) const;
    // Reflection from above of the slab lying on a medium of reflection R.
    Op reflect_over(int c, int m, const Grid &g, const Op &R) const;

  private:
    Op identity() const;
    Op exp_tau(double tau) const;
    void thin(int m, double delta, double omega, Op &R, Op &T) const;

    const ADSlab *slab_;
    const std::vector<double> *grid_;
    double thin_depth_;
    int orders_ = 0;  // scattering orders; 0 when it does not scatter
    std::vector<double> pr_, pt_;
};

// -- adding (adding_doubling_adding.cpp) -----------------------------------------------

// Reflection of everything below the top (seen from the first slab), from the base up.
// below[j] is boundary j (1..K), slabs[j] slab j (0..K-1).
Op inner_reflection(const std::vector<BoundaryOperators> &below, const std::vector<SlabOperators> &slabs,
                    const Sizes &s, int c, int m, const Grid &g);
// The whole stack as one layer, top down: the top's internal reflection, then slab,
// boundary, ..., slab, and the base's internal reflection (their transmissions to the
// outside are applied by the caller).
LayerOperators stack_operators(const TopOperators &top, const std::vector<BoundaryOperators> &below,
                               const std::vector<SlabOperators> &slabs, const Sizes &s, int c, int m,
                               const Grid &g);

// -- spectral interpolation (adding_doubling_spectral.cpp) -----------------------------

// The channels whose inner reflection is solved: every stride-th and the last (all when
// fewer than 4 would remain; the rest are interpolated in wavelength).
std::vector<int> solved_channels(int C, int stride);
// The operators R[c * M + m] of the channels not in `solved`, cubic Lagrange in wavelength
// on the 4 nearest solved channels.
void interpolate_channels(std::vector<Op> &R, const std::vector<double> &wavelengths,
                          const std::vector<int> &solved, int M);

// -- query values of one (channel, order) (adding_doubling_queries.cpp) ---------------

// A smooth top: the stack's reflection Y at the extras (xo rows, xi columns), V Qo x Qi.
void smooth_top_values(const Op &Y, const std::vector<int> &xo, const std::vector<int> &xi, std::size_t N,
                       double *V);
// A rough top: Tu W (Y_D + Y_K W) Td at the query cosines, added to V (Qo x Qi).
void rough_top_values(const Op &Y, const std::vector<double> &Td, const std::vector<double> &Tu,
                      const Grid &g, std::size_t N, std::size_t Qo, std::size_t Qi, double *V);
// A two-sided stack: per pair p, the stack operator op[p] (0 Rt, 1 Td, 2 Rb, 3 Tu) at the
// extras (row[p], col[p]).
void two_sided_values(const LayerOperators &S, const std::vector<int> &op, const std::vector<int> &row,
                      const std::vector<int> &col, int n, std::size_t N, double *V);

} // namespace bsdflab::ad
