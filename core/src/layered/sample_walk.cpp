// sample()'s walk: the shared steps (walk.h) until the walk leaves the stack through an
// outer boundary (or ends inside); depths measured from the top.
#include "walk.h"

namespace bsdflab {

using layered::Flight;
using layered::kSampleRoulette;
using layered::Side;
using layered::Walk;

namespace {

// The walk left the stack along `wo`: its lobe, and the delta path's probability as pdf
// (a non-delta exit's pdf is the caller's pdf()).
BSDFSample left(const Vec3 &wi, const Vec3 &wo, bool all_delta, double delta_prob, double eta) {
    BSDFSample out;
    out.wo = wo;
    const bool reflected = wi.z * wo.z > 0;
    if (all_delta) out.lobe = reflected ? kDeltaReflection : kDeltaTransmission;
    else out.lobe = reflected ? kGlossyReflection : kGlossyTransmission;
    out.pdf = all_delta ? delta_prob : 0.0;
    out.eta = reflected ? 1.0 : eta;
    return out;
}

} // namespace

// sample()'s walk after the entry boundary transmitted (`s`: that sample, its weight in
// buf[C..2C)). Returns the exit (weight in buf[0..C)) or nothing when the walk ends
// inside. With `density`, every arrival at boundary density->boundary heading out adds
// that boundary's density of transmitting toward density->wo (pdf()).
BSDFSample LayeredBSDF::sample_walk(const Vec3 &wi, BSDFSample s, const Query &q, PCG32 &rng, double *buf,
                                    ExitDensity *density) const {
    const int C = channels(), K = static_cast<int>(slabs_.size());
    Walk walk(*this, q, rng, Side::Top, buf, buf + C, buf + 2 * C);
    double eta = s.eta; // product of the relative indices crossed so far
    // A path with no non-delta vertex is a delta lobe of the stack (eval has no density
    // for it): it is labelled delta, with the probability of its discrete choices as pdf.
    bool all_delta = (s.lobe & kDelta) != 0;
    double delta_prob = s.pdf;
    if (!walk.enter(layered::side_of(wi), s.wo, walk.wgt)) return {};
    for (int events = 1; events <= options_.max_depth; ++events) {
        switch (walk.fly()) {
        case Flight::Stuck: return {};
        case Flight::Scattered:
            walk.dir = walk.scatter();
            all_delta = false;
            break;
        case Flight::Arrived: {
            const int b = walk.arrive();
            if (density && density->rough && b == density->boundary)
                density->sum +=
                    boundaries_[std::size_t(b)]->pdf(-walk.dir, density->wo, kAll, boundary_query(q, b));
            s = walk.cross(b, kAll);
            if (!s.lobe) return {};
            if (s.lobe & kDelta) delta_prob *= s.pdf;
            else all_delta = false;
            if (s.lobe & kTransmission) {
                eta *= s.eta;
                if (b == 0 || b == K) return left(wi, walk.dir, all_delta, delta_prob, eta);
            }
            break;
        }
        }
        if (!walk.survive(events, kSampleRoulette)) return {};
    }
    capped_.fetch_add(1, std::memory_order_relaxed); // cut by the depth cap
    return {};
}

} // namespace bsdflab
