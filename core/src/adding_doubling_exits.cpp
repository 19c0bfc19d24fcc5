// AddingDoubling::eval_rough_base (adding_doubling.h): transmission both ways and
// reflection from below of a transmissive stack with a smooth top and a rough dielectric
// base. The stack's four operators come from the adding equations (ad::stack_operators:
// the base's internal reflection, identity transmissions); the top's refracted query
// cosines are zero-weight extras in the first slab, as for a two-sided stack. The base's
// transmission lobes are narrower than the nodes resolve, so at the exit (and at the
// entry of light from below) they are integrated on fine nodes against the panel-wise
// interpolant of the radiance at the nodes (product integration, as the rough top's):
//     exit     sum_f X(q, f) mu_f w_f pi (1 + [m = 0]) sum_k B[f][k] L_k = sum_k Px[q][k] W_k L_k,
//     entry    L_k = sum_f B[f][k] (mu_f w_f / mu_k w_k) E(f, l) = Pe[k][l] (as a column of K W),
// X(q, f) = f_base(wi_q, +mu_f), E(f, l) = f_base(+mu_f, wo_l) (cosine coefficients; the
// base's BSDF carries its own radiance scaling). An operator's delta part D (the
// unscattered beam, the top's specular reflection) is not smooth across a beam: between
// the top and the base it carries the beam to one direction, where the base's BSDF is
// evaluated directly (no Fourier series: the lobe is narrower than the orders resolve);
// between the base's exit and entry (reflection from below) it is interpolated onto the
// fine nodes and both fine kernels are integrated against it there. A rough top (over the
// rough base) enters through its own product-integrated kernels (no extras), and the beam
// between its lobe and the base's is integrated the same way on their common fine nodes.
#include <algorithm>
#include <cmath>
#include "adding_doubling_parts.h"
#include "bsdflab/constants.h"
#include "bsdflab/frame.h"
#include "bsdflab/parallel.h"

namespace bsdflab {

using ad::Grid;
using ad::Op;

namespace {

enum Kind { kDown = 0, kUp = 1, kBelow = 2 };  // transmission down, up, reflection from below

} // namespace

void AddingDoubling::eval_rough_base(const double *wi_, const double *wo_, std::size_t count, double *out,
                                     bool scattered_only) const {
    const std::size_t K = slabs_.size();
    // A transmission lobe is narrower than alpha by the index contrast c = |n1 - n2| / max:
    // refraction through a tilted facet turns the ray by ~c times the tilt (GGX 0.3 from
    // glass into water: ~0.07 rad). The sub-panels and azimuth samples of the base's
    // kernels follow its width (1 / c more, in powers of 2, at most 16), and so do the
    // orders, at most 4 x (light entering and leaving through the base returns in a lobe
    // as narrow, around the mirror direction).
    // A rough top (over the rough base): its transmission lobes meet the base's in the
    // unscattered beam, so the narrower of the two sets the samples and orders (orders_
    // carries the top's 6 / alpha + 2: the constructor).
    const bool rough_top = !smooth_top_;
    const double nb = media_[K], nu = media_[K + 1], at = ad::rough_alpha(*boundaries_[0]);
    const double contrast_b = std::max(std::abs(nb - nu) / std::max(nb, nu), 1.0 / 16.0);
    const double contrast_t =
        std::max(std::abs(media_[0] - media_[1]) / std::max(media_[0], media_[1]), 1.0 / 16.0);
    const double contrast = rough_top ? std::min(contrast_b, contrast_t) : contrast_b;
    int Hx = half_samples_, widen = 1;
    while (Hx * contrast < half_samples_) Hx *= 2;
    while (widen < 4 && widen * contrast < 1.0) widen *= 2;
    const int C = channels(), M = orders_ * widen, n = static_cast<int>(mu_.size());
    while (rough_top && Hx < 2 * M) Hx *= 2;
    const std::size_t CM = static_cast<std::size_t>(C) * M;
    const BSDF &top = *boundaries_[0], &base = *boundaries_[K];
    // Per active pair: its kind, the cosines it reads (a top extra's refracted cosine, the
    // base's outside cosines), its scale per channel and the base's own reflection.
    std::vector<std::size_t> active;
    std::vector<int> kind;
    std::vector<double> extra_cos, exit_cos, entry_cos, scale, direct;
    std::vector<double> t(C), d(C);
    for (std::size_t p = 0; p < count; ++p) {
        Vec3 wi{wi_[3 * p], wi_[3 * p + 1], wi_[3 * p + 2]}, wo{wo_[3 * p], wo_[3 * p + 1], wo_[3 * p + 2]};
        if (!usable_direction(wi) || !usable_direction(wo) || wi.z == 0 || wo.z == 0) continue;
        if (wi.z > 0 && wo.z > 0) continue;  // reflection from above: eval's own path
        const int k = wi.z < 0 ? (wo.z > 0 ? kDown : kBelow) : kUp;
        double mu = 0.0, s = std::abs(wo.z);
        std::fill(t.begin(), t.end(), 1.0);
        std::fill(d.begin(), d.end(), 0.0);
        if (k != kBelow && rough_top) { // the top's cosine outside; its BSDF carries its own scaling
            mu = k == kDown ? wo.z : wi.z;
        } else if (k ==
                   kDown) { // the light crosses the smooth top: its solid angle inside is (n1 / n0)^2 its own
            ad::delta_weight(top, wo.z, kDeltaTransmission, t.data(), &mu);
            s *= (media_[1] / media_[0]) * (media_[1] / media_[0]);
        } else if (k == kUp) {
            ad::delta_weight(top, wi.z, kDeltaTransmission, t.data(), &mu);
        } else if (!scattered_only) { // the base's own reflection from below, exact
            Query q;
            base.eval(wi, wo, kReflection, q, d.data());
        }
        if (k != kBelow && !(mu > 0)) continue;
        for (int c = 0; c < C; ++c) {
            scale.push_back(t[c] * s);
            direct.push_back(d[c]);
        }
        kind.push_back(k);
        extra_cos.push_back(mu); // 0 for reflection from below (unused); a rough top's outside cosine
        exit_cos.push_back(k == kUp ? 0.0 : wi.z);
        entry_cos.push_back(k == kDown ? 0.0 : wo.z);
        active.push_back(p);
    }
    if (active.empty()) return;
    const std::size_t P = active.size();

    // The grid: nodes, then the top's refracted query cosines.
    // A rough top has no extras: its cosines outside, the light's (down) and the viewer's
    // (up), index its kernels instead.
    std::vector<double> tops, downs, ups;
    for (std::size_t a = 0; a < P; ++a) {
        if (kind[a] != kBelow && !rough_top) tops.push_back(extra_cos[a]);
        if (kind[a] == kDown && rough_top) downs.push_back(extra_cos[a]);
        if (kind[a] == kUp && rough_top) ups.push_back(extra_cos[a]);
    }
    std::vector<int> top_index, down_index, up_index;
    const std::vector<double> extras = ad::distinct(tops, top_index), qi = ad::distinct(downs, down_index),
                              qo = ad::distinct(ups, up_index);
    std::vector<double> grid(mu_);
    grid.insert(grid.end(), extras.begin(), extras.end());
    const ad::Sizes s{C, M, Hx, n, grid.size()};
    const std::size_t N = s.N;

    // The base's outside cosines at the exit (viewer below) and the entry (light below).
    std::vector<double> xs, es;
    std::vector<int> xa(P, -1), ea(P, -1), ta(P, -1);
    for (std::size_t a = 0, j = 0, u = 0, v = 0; a < P; ++a) {
        if (kind[a] != kUp) xs.push_back(exit_cos[a]);
        if (kind[a] != kDown) es.push_back(entry_cos[a]);
        if (kind[a] != kBelow && !rough_top) ta[a] = n + top_index[j++];
        if (kind[a] == kDown && rough_top) ta[a] = down_index[u++];
        if (kind[a] == kUp && rough_top) ta[a] = up_index[v++];
    }
    std::vector<int> xi, ei;
    const std::vector<double> qx = ad::distinct(xs, xi), qe = ad::distinct(es, ei);
    for (std::size_t a = 0, u = 0, v = 0; a < P; ++a) {
        if (kind[a] != kUp) xa[a] = xi[u++];
        if (kind[a] != kDown) ea[a] = ei[v++];
    }
    const std::size_t Qx = qx.size(), Qe = qe.size();

    // Fine nodes of the base's lobes and its kernels there; their projection onto the nodes.
    std::vector<double> mu_f, w_f, B;
    double h = std::clamp(ad::rough_alpha(base) * contrast_b * settings_.fine_step, 0.002, 0.05);
    if (rough_top) h = std::min(h, std::clamp(at * contrast_t * settings_.fine_step, 0.002, 0.05));
    ad::product_nodes(settings_.nodes, breaks_, h, mu_f, w_f, B);
    const std::size_t nf = mu_f.size();
    const std::vector<double> X = ad::fourier_kernel(base, qx, mu_f, M, Hx); // Qx x nf
    const std::vector<double> E = ad::fourier_kernel(base, mu_f, qe, M, Hx); // nf x Qe
    std::vector<double> Px(Qx * n * CM, 0.0), Pe(static_cast<std::size_t>(n) * Qe * CM, 0.0);
    for (std::size_t f = 0; f < nf; ++f)
        for (int k = 0; k < n; ++k) {
            const double w = B[f * n + k] * mu_f[f] * w_f[f] / (mu_[k] * w_[k]);
            if (w == 0.0) continue;
            for (std::size_t q = 0; q < Qx; ++q)
                for (std::size_t x = 0; x < CM; ++x) Px[(q * n + k) * CM + x] += w * X[(q * nf + f) * CM + x];
            for (std::size_t l = 0; l < Qe; ++l)
                for (std::size_t x = 0; x < CM; ++x)
                    Pe[(k * Qe + l) * CM + x] += w * E[(f * Qe + l) * CM + x];
        }
    // The unscattered beam between the top extra and the base meets the base's lobe at one
    // direction: its BSDF there, evaluated directly (a point value of a lobe narrower than
    // the Fourier orders resolve; the beam's delta part is the same at every order).
    std::vector<double> fbeam(P * C, 0.0);
    parallel_for(P, 16, [&](std::size_t begin, std::size_t end) {
        Query q;
        std::vector<double> f(C);
        for (std::size_t a = begin; a < end; ++a) {
            if (kind[a] == kBelow || rough_top) continue; // a rough top's beam: the fine product below
            const std::size_t p = active[a];
            const double *o = kind[a] == kDown ? &wo_[3 * p] : &wi_[3 * p]; // the direction inside the top
            const double r = std::hypot(o[0], o[1]), mu = extra_cos[a];
            const double sn = std::sqrt(std::max(0.0, (1.0 - mu) * (1.0 + mu)));
            const Vec3 in = r > 0 ? Vec3{sn * o[0] / r, sn * o[1] / r, mu} : Vec3{0.0, 0.0, 1.0};
            const Vec3 wi{wi_[3 * p], wi_[3 * p + 1], wi_[3 * p + 2]},
                wo{wo_[3 * p], wo_[3 * p + 1], wo_[3 * p + 2]};
            if (kind[a] == kDown) base.eval(wi, in, kAll, q, f.data());
            else base.eval(in, wo, kAll, q, f.data());
            const double cos_light = kind[a] == kDown ? mu : std::abs(wo.z);
            for (int c = 0; c < C; ++c) fbeam[a * C + c] = f[c] / cos_light;
        }
    });
    std::vector<double> dbeam(P * C, 0.0); // the stack's delta transmission at the extra, per channel

    std::vector<ad::BoundaryOperators> below(K + 1);
    for (std::size_t j = 1; j <= K; ++j)
        below[j] = ad::boundary_operators(*boundaries_[j], j < K, index_matched(j), grid, s);
    std::vector<ad::SlabOperators> slabs;
    slabs.reserve(K);
    for (std::size_t j = 0; j < K; ++j) slabs.emplace_back(slabs_[j], grid, settings_, M);
    const ad::TopOperators T =
        ad::top_operators(top, !rough_top, grid, mu_, w_, breaks_, qi, qo, settings_, s);
    // A rough top's kernels at the fine nodes: the unscattered beam between its lobe and the
    // base's, both integrated on the fine nodes against the (smooth) delta part between.
    const std::size_t Qi = qi.size(), Qo = qo.size();
    std::vector<double> TdF, TuF;
    if (rough_top) {
        const std::vector<double> fine_down = ad::signed_cos(mu_f, -1.0);
        TdF = ad::fourier_kernel(top, fine_down, qi, M, Hx); // nf x Qi
        TuF = ad::fourier_kernel(top, qo, fine_down, M, Hx); // Qo x nf
    }

    std::vector<double> V(CM * P, 0.0);
    parallel_for_each(CM, [&](std::size_t task) {
        const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
        const Grid g{n, static_cast<int>(N), order_weights(m, N)};
        const ad::LayerOperators S = ad::stack_operators(T, below, slabs, s, c, m, g);
        auto px = [&](std::size_t q, int k) { return Px[(q * n + k) * CM + task]; };
        auto pe = [&](int k, std::size_t l) { return Pe[(k * Qe + l) * CM + task]; };
        // Reflection from below: Z = Rb_K W Pe on the nodes, and the delta part of Rb on the fine nodes.
        std::vector<double> Z(static_cast<std::size_t>(n) * Qe, 0.0), Df(nf, 0.0);
        if (!S.Rb.K.empty())
            for (int k = 0; k < n; ++k)
                for (int j = 0; j < n; ++j) {
                    const double r = S.Rb.K[k * N + j] * g.W[j];
                    if (r != 0.0)
                        for (std::size_t l = 0; l < Qe; ++l) Z[k * Qe + l] += r * pe(j, l);
                }
        if (!S.Rb.D.empty())
            for (std::size_t f = 0; f < nf; ++f)
                for (int k = 0; k < n; ++k) Df[f] += B[f * n + k] * S.Rb.D[k];
        const double order_w = kPi * (m == 0 ? 2.0 : 1.0);
        // A rough top: the stack below its lobes (Zd = S_Td.K W Td, Zu = Tu W S_Tu.K on the
        // nodes) and the delta parts of S_Td and S_Tu on the fine nodes.
        std::vector<double> Zd, Zu, Ddf, Duf;
        if (rough_top) {
            Zd.assign(static_cast<std::size_t>(n) * Qi, 0.0);
            Zu.assign(Qo * n, 0.0);
            Ddf.assign(nf, 0.0);
            Duf.assign(nf, 0.0);
            for (int k = 0; k < n; ++k)
                for (int j = 0; j < n; ++j) {
                    const double wj = g.W[j];
                    if (!S.Td.K.empty())
                        for (std::size_t b = 0; b < Qi; ++b)
                            Zd[k * Qi + b] += S.Td.K[k * N + j] * wj * T.Td[(j * Qi + b) * CM + task];
                    if (!S.Tu.K.empty())
                        for (std::size_t q = 0; q < Qo; ++q)
                            Zu[q * n + k] += T.Tu[(q * n + j) * CM + task] * wj * S.Tu.K[j * N + k];
                }
            for (std::size_t f = 0; f < nf; ++f)
                for (int k = 0; k < n; ++k) {
                    if (!S.Td.D.empty()) Ddf[f] += B[f * n + k] * S.Td.D[k];
                    if (!S.Tu.D.empty()) Duf[f] += B[f * n + k] * S.Tu.D[k];
                }
        }
        for (std::size_t a = 0; a < P; ++a) {
            double v = 0.0;
            if (kind[a] == kDown && rough_top) {
                for (int k = 0; k < n; ++k) v += px(xa[a], k) * g.W[k] * Zd[k * Qi + ta[a]];
                for (std::size_t f = 0; f < nf; ++f)
                    v += X[(xa[a] * nf + f) * CM + task] * Ddf[f] * TdF[(f * Qi + ta[a]) * CM + task] *
                         order_w * mu_f[f] * w_f[f];
            } else if (kind[a] == kUp && rough_top) {
                for (int k = 0; k < n; ++k) v += Zu[ta[a] * n + k] * g.W[k] * pe(k, ea[a]);
                for (std::size_t f = 0; f < nf; ++f)
                    v += TuF[(ta[a] * nf + f) * CM + task] * Duf[f] * E[(f * Qe + ea[a]) * CM + task] *
                         order_w * mu_f[f] * w_f[f];
            } else if (kind[a] == kDown) {
                const int e = ta[a];
                if (!S.Td.K.empty())
                    for (int k = 0; k < n; ++k) v += px(xa[a], k) * g.W[k] * S.Td.K[k * N + e];
                if (m == 0 && !S.Td.D.empty()) dbeam[a * C + c] = S.Td.D[e];
            } else if (kind[a] == kUp) {
                const int e = ta[a];
                if (!S.Tu.K.empty())
                    for (int k = 0; k < n; ++k) v += S.Tu.K[e * N + k] * g.W[k] * pe(k, ea[a]);
                if (m == 0 && !S.Tu.D.empty()) dbeam[a * C + c] = S.Tu.D[e];
            } else {
                for (int k = 0; k < n; ++k) v += px(xa[a], k) * g.W[k] * Z[k * Qe + ea[a]];
                if (!S.Rb.D.empty())
                    for (std::size_t f = 0; f < nf; ++f)
                        v += X[(xa[a] * nf + f) * CM + task] * Df[f] * E[(f * Qe + ea[a]) * CM + task] *
                             order_w * mu_f[f] * w_f[f];
            }
            V[task * P + a] = v;
        }
    });
    parallel_for(P, 256, [&](std::size_t begin, std::size_t end) {
        std::vector<double> cm(M);
        for (std::size_t a = begin; a < end; ++a) {
            const std::size_t p = active[a];
            const double dphi =
                std::atan2(wi_[3 * p + 1], wi_[3 * p]) - std::atan2(wo_[3 * p + 1], wo_[3 * p]) - kPi;
            for (int m = 0; m < M; ++m) cm[m] = std::cos(m * dphi);
            for (int c = 0; c < C; ++c) {
                double sum = 0.0;
                for (int m = 0; m < M; ++m) sum += V[(static_cast<std::size_t>(c) * M + m) * P + a] * cm[m];
                sum += dbeam[a * C + c] * fbeam[a * C + c];
                const double v = sum * scale[a * C + c] + direct[a * C + c];
                out[p * C + c] = std::isfinite(v) ? v : 0.0;
            }
        }
    });
}

} // namespace bsdflab
