// A slab's operators for the adding-doubling solve (adding_doubling_parts.h): a
// single-scattering layer with a Richardson-corrected start, doubled to the slab's depth.
#include <algorithm>
#include <cmath>
#include "adding_doubling_parts.h"

namespace bsdflab::ad {

SlabOperators::SlabOperators(const ADSlab &slab, const std::vector<double> &grid, const ADSettings &settings,
                             int M)
    : slab_(&slab), grid_(&grid), thin_depth_(settings.thin_depth) {
    if (!(slab.sigma_s > 0 && slab.thickness > 0)) return;
    orders_ = settings.orders > 0 ? M : std::min(M, hg_orders_needed(slab.g, settings.order_tolerance));
    pr_ = hg_coefficients(slab.g, grid, orders_, false);
    pt_ = hg_coefficients(slab.g, grid, orders_, true);
}

Op SlabOperators::identity() const {
    Op o;
    o.D.assign(grid_->size(), 1.0);
    return o;
}

Op SlabOperators::exp_tau(double tau) const {
    const std::vector<double> &grid = *grid_;
    Op o;
    o.D.resize(grid.size());
    for (std::size_t i = 0; i < grid.size(); ++i) o.D[i] = std::exp(-tau / grid[i]);
    return o;
}

// Single-scattering layer of depth delta and albedo omega at order m.
void SlabOperators::thin(int m, double delta, double omega, Op &R, Op &T) const {
    const std::vector<double> &grid = *grid_;
    const std::size_t N = grid.size();
    const double *Pr = &pr_[static_cast<std::size_t>(m) * N * N];
    const double *Pt = &pt_[static_cast<std::size_t>(m) * N * N];
    R.K.assign(N * N, 0.0);
    T.K.assign(N * N, 0.0);
    for (std::size_t i = 0; i < N; ++i)
        for (std::size_t k = 0; k < N; ++k) {
            double mo = grid[i], mi = grid[k];
            R.K[i * N + k] = omega * Pr[i * N + k] * -std::expm1(-delta * (1.0 / mo + 1.0 / mi)) / (mo + mi);
            double x = 1.0 / mi - 1.0 / mo;
            double h =
                std::abs(delta * x) < 1e-8 ? delta * (1.0 - 0.5 * delta * x) : -std::expm1(-delta * x) / x;
            T.K[i * N + k] = omega * Pt[i * N + k] * std::exp(-delta / mo) * h / (mo * mi);
        }
    T.D = exp_tau(delta).D;
    R.D.clear();
}

LayerOperators SlabOperators::layer(int c, int m, const Grid &g) const {
    const ADSlab &s = *slab_;
    const std::size_t N = grid_->size();
    double sigma_t = s.sigma_a[c] + s.sigma_s, tau = sigma_t * s.thickness;
    if (!(tau > 0)) return LayerOperators{Op(), identity(), Op(), identity()};
    double omega = sigma_t > 0 ? s.sigma_s / sigma_t : 0.0;
    if (!(omega > 0) || m >= orders_) return LayerOperators{Op(), exp_tau(tau), Op(), exp_tau(tau)};
    int k = std::max(0, static_cast<int>(std::ceil(std::log2(tau / thin_depth_))));
    double delta = tau / std::ldexp(1.0, k);
    // Richardson start: 2 (doubled half layer) - (single layer) cancels the O(delta^2)
    // multiple scattering the single-scattering layer misses.
    Op R1, T1, Rs, Ts;
    thin(m, delta, omega, R1, T1);
    thin(m, 0.5 * delta, omega, Rs, Ts);
    double_symmetric(Rs, Ts, g);
    for (std::size_t p = 0; p < N * N; ++p) {
        Rs.K[p] = 2.0 * Rs.K[p] - R1.K[p];
        Ts.K[p] = 2.0 * Ts.K[p] - T1.K[p];
    }
    Rs.D.clear();
    Ts.D = T1.D;
    for (int d = 1; d <= k; ++d) {
        double_symmetric(Rs, Ts, g);
        Ts.D = exp_tau(delta * std::ldexp(1.0, d)).D;  // the unscattered beam exactly
    }
    return LayerOperators{Rs, Ts, Rs, Ts};
}

Op SlabOperators::reflect_over(int c, int m, const Grid &g, const Op &R) const {
    const ADSlab &s = *slab_;
    double tau = (s.sigma_a[c] + s.sigma_s) * s.thickness;
    if (!(tau > 0)) return R;
    LayerOperators L = layer(c, m, g);
    if (L.Rt.K.empty()) return mul(L.Td, mul(R, L.Td, g), g);  // no scattering
    return ad::reflect_over(L, R, g);
}

} // namespace bsdflab::ad
