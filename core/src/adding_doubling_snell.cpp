// AddingDoubling::solve_snell: a stack with a smooth interior interface between unequal
// indices (docs/solvers.md, "Smooth interior interfaces between unequal indices").
//
// Directions are labelled by the Snell invariant p = n sin(theta), which a smooth
// interface keeps. The nodes are the densest slab's (mu_: panels cut at the critical
// cosine of every lower index of the stack, so each panel is one p-interval in every
// slab), and slab j sees node k at mu_j = sqrt(1 - p_k^2 / n_j^2), or not at all where
// p_k >= n_j (beyond its horizon: a dead point, every operator zero there). Since
// mu dmu = p dp / n^2, node k's weight in slab j is n_max^2 / n_j^2 times the densest
// slab's; so the solve works in basic radiance L / n^2, where one weight
// W~_k = pi (1 + [m = 0]) n_max^2 mu_k w_k serves every slab: a kernel K (radiance, its
// input medium's weights) becomes K / n_out^2, a delta part D becomes D n_in^2 / n_out^2
// (for a smooth interface's transmission, whose D carries the radiance's (n_out / n_in)^2,
// the Fresnel transmittance itself). A smooth interface's four operators are diagonal in
// k: exact, no interpolation between media.
#include <cmath>
#include "adding_doubling_parts.h"
#include "bsdflab/constants.h"
#include "bsdflab/parallel.h"

namespace bsdflab {

using ad::Grid;
using ad::LayerOperators;
using ad::Op;

namespace {

// One slab's view of the p points: its cosines (1 where dead, a finite stand-in) and
// which points live (1) or lie beyond its horizon (0).
struct Medium {
    double n = 1.0;
    std::vector<double> cos, live;
};

// Operator o (radiance, its media's weights) in basic radiance, zero at dead points.
Op basic(Op o, const Medium &out, const Medium &in) {
    const std::size_t N = out.cos.size();
    if (!o.D.empty()) {
        const double s = (in.n * in.n) / (out.n * out.n);
        for (std::size_t i = 0; i < N; ++i) o.D[i] *= s * out.live[i] * in.live[i];
    }
    if (!o.K.empty()) {
        const double s = 1.0 / (out.n * out.n);
        for (std::size_t i = 0; i < N; ++i)
            for (std::size_t j = 0; j < N; ++j) o.K[i * N + j] *= s * out.live[i] * in.live[j];
    }
    return o;
}

Op identity(const Medium &m) {
    Op o;
    o.D = m.live;
    return o;
}

// Boundary j's operators in radiance between the slab above (a) and below (b); the base
// (interior false) its reflection from above only. Delta parts as [channel][point],
// kernels in fourier_kernel's layout.
struct Boundary {
    bool delta = false;
    std::vector<double> Rt, Td, Rb, Tu;

    Op at(const std::vector<double> &x, const ad::Sizes &s, int c, int m) const {
        Op o;
        if (x.empty()) return o;
        if (delta) o.D.assign(x.begin() + c * s.N, x.begin() + (c + 1) * s.N);
        else o.K = ad::kernel_at(x, s.N, s.N, s.C, s.M, c, m);
        return o;
    }
};

Boundary boundary(const BSDF &b, bool interior, const Medium &a, const Medium &below, const ad::Sizes &s) {
    Boundary B;
    B.delta = ad::is_delta(b);
    const std::vector<double> up = a.cos, down = ad::signed_cos(below.cos, -1.0);
    if (B.delta) {
        // sample()'s weights: wi on the side of the output radiance, the transmission's
        // weight T (n_out / n_in)^2 (radiance); zero beyond the critical angle.
        B.Rt = ad::delta_table(b, a.cos, 1.0, kDeltaReflection, s.C);
        if (!interior) return B;
        B.Tu = ad::delta_table(b, a.cos, 1.0, kDeltaTransmission, s.C);
        B.Rb = ad::delta_table(b, below.cos, -1.0, kDeltaReflection, s.C);
        B.Td = ad::delta_table(b, below.cos, -1.0, kDeltaTransmission, s.C);
        return B;
    }
    B.Rt = ad::fourier_kernel(b, up, up, s.M, s.H);
    if (!interior) return B;
    B.Td = ad::fourier_kernel(b, down, up, s.M, s.H);
    B.Rb = ad::fourier_kernel(b, down, down, s.M, s.H);
    B.Tu = ad::fourier_kernel(b, up, down, s.M, s.H);
    return B;
}

} // namespace

void AddingDoubling::solve_snell(const std::vector<double> &out_cos, const std::vector<double> &in_cos,
                                 std::vector<double> &values, const Queries *two_sided) const {
    const int C = channels(), M = orders_;
    const int n = static_cast<int>(mu_.size());
    const std::size_t K = slabs_.size(), Qo = out_cos.size(), Qi = in_cos.size();
    // p of every point: the nodes, then the extras (query directions, inside the first slab
    // for a one-sided solve; already p for a two-sided one).
    std::vector<double> p(n);
    for (int k = 0; k < n; ++k) p[k] = n_max_ * std::sqrt((1.0 - mu_[k]) * (1.0 + mu_[k]));
    std::vector<int> xo(Qo), xi(Qi);
    if (two_sided) {
        p.insert(p.end(), two_sided->cosines.begin(), two_sided->cosines.end());
    } else {
        std::vector<double> all(out_cos);
        all.insert(all.end(), in_cos.begin(), in_cos.end());
        std::vector<int> index;
        for (double mu : ad::distinct(all, index))
            p.push_back(media_[1] * std::sqrt((1.0 - mu) * (1.0 + mu)));
        for (std::size_t q = 0; q < Qo; ++q) xo[q] = n + index[q];
        for (std::size_t q = 0; q < Qi; ++q) xi[q] = n + index[Qo + q];
    }
    const std::size_t N = p.size();
    std::vector<Medium> media(K);
    for (std::size_t j = 0; j < K; ++j) {
        Medium &md = media[j];
        md.n = media_[j + 1];
        md.cos.assign(N, 1.0);
        md.live.assign(N, 0.0);
        for (std::size_t i = 0; i < N; ++i) {
            const double x = p[i] / md.n;
            if (!(x < 1.0)) continue;
            md.cos[i] =
                md.n == n_max_ && i < static_cast<std::size_t>(n) ? mu_[i] : std::sqrt((1.0 - x) * (1.0 + x));
            md.live[i] = 1.0;
        }
    }
    const ad::Sizes s{C, M, half_samples_, n, N};
    std::vector<Boundary> bounds(K + 1);
    for (std::size_t j = 1; j <= K; ++j)
        bounds[j] = boundary(*boundaries_[j], j < K, media[j - 1], media[std::min(j, K - 1)], s);
    const std::vector<double> top_rb =
        ad::delta_table(*boundaries_[0], media[0].cos, -1.0, kDeltaReflection, C);
    std::vector<ad::SlabOperators> slabs;
    slabs.reserve(K);
    for (std::size_t j = 0; j < K; ++j) slabs.emplace_back(slabs_[j], media[j].cos, settings_, M);

    auto weights = [&](int m, double scale, const std::vector<double> *live) {
        std::vector<double> W(N, 0.0);
        for (int k = 0; k < n; ++k)
            W[k] = (m == 0 ? 2.0 : 1.0) * kPi * mu_[k] * w_[k] * scale * (live ? (*live)[k] : 1.0);
        return W;
    };
    auto task_ops = [&](int c, int m, const Grid &g, auto &&use) {
        auto slab = [&](std::size_t j) {
            const Medium &md = media[j];
            const Grid gj{n, static_cast<int>(N), weights(m, n_max_ * n_max_ / (md.n * md.n), &md.live)};
            LayerOperators L = slabs[j].layer(c, m, gj);
            return LayerOperators{basic(L.Rt, md, md), basic(L.Td, md, md), basic(L.Rb, md, md),
                                  basic(L.Tu, md, md)};
        };
        auto interior = [&](std::size_t j) {
            const Boundary &B = bounds[j];
            const Medium &a = media[j - 1], &b = media[j];
            return LayerOperators{basic(B.at(B.Rt, s, c, m), a, a), basic(B.at(B.Td, s, c, m), b, a),
                                  basic(B.at(B.Rb, s, c, m), b, b), basic(B.at(B.Tu, s, c, m), a, b)};
        };
        Op base = basic(bounds[K].at(bounds[K].Rt, s, c, m), media[K - 1], media[K - 1]);
        Op rb;
        rb.D.assign(top_rb.begin() + c * N, top_rb.begin() + (c + 1) * N);
        rb = basic(rb, media[0], media[0]);
        use(slab, interior, base, rb, g);
    };

    if (two_sided) {
        const std::size_t P = two_sided->op.size();
        values.assign(static_cast<std::size_t>(C) * M * P, 0.0);
        parallel_for_each(static_cast<std::size_t>(C) * M, [&](std::size_t task) {
            const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
            const Grid g{n, static_cast<int>(N), weights(m, n_max_ * n_max_, nullptr)};
            task_ops(c, m, g, [&](auto &slab, auto &interior, const Op &base, const Op &rb, const Grid &gg) {
                LayerOperators S{Op(), identity(media[0]), rb, identity(media[0])};
                for (std::size_t j = 0; j < K; ++j) {
                    S = ad::add_layers(S, slab(j), gg);
                    const LayerOperators L = j + 1 < K ? interior(j + 1)
                                                       : LayerOperators{base, identity(media[K - 1]), Op(),
                                                                        identity(media[K - 1])};
                    S = ad::add_layers(S, L, gg);
                }
                double *V = &values[task * P];
                ad::two_sided_values(S, two_sided->op, two_sided->row, two_sided->col, n, N, V);
                // Back to radiance in the viewer's slab: the first for Rt and Tu, the last else.
                for (std::size_t q = 0; q < P; ++q) {
                    const double nv = two_sided->op[q] == 0 || two_sided->op[q] == 3 ? media_[1] : media_[K];
                    V[q] *= nv * nv;
                }
            });
        });
        return;
    }
    values.assign(static_cast<std::size_t>(C) * M * Qo * Qi, 0.0);
    parallel_for_each(static_cast<std::size_t>(C) * M, [&](std::size_t task) {
        const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
        const Grid g{n, static_cast<int>(N), weights(m, n_max_ * n_max_, nullptr)};
        task_ops(c, m, g, [&](auto &slab, auto &interior, const Op &base, const Op &rb, const Grid &gg) {
            Op R = base;
            for (std::size_t j = K; j-- > 0;) {
                R = ad::reflect_over(slab(j), R, gg);
                if (j >= 1) R = ad::reflect_over(interior(j), R, gg);
            }
            if (R.D.empty() && R.K.empty()) return;
            const Op Y = ad::mul(ad::inverse_one_minus(ad::mul(R, rb, gg), gg), R, gg);
            double *V = &values[task * Qo * Qi];
            ad::smooth_top_values(Y, xo, xi, N, V);
            const double n1 = media_[1];
            for (std::size_t q = 0; q < Qo * Qi; ++q) V[q] *= n1 * n1;
        });
    });
}

} // namespace bsdflab
