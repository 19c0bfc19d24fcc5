// The operator algebra of the adding-doubling solver (adding_doubling.h), for one
// wavelength and one Fourier order on a grid of N cosines: the first n are quadrature
// nodes (weights W_j), the remaining N - n zero-weight extra cosines (Nystrom
// extension: exact values there, they never feed back into the nodes). An operator is
// D + K W with a diagonal delta part D and a kernel K (N x N, row = output); an empty
// vector means zero. Keeping D apart makes products and inverses exact at the extras:
//     (D1 + K1 W)(D2 + K2 W) = D1 D2 + (D1 K2 + K1 D2 + K1 W K2) W,
//     (I - D - K W)^-1 = G + (X G) W,  G = (I - D)^-1,  X = (I - G K W)^-1 G K,
// where I - G K W is block triangular (W vanishes on the extras), so only its n x n
// block is factorised.
#pragma once
#include <cstdint>
#include <vector>
#include "bsdf.h"

namespace bsdflab::ad {

struct Grid {
    int n = 0;              // weighted nodes
    int N = 0;              // nodes + extras
    std::vector<double> W;  // N: pi (1 + [m = 0]) mu_j w_j, 0 on extras
};

struct Op {
    std::vector<double> D;  // N, or empty
    std::vector<double> K;  // N x N row-major, or empty
};

struct LayerOperators {
    Op Rt, Td, Rb, Tu;  // reflection from the top / bottom, transmission down / up
};

Op mul(const Op &a, const Op &b, const Grid &g);           // a after b
Op add(const Op &a, const Op &b);
Op inverse_one_minus(const Op &a, const Grid &g);          // (I - a)^-1
// Reflection from the top of `top` lying on a medium whose reflection from above is R.
Op reflect_over(const LayerOperators &top, const Op &R, const Grid &g);
// The layer `a` lying on the layer `b`: all four operators of the pair (the adding equations).
LayerOperators add_layers(const LayerOperators &a, const LayerOperators &b, const Grid &g);
// A homogeneous up-down symmetric layer (Rt = Rb = R, Td = Tu = T) stacked on itself.
void double_symmetric(Op &R, Op &T, const Grid &g);

} // namespace bsdflab::ad

// -- discretisation (adding_doubling_kernels.cpp) -------------------------------------
namespace bsdflab::ad {

// Gauss-Legendre nodes and weights on (0, 1] cut at `breaks`; a panel [a, b] starting at
// a critical cosine a > 0 is mapped by mu = sqrt(a^2 + (b^2 - a^2) u^2), which makes the
// sqrt(mu^2 - a^2) of the Fresnel terms beyond it analytic in u.
void panel_nodes(int per_panel, std::vector<double> breaks, std::vector<double> &mu, std::vector<double> &w);

// Product integration for kernels narrower than the nodes resolve (a rough top's
// lobes): fine nodes mu_f (weights w_f in mu) on every panel, composite 4-point Gauss in
// theta = acos(mu) with sub-panels no wider than h radians, and B (fine x n, row-major)
// with B[f][k] = l_k(mu_f), the Lagrange basis of node k's panel in its own variable u
// (zero outside the panel). sum_k B[f][k] Y_k interpolates a function smooth on the
// panels, so a narrow kernel K integrates against it exactly as
// sum_f K(mu_f) mu_f w_f sum_k B[f][k] Y_k.
void product_nodes(int per_panel, std::vector<double> breaks, double h, std::vector<double> &mu_f,
                   std::vector<double> &w_f, std::vector<double> &B);

// Cosine coefficients over the propagation-azimuth difference of f = eval(wi, wo) /
// |wo.z| with wi.z = out_z[i], wo.z = in_z[j]: out[((i * in + j) * C + c) * M + m], from
// 2 H samples of one period (the BSDF is isotropic: H + 1 evaluations on [0, pi]).
std::vector<double> fourier_kernel(const BSDF &b, const std::vector<double> &out_z,
                                   const std::vector<double> &in_z, int M, int H);

// fourier_kernel of a kernel with fine rows (fine_rows) or fine columns, product-integrated
// onto the n nodes on the fly (the fine kernel is never stored): rows (or columns) k of the
// result are sum_f B[f][k] scale[f][k] K_f. Layout: n x other (fine rows) or other x n,
// then [channel][order] as fourier_kernel.
std::vector<double> projected_kernel(const BSDF &b, const std::vector<double> &fine_z,
                                     const std::vector<double> &other_z, bool fine_rows,
                                     const std::vector<double> &B, const std::vector<double> &scale, int n,
                                     int M, int H);

// The weight per channel of a delta BSDF's `lobe` (kDeltaReflection or
// kDeltaTransmission, alone) for wi of cosine z; the sampled direction's |z| in cos_out.
void delta_weight(const BSDF &b, double z, uint32_t lobe, double *out, double *cos_out);

// Henyey-Greenstein coefficients p^m(mu_i, mu_j) on an N-cosine grid, [m][i][j], for
// propagation directions in the same hemisphere (transmission) or opposite ones.
std::vector<double> hg_coefficients(double g, const std::vector<double> &mu, int M, bool same);

} // namespace bsdflab::ad
