// The boundaries' operators for the adding-doubling solve (adding_doubling_parts.h): every
// boundary below the top from its eval (cosine transform) or its delta weights, and the
// top's, a rough top's by product integration.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "adding_doubling_parts.h"
#include "bsdflab/interfaces.h"

namespace bsdflab::ad {

bool is_delta(const BSDF &b) { return (b.lobes() & ~kDelta) == 0; }

double rough_alpha(const BSDF &b) {
    auto *r = dynamic_cast<const RoughInterface *>(&b);
    return r && !r->pass_through() ? r->microfacet().alpha() : 0.0;
}

std::vector<double> distinct(const std::vector<double> &v, std::vector<int> &index) {
    std::vector<double> d(v);
    std::sort(d.begin(), d.end());
    d.erase(std::unique(d.begin(), d.end()), d.end());
    index.resize(v.size());
    for (std::size_t i = 0; i < v.size(); ++i)
        index[i] = static_cast<int>(std::lower_bound(d.begin(), d.end(), v[i]) - d.begin());
    return d;
}

std::vector<double> signed_cos(const std::vector<double> &mu, double sign) {
    std::vector<double> z(mu);
    for (double &x : z) x *= sign;
    return z;
}

std::vector<double> kernel_at(const std::vector<double> &coef, std::size_t rows, std::size_t cols, int C,
                              int M, int c, int m) {
    std::vector<double> K(rows * cols);
    for (std::size_t p = 0; p < rows * cols; ++p) K[p] = coef[(p * C + c) * M + m];
    return K;
}

std::vector<double> delta_table(const BSDF &b, const std::vector<double> &grid, double sign, uint32_t lobe,
                                int C) {
    const std::size_t N = grid.size();
    std::vector<double> d(C * N), v(C);
    for (std::size_t i = 0; i < N; ++i) {
        delta_weight(b, sign * grid[i], lobe, v.data(), nullptr);
        for (int c = 0; c < C; ++c) d[c * N + i] = v[c];
    }
    return d;
}

Op BoundaryOperators::op(const std::vector<double> &a, const Sizes &s, int c, int m) const {
    Op o;
    if (a.empty()) return o;
    if (delta) {
        o.D.assign(a.begin() + c * s.N, a.begin() + (c + 1) * s.N);
    } else {
        o.K = kernel_at(a, s.N, s.N, s.C, s.M, c, m);
    }
    return o;
}

LayerOperators BoundaryOperators::layer(const Sizes &s, int c, int m) const {
    return LayerOperators{op(Rt, s, c, m), op(Td, s, c, m), op(Rb, s, c, m), op(Tu, s, c, m)};
}

BoundaryOperators boundary_operators(const BSDF &b, bool interior, bool index_matched,
                                     const std::vector<double> &grid, const Sizes &s) {
    BoundaryOperators B;
    B.interior = interior;
    B.delta = is_delta(b);
    const std::vector<double> up = grid, down = signed_cos(grid, -1.0);
    if (!B.delta) {
        B.Rt = fourier_kernel(b, up, up, s.M, s.H);
        if (B.interior) {
            B.Td = fourier_kernel(b, down, up, s.M, s.H);
            B.Rb = fourier_kernel(b, down, down, s.M, s.H);
            B.Tu = fourier_kernel(b, up, down, s.M, s.H);
        }
        return B;
    }
    if (B.interior && !index_matched)
        throw std::invalid_argument("adding-doubling: a smooth interior interface must be index-matched");
    B.Rt = delta_table(b, grid, 1.0, kDeltaReflection, s.C);
    if (B.interior) {
        B.Td = delta_table(b, grid, 1.0, kDeltaTransmission, s.C);
        B.Rb = delta_table(b, grid, -1.0, kDeltaReflection, s.C);
        B.Tu = delta_table(b, grid, -1.0, kDeltaTransmission, s.C);
    }
    return B;
}

Op TopOperators::rb(const Sizes &s, int c, int m) const {
    Op o;
    if (smooth) o.D.assign(Rb.begin() + c * s.N, Rb.begin() + (c + 1) * s.N);
    else o.K = kernel_at(Rb, s.N, s.N, s.C, s.M, c, m);
    return o;
}

TopOperators top_operators(const BSDF &top, bool smooth, const std::vector<double> &grid,
                           const std::vector<double> &mu, const std::vector<double> &w,
                           const std::vector<double> &breaks, const std::vector<double> &in_cos,
                           const std::vector<double> &out_cos, const ADSettings &settings, const Sizes &s) {
    TopOperators T;
    T.smooth = smooth;
    if (smooth) {
        T.Rb = delta_table(top, grid, -1.0, kDeltaReflection, s.C);
        return T;
    }
    // The top's lobes are narrower than the nodes resolve: integrate them on fine nodes
    // against the (smooth) interpolant of what lies below.
    const int n = s.n;
    std::vector<double> mu_f, w_f, B;
    double h = std::clamp(rough_alpha(top) * settings.fine_step, 0.004, 0.05);
    product_nodes(settings.nodes, breaks, h, mu_f, w_f, B);
    const std::size_t nf = mu_f.size();
    std::vector<double> scale(nf * n);  // (mu_f w_f) / (mu_k w_k)
    for (std::size_t f = 0; f < nf; ++f)
        for (int k = 0; k < n; ++k) scale[f * n + k] = mu_f[f] * w_f[f] / (mu[k] * w[k]);
    const std::vector<double> fine_down = signed_cos(mu_f, -1.0), down = signed_cos(grid, -1.0);
    T.Rb = projected_kernel(top, fine_down, down, true, B, scale, n, s.M, s.H);
    T.Td = projected_kernel(top, fine_down, in_cos, true, B, scale, n, s.M, s.H);
    T.Tu = projected_kernel(top, fine_down, out_cos, false, B, scale, n, s.M, s.H);
    return T;
}

TopOperators rough_top_with_extras(const BSDF &top, const std::vector<double> &grid,
                                   const std::vector<double> &mu, const std::vector<double> &w,
                                   const std::vector<double> &breaks, const std::vector<double> &in_cos,
                                   const std::vector<double> &out_cos, const ADSettings &settings,
                                   const Sizes &s) {
    TopOperators T = top_operators(top, false, grid, mu, w, breaks, in_cos, out_cos, settings, s);
    const int n = s.n;
    const std::size_t N = s.N, cm = static_cast<std::size_t>(s.C) * s.M, X = N - n;
    T.Rb.resize(N * N * cm, 0.0);  // rows n.. appended (top_operators' are n x N)
    if (X == 0) return T;
    std::vector<double> mu_f, w_f, B;
    const double h = std::clamp(rough_alpha(top) * settings.fine_step, 0.004, 0.05);
    product_nodes(settings.nodes, breaks, h, mu_f, w_f, B);
    const std::size_t nf = mu_f.size();
    std::vector<double> scale(nf * n);
    for (std::size_t f = 0; f < nf; ++f)
        for (int k = 0; k < n; ++k) scale[f * n + k] = mu_f[f] * w_f[f] / (mu[k] * w[k]);
    const std::vector<double> extras(grid.begin() + n, grid.end());
    const std::vector<double> rows = projected_kernel(top, signed_cos(mu_f, -1.0), signed_cos(extras, -1.0),
                                                      false, B, scale, n, s.M, s.H);  // X x n
    for (std::size_t e = 0; e < X; ++e)
        std::copy(rows.begin() + e * n * cm, rows.begin() + (e + 1) * n * cm,
                  T.Rb.begin() + (n + e) * N * cm);
    return T;
}

} // namespace bsdflab::ad
