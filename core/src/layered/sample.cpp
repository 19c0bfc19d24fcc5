// sample() and pdf(): the entry boundary's own reflection exactly, the rest by sample()'s walk
// (sample_walk.cpp); pdf() estimates the density of that walk's exits.
#include <algorithm>
#include <cmath>
#include "bsdflab/sampling.h"
#include "bsdflab/scratch.h"
#include "bsdflab/frame.h"
#include "walk.h"

namespace bsdflab {

using layered::kNonDeltaTransmission;

// The density with which sample() returns wo, per draw (it integrates to the share of
// draws that return a direction; the rest end inside the stack). Two parts:
//  - the entry boundary's own reflection, drawn by sample()'s first event: exact;
//  - the walk's exits through the outer boundary X on wo's side, if X transmits through a
//    non-delta lobe: a last-event estimate. The walk is sample()'s own (same events, same
//    roulette); every time it arrives at X heading out it adds X's density of
//    transmitting toward wo, then continues as sample() does (the arrival ends the walk if
//    X transmits). The expected sum over arrivals is the exit density at wo, so the
//    estimate is unbiased but for one defensive pseudo-walk (below: O(1/n) of the mass)
//    that keeps it positive; it is seeded from (seed, wi, wo), so pdf() is a fixed function
//    of the pair, which multiple importance sampling needs for its weights to sum to 1.
//  - a delta X (smooth top): the exits' density is that of the last non-delta vertex's
//    sample refracted through X; not estimated here: the share of draws that leave
//    through X (estimated by the same walks, smoothed so it is never 0) spread as a
//    cosine lobe over the directions X can refract into (see the end of the function).
// pbrt-v4's LayeredBxDF::PDF instead estimates the two-interface TRT density without the
// medium, mixed with 10 % uniform; it does not integrate to the sampler's share.
double LayeredBSDF::pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const {
    if (!usable_direction(wi) || !usable_direction(wo)) return 0.0;
    const bool base_transmits = boundaries_.back()->lobes() & kTransmission;
    if ((wi.z < 0 || wo.z < 0) && !base_transmits) return 0.0;
    const bool reflect = wi.z * wo.z > 0;
    if (!(lobes & (reflect ? kGlossyReflection : kGlossyTransmission))) return 0.0;
    const int K = static_cast<int>(slabs_.size()), C = channels();
    const BSDF &E = *boundaries_[wi.z > 0 ? 0 : K];
    const Query &qe = boundary_query(q, wi.z > 0 ? 0 : K);
    const int n = options_.pdf_samples;
    if (n < 1) return approximate_pdf(wi, wo, reflect, q);
    double p = reflect ? E.pdf(wi, wo, kAll, qe) : 0.0;
    const int x = wo.z > 0 ? 0 : K;
    ThreadWorkspace lease;
    double *buf = lease.get().doubles(3 * C);
    PCG32 rng(hash_directions(options_.seed ^ 0x9df5a1e3c4b2d187ull, wi, wo));
    ExitDensity density{wo, x, (boundaries_[x]->lobes() & kNonDeltaTransmission) != 0, 0.0};
    int left_through_x = 0;
    for (int i = 0; i < n; ++i) {
        const double u1 = rng.uniform();
        const double u2x = rng.uniform();
        const double u2y = rng.uniform();
        BSDFSample s = E.sample(wi, u1, u2x, u2y, kAll, qe, buf + C);
        if (!s.lobe || (s.lobe & kReflection)) continue;
        BSDFSample out = sample_walk(wi, s, q, rng, buf, &density);
        if (out.lobe && !(out.lobe & kDelta) && (out.wo.z > 0) == (wo.z > 0)) ++left_through_x;
    }
    // Rough X: the arrivals' density, with one defensive pseudo-walk whose exit density is
    // a cosine lobe carrying the smoothed share of draws that left through X. Without it the
    // estimate was 0 wherever none of the n walks arrived (36 % of a rough transmissive
    // stack's own samples at n = 1), and MIS then gave the sample no weight. Its mass bias,
    // ((k + 1) / (n + 2) - k / n) / (n + 1) of the share, vanishes as 1 / n.
    const double share = (left_through_x + 1.0) / (n + 2.0);
    if (density.rough) return p + (density.sum + share * std::abs(wo.z) * kInvPi) / (n + 1.0);
    // Delta X: the share of draws leaving through X spread as a cosine lobe over the
    // directions X can refract into. The share is smoothed, (k + 1) / (n + 2), so that a
    // direction sample() returns never reads pdf 0 (with n = 1 the raw k / n was 0 for
    // ~64 % of a smooth top's own samples, and a renderer that drops pdf-0 samples, or an
    // emitter light sampling cannot reach, loses them). The lobe is 0 where X cannot
    // refract toward wo (an outside denser than the slab, beyond the critical angle:
    // sample() never goes there) and normalised over the rest.
    const BSDF &X = *boundaries_[x];
    const Query &qx = boundary_query(q, x);
    double *t = buf + C;
    if (!(X.sample(wo, 0.5, 0.5, 0.5, kDeltaTransmission, qx, t).lobe & kDeltaTransmission)) return p;
    const BSDFSample normal =
        X.sample(Vec3{0.0, 0.0, wo.z > 0 ? 1.0 : -1.0}, 0.5, 0.5, 0.5, kDeltaTransmission, qx, t);
    // sin^2 of the critical angle on wo's side (1: no critical angle)
    const double cone = normal.lobe ? std::min(1.0, normal.eta * normal.eta) : 1.0;
    return p + share * std::abs(wo.z) * kInvPi / cone;
}

// Estimator version 4's pdf (pdf_samples = 0, kept for comparisons): the entry's glossy
// lobe weighted by its reflectance, the rest spread as a cosine lobe over the exit
// hemisphere(s). It integrates to 1, while the sampler returns a direction for only a
// share of its draws, and its shape differs from the walk's exits at grazing angles.
double LayeredBSDF::approximate_pdf(const Vec3 &wi, const Vec3 &wo, bool reflect, const Query &q) const {
    const bool base_transmits = boundaries_.back()->lobes() & kTransmission;
    const int e = wi.z > 0 ? 0 : static_cast<int>(boundaries_.size()) - 1;
    const BSDF &E = *boundaries_[std::size_t(e)];
    const Query &qe = boundary_query(q, e);
    const int C = channels();
    ThreadWorkspace lease;
    double *w = lease.get().doubles(C);
    E.sample(wi, 0.5, 0.5, 0.5, kReflection, qe, w);
    double r = std::clamp(channel_mean(w, C), 0.0, 1.0);
    double p = reflect ? r * E.pdf(wi, wo, kReflection, qe) : 0.0;
    double spread = (1.0 - r) * std::abs(wo.z) * kInvPi;
    p += base_transmits ? 0.5 * spread : spread;
    return p;
}

BSDFSample LayeredBSDF::sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                               const Query &q, double *weight) const {
    zero(weight);
    const int C = channels(), K = static_cast<int>(slabs_.size());
    if (!usable_direction(wi)) return {};
    const bool base_transmits = boundaries_.back()->lobes() & kTransmission;
    if (wi.z < 0 && !base_transmits) return {};
    const int entry = wi.z > 0 ? 0 : K;
    PCG32 rng(hash_directions(options_.seed, wi, Vec3{u1, u2x, u2y}));
    ThreadWorkspace lease;
    double *buf = lease.get().doubles(3 * C);
    double *w = buf + C;

    BSDFSample s = boundaries_[entry]->sample(wi, u1, u2x, u2y, kAll, boundary_query(q, entry), w);
    if (!s.lobe) return {};
    if (s.lobe & kReflection) { // the top's own reflection (delta or glossy)
        if (!(s.lobe & lobes)) return {};
        std::copy(w, w + C, weight);
        // A renderer weights this direction by MIS against light sampling with pdf():
        // report that same density (the weight does not depend on it).
        if (!(s.lobe & kDelta)) s.pdf = pdf(wi, s.wo, kAll, q);
        return s;
    }
    BSDFSample out = sample_walk(wi, s, q, rng, buf, nullptr);
    if (!out.lobe || !(out.lobe & lobes)) return {};
    if (!(out.lobe & kDelta)) out.pdf = pdf(wi, out.wo, kAll, q);
    std::copy(buf, buf + C, weight);
    return out;
}

} // namespace bsdflab
