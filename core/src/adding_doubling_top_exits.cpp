// AddingDoubling::eval_rough_top (adding_doubling.h): transmission both ways and reflection
// from below of a transmissive stack with a rough top and a smooth dielectric base. The
// stack's four operators come from the adding equations (ad::stack_operators: the top's
// reflection from below, slabs, interior boundaries, the base's internal reflection,
// identity transmissions); the base's refracted query cosines are zero-weight extras in
// the last slab, as for a two-sided stack, and the base's delta weights apply at the ends.
// The top's transmission lobes are narrower than the nodes resolve, so at the exit above
// (viewer above) and the entry (light above) they are integrated on fine nodes against the
// panel-wise interpolant of the radiance at the nodes (ad::top_operators: Tu W L and
// Td's columns, as for reflection from above). An operator's delta part D (the unscattered
// beam, delta reflections inside) is not smooth across a beam: it carries the beam to one
// direction inside, where the top's BSDF is evaluated directly (a point value of a lobe
// narrower than the orders resolve): Td.D(v) f_top(w_v, wo) down, f_top(wi, w_l) Tu.D(l)
// up, and Td.D(v) f_top(w_v, w_l) Tu.D(l) for the beam that enters through the base and
// returns by one reflection from below at the top (ad::rough_top_with_extras leaves that
// entry out of the kernel).
#include <algorithm>
#include <cmath>
#include "adding_doubling_parts.h"
#include "bsdflab/constants.h"
#include "bsdflab/frame.h"
#include "bsdflab/parallel.h"

namespace bsdflab {

using ad::Grid;

namespace {

enum Kind { kDown = 0, kUp = 1, kBelow = 2 };  // transmission down, up, reflection from below

// The direction inside (cosine mu, pointing down) with the azimuth of the outside direction o.
Vec3 inside_down(const double *o, double mu) {
    const double r = std::hypot(o[0], o[1]);
    const double sn = std::sqrt(std::max(0.0, (1.0 - mu) * (1.0 + mu)));
    return r > 0 ? Vec3{sn * o[0] / r, sn * o[1] / r, -mu} : Vec3{0.0, 0.0, -1.0};
}

} // namespace

void AddingDoubling::eval_rough_top(const double *wi_, const double *wo_, std::size_t count,
                                    double *out) const {
    const std::size_t K = slabs_.size();
    const int C = channels(), M = orders_, n = static_cast<int>(mu_.size());
    const std::size_t CM = static_cast<std::size_t>(C) * M;
    const BSDF &top = *boundaries_[0], &base = *boundaries_[K];
    // The light's solid angle inside the last slab is (nK / nK+1)^2 its own below.
    const double r = media_[K] / media_[K + 1];
    // Per active pair: its kind, the base's inside cosines (viewer, light; 0 where the top
    // is crossed instead), the top's outside cosine, its scale per channel.
    std::vector<std::size_t> active;
    std::vector<int> kind;
    std::vector<double> view_cos, light_cos, top_cos, scale;
    std::vector<double> tv(C), tl(C);
    for (std::size_t p = 0; p < count; ++p) {
        const double *wi = &wi_[3 * p], *wo = &wo_[3 * p];
        if (!usable_direction(Vec3{wi[0], wi[1], wi[2]}) || !usable_direction(Vec3{wo[0], wo[1], wo[2]}) ||
            wi[2] == 0 || wo[2] == 0)
            continue;
        if (wi[2] > 0 && wo[2] > 0) continue;  // reflection from above: eval's own path
        const int k = wi[2] < 0 ? (wo[2] > 0 ? kDown : kBelow) : kUp;
        double mu_v = 0.0, mu_l = 0.0, s = std::abs(wo[2]);
        std::fill(tv.begin(), tv.end(), 1.0);
        std::fill(tl.begin(), tl.end(), 1.0);
        if (k != kUp) {
            ad::delta_weight(base, wi[2], kDeltaTransmission, tv.data(), &mu_v);
            if (!(mu_v > 0)) continue;
        }
        if (k != kDown) {
            ad::delta_weight(base, wo[2], kDeltaTransmission, tl.data(), &mu_l);
            if (!(mu_l > 0)) continue;
            s *= r * r;
        }
        for (int c = 0; c < C; ++c) scale.push_back(tv[c] * tl[c] * s);
        kind.push_back(k);
        view_cos.push_back(mu_v);
        light_cos.push_back(mu_l);
        top_cos.push_back(k == kDown ? wo[2] : (k == kUp ? wi[2] : 0.0));
        active.push_back(p);
    }
    if (active.empty()) return;
    const std::size_t P = active.size();

    // The grid: nodes, then the base's refracted query cosines; the top's outside cosines
    // of the light (down) and the viewer (up).
    std::vector<double> base_cos, ins, outs;
    for (std::size_t a = 0; a < P; ++a) {
        if (kind[a] != kUp) base_cos.push_back(view_cos[a]);
        if (kind[a] != kDown) base_cos.push_back(light_cos[a]);
        if (kind[a] == kDown) ins.push_back(top_cos[a]);
        if (kind[a] == kUp) outs.push_back(top_cos[a]);
    }
    std::vector<int> bi, ii, oi;
    const std::vector<double> extras = ad::distinct(base_cos, bi), qi = ad::distinct(ins, ii),
                              qo = ad::distinct(outs, oi);
    std::vector<double> grid(mu_);
    grid.insert(grid.end(), extras.begin(), extras.end());
    const ad::Sizes s{C, M, half_samples_, n, grid.size()};
    const std::size_t N = s.N, Qi = qi.size(), Qo = qo.size();
    std::vector<int> ve(P, -1), le(P, -1), ta(P, -1);  // viewer / light extra, top cosine index
    for (std::size_t a = 0, b = 0, u = 0, v = 0; a < P; ++a) {
        if (kind[a] != kUp) ve[a] = n + bi[b++];
        if (kind[a] != kDown) le[a] = n + bi[b++];
        if (kind[a] == kDown) ta[a] = ii[u++];
        if (kind[a] == kUp) ta[a] = oi[v++];
    }

    // The unscattered beam meets the top's lobe at one direction: its BSDF there (f, no
    // cosine), evaluated directly.
    std::vector<double> fbeam(P * C, 0.0);
    parallel_for(P, 16, [&](std::size_t begin, std::size_t end) {
        Query q;
        std::vector<double> f(C);
        for (std::size_t a = begin; a < end; ++a) {
            const std::size_t p = active[a];
            const Vec3 wi{wi_[3 * p], wi_[3 * p + 1], wi_[3 * p + 2]},
                wo{wo_[3 * p], wo_[3 * p + 1], wo_[3 * p + 2]};
            const Vec3 v = kind[a] == kUp ? wi : inside_down(&wi_[3 * p], view_cos[a]);
            const Vec3 l = kind[a] == kDown ? wo : inside_down(&wo_[3 * p], light_cos[a]);
            top.eval(v, l, kAll, q, f.data());
            for (int c = 0; c < C; ++c) fbeam[a * C + c] = f[c] / std::abs(l.z);
        }
    });

    std::vector<ad::BoundaryOperators> below(K + 1);
    for (std::size_t j = 1; j <= K; ++j)
        below[j] = ad::boundary_operators(*boundaries_[j], j < K, index_matched(j), grid, s);
    std::vector<ad::SlabOperators> slabs;
    slabs.reserve(K);
    for (std::size_t j = 0; j < K; ++j) slabs.emplace_back(slabs_[j], grid, settings_, M);
    const ad::TopOperators T = ad::rough_top_with_extras(top, grid, mu_, w_, breaks_, qi, qo, settings_, s);

    std::vector<double> V(CM * P, 0.0), dbeam(P * C, 0.0);  // dbeam: the stack's delta part per pair
    parallel_for_each(CM, [&](std::size_t task) {
        const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
        const Grid g{n, static_cast<int>(N), order_weights(m, N)};
        const ad::LayerOperators S = ad::stack_operators(T, below, slabs, s, c, m, g);
        auto td = [&](int k, int b) { return T.Td[(static_cast<std::size_t>(k) * Qi + b) * CM + task]; };
        auto tu = [&](int q, int k) { return T.Tu[(static_cast<std::size_t>(q) * n + k) * CM + task]; };
        auto d = [](const ad::Op &o, int i) { return o.D.empty() ? 0.0 : o.D[i]; };
        for (std::size_t a = 0; a < P; ++a) {
            double v = 0.0, beam = 0.0;
            if (kind[a] == kDown) {
                if (!S.Td.K.empty())
                    for (int k = 0; k < n; ++k) v += S.Td.K[ve[a] * N + k] * g.W[k] * td(k, ta[a]);
                beam = d(S.Td, ve[a]);
            } else if (kind[a] == kUp) {
                if (!S.Tu.K.empty())
                    for (int k = 0; k < n; ++k) v += tu(ta[a], k) * g.W[k] * S.Tu.K[k * N + le[a]];
                beam = d(S.Tu, le[a]);
            } else {
                if (!S.Rb.K.empty()) v = S.Rb.K[ve[a] * N + le[a]];
                beam = d(S.Td, ve[a]) * d(S.Tu, le[a]);
            }
            V[task * P + a] = v;
            if (m == 0) dbeam[a * C + c] = beam;  // a delta part is the same at every order
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
                double sum = dbeam[a * C + c] * fbeam[a * C + c];
                for (int m = 0; m < M; ++m) sum += V[(static_cast<std::size_t>(c) * M + m) * P + a] * cm[m];
                const double v = sum * scale[a * C + c];
                out[p * C + c] = std::isfinite(v) ? v : 0.0;
            }
        }
    });
}

} // namespace bsdflab
