// AddingDoubling::solve: the grid, then the named parts of adding_doubling_parts.h in
// order (boundary operators, the top's, slabs, adding, spectral interpolation, query
// values), one task per (channel, order).
#include <algorithm>
#include <mutex>
#include "adding_doubling_parts.h"
#include "bsdflab/constants.h"
#include "bsdflab/parallel.h"

namespace bsdflab {

using ad::Grid;
using ad::Op;

void AddingDoubling::solve(const std::vector<double> &out_cos, const std::vector<double> &in_cos,
                           std::vector<double> &values, const Queries *two_sided) const {
    if (snell_) return solve_snell(out_cos, in_cos, values, two_sided);
    const int C = channels(), M = orders_;
    const int n = static_cast<int>(mu_.size());
    const std::size_t Qo = out_cos.size(), Qi = in_cos.size(), K = slabs_.size();
    // The grid: nodes, then (smooth top) the query cosines inside the first slab.
    std::vector<double> grid(mu_);
    std::vector<int> xo(Qo), xi(Qi);
    if (two_sided) {
        grid.insert(grid.end(), two_sided->cosines.begin(), two_sided->cosines.end());
    } else if (smooth_top_) {
        std::vector<double> all(out_cos);
        all.insert(all.end(), in_cos.begin(), in_cos.end());
        std::vector<int> index;
        const std::vector<double> extras = ad::distinct(all, index);
        for (std::size_t q = 0; q < Qo; ++q) xo[q] = n + index[q];
        for (std::size_t q = 0; q < Qi; ++q) xi[q] = n + index[Qo + q];
        grid.insert(grid.end(), extras.begin(), extras.end());
    }
    const ad::Sizes s{C, M, half_samples_, n, grid.size()};
    const std::size_t N = s.N;
    auto order_grid = [&](int m) { return Grid{n, static_cast<int>(N), order_weights(m, N)}; };
    // A rough top's queries never enter below it: what lies there is solved once per
    // solver (and shared with with_top copies).
    std::unique_lock<std::mutex> lock(inner_->mutex, std::defer_lock);
    if (!smooth_top_) lock.lock();
    const bool cached = !smooth_top_ && inner_->ready;

    std::vector<ad::BoundaryOperators> below(K + 1);
    std::vector<ad::SlabOperators> slabs;
    if (!cached) {
        for (std::size_t j = 1; j <= K; ++j)
            below[j] = ad::boundary_operators(*boundaries_[j], j < K, index_matched(j), grid, s);
        slabs.reserve(K);
        for (std::size_t j = 0; j < K; ++j) slabs.emplace_back(slabs_[j], grid, settings_, M);
    }
    const ad::TopOperators top = ad::top_operators(*boundaries_[0], smooth_top_, grid, mu_, w_, breaks_,
                                                   in_cos, out_cos, settings_, s);
    // A rough top over a stack that reflects by a delta path: that part D of the inner
    // reflection lies between the top's two narrow lobes, so it is integrated on the fine
    // nodes against both unprojected kernels (a product of two lobes has no quadrature on
    // the nodes), D interpolated there (it is smooth in mu: Fresnel x transmittance).
    std::vector<double> mu_f, w_f, B, fine_down;
    if (!smooth_top_ && delta_below_ && !two_sided) {
        const double h = std::clamp(ad::rough_alpha(*boundaries_[0]) * settings_.fine_step, 0.004, 0.05);
        ad::product_nodes(settings_.nodes, breaks_, h, mu_f, w_f, B);
        fine_down = ad::signed_cos(mu_f, -1.0);
    }
    const std::size_t nf = mu_f.size();
    std::vector<double> YD(nf > 0 ? static_cast<std::size_t>(C) * M * n : 0, 0.0); // Y's delta part per task
    if (!smooth_top_ && !cached) {
        const std::vector<int> solved = ad::solved_channels(C, settings_.spectral_stride);
        inner_->R.assign(static_cast<std::size_t>(C) * M, Op());
        parallel_for_each(solved.size() * M, [&](std::size_t t) {
            int c = solved[t / M], m = static_cast<int>(t % M);
            inner_->R[static_cast<std::size_t>(c) * M + m] =
                ad::inner_reflection(below, slabs, s, c, m, order_grid(m));
        });
        ad::interpolate_channels(inner_->R, wavelengths_, solved, M);
        inner_->ready = true;
    }

    if (two_sided) {
        const std::size_t P = two_sided->op.size();
        values.assign(static_cast<std::size_t>(C) * M * P, 0.0);
        parallel_for_each(static_cast<std::size_t>(C) * M, [&](std::size_t task) {
            const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
            const ad::LayerOperators S = ad::stack_operators(top, below, slabs, s, c, m, order_grid(m));
            ad::two_sided_values(S, two_sided->op, two_sided->row, two_sided->col, n, N, &values[task * P]);
        });
        return;
    }
    values.assign(static_cast<std::size_t>(C) * M * Qo * Qi, 0.0);
    parallel_for_each(static_cast<std::size_t>(C) * M, [&](std::size_t task) {
        const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
        const Grid g = order_grid(m);
        const Op R = smooth_top_ ? ad::inner_reflection(below, slabs, s, c, m, g) : inner_->R[task];
        if (R.D.empty() && R.K.empty()) return;
        // The stack's reflection under the top, its internal reflections included.
        Op Y = ad::mul(ad::inverse_one_minus(ad::mul(R, top.rb(s, c, m), g), g), R, g);
        double *V = &values[task * Qo * Qi];
        if (smooth_top_) return ad::smooth_top_values(Y, xo, xi, N, V);
        if (nf > 0 && !Y.D.empty()) { // kept for the fine-node product below
            std::copy(Y.D.begin(), Y.D.begin() + n, &YD[task * n]);
            Y.D.clear();
        }
        ad::rough_top_values(Y, ad::kernel_at(top.Td, N, Qi, C, M, c, m),
                             ad::kernel_at(top.Tu, Qo, N, C, M, c, m), g, N, Qo, Qi, V);
    });
    if (nf > 0) fine_delta_product(fine_down, mu_f, w_f, B, YD, out_cos, in_cos, values);
}

void AddingDoubling::fine_delta_product(const std::vector<double> &fine_down, const std::vector<double> &mu_f,
                                        const std::vector<double> &w_f, const std::vector<double> &B,
                                        const std::vector<double> &YD, const std::vector<double> &out_cos,
                                        const std::vector<double> &in_cos,
                                        std::vector<double> &values) const {
    // The top's kernels at the fine nodes, a block of fine nodes at a time: whole, they
    // take nf (Qi + Qo) C M doubles (GGX 0.01, 25 cosines, 81 wavelengths: ~31 GB).
    constexpr std::size_t kBlockBytes = std::size_t{32} << 20;
    const int C = channels(), M = orders_, n = static_cast<int>(mu_.size());
    const std::size_t CM = static_cast<std::size_t>(C) * M, Qo = out_cos.size(), Qi = in_cos.size();
    const std::size_t nf = mu_f.size(), per_node = (Qi + Qo) * CM * sizeof(double);
    const std::size_t F = std::clamp<std::size_t>(kBlockBytes / std::max<std::size_t>(per_node, 1), 1, nf);
    const BSDF &top = *boundaries_[0];
    for (std::size_t f0 = 0; f0 < nf; f0 += F) {
        const std::size_t nb = std::min(nf, f0 + F) - f0;
        const std::vector<double> cos_b(fine_down.begin() + f0, fine_down.begin() + f0 + nb);
        const std::vector<double> TdF = ad::fourier_kernel(top, cos_b, in_cos, M, half_samples_); // nb x Qi
        const std::vector<double> TuF = ad::fourier_kernel(top, out_cos, cos_b, M, half_samples_); // Qo x nb
        parallel_for_each(CM, [&](std::size_t task) {
            const int m = static_cast<int>(task % M);
            const double *yd = &YD[task * n];
            std::vector<double> Df(nb, 0.0);
            bool any = false;
            for (std::size_t f = 0; f < nb; ++f) {
                for (int k = 0; k < n; ++k) Df[f] += B[(f0 + f) * n + k] * yd[k];
                Df[f] *= kPi * (m == 0 ? 2.0 : 1.0) * mu_f[f0 + f] * w_f[f0 + f];
                any = any || Df[f] != 0.0;
            }
            if (!any) return;
            double *V = &values[task * Qo * Qi];
            for (std::size_t a = 0; a < Qo; ++a)
                for (std::size_t b = 0; b < Qi; ++b) {
                    double v = 0.0;
                    for (std::size_t f = 0; f < nb; ++f)
                        v += TuF[(a * nb + f) * CM + task] * Df[f] * TdF[(f * Qi + b) * CM + task];
                    V[a * Qi + b] += v;
                }
        });
    }
}

} // namespace bsdflab
