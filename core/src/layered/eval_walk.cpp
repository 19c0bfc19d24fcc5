// eval's walk as steps (eval_walk.h): enter, fly, scatter at a vertex, cross the exit-side or
// the far boundary, survive.
#include "eval_walk.h"
#include <algorithm>
#include <cmath>

namespace bsdflab::layered {

EvalWalk::EvalWalk(const LayeredBSDF &model, const Query &q, PCG32 &rng, WalkMemory &mem, Side entry,
                   Side exit)
    : m_(model), q_(q), rng_(rng), ch_(mem.chain), walk_(model, q, rng, exit, mem.beta, mem.wgt, mem.fly_tr),
      tmp_(mem.tmp), tr_(mem.tr), contrib_(mem.contrib), C_(model.channels()), K_(int(model.slabs_.size())),
      entry_(entry), exit_(exit), nee_(model.options_.nee) {}

// flatten: the steps inline into the loop, as the one function they were (per-event calls
// cost a few % on long walks, docs/estimators.md "Walk refactor speed").
[[gnu::flatten]] bool EvalWalk::run(const Vec3 &wi, double entry_scale) {
    if (!enter(wi, entry_scale)) return false;
    for (int events = 1; events <= m_.options_.max_depth; ++events)
        if (!event() || !walk_.survive(events, kEvalRoulette)) return false;
    return true; // cut by the depth cap
}

// The entry vertex connects (a rough entry toward a chain on the other side) before its
// own sample enters the stack.
bool EvalWalk::enter(const Vec3 &wi, double entry_scale) {
    std::fill(walk_.beta, walk_.beta + C_, 1.0);
    covered_ = true;
    const int j = outer_slab(entry_, K_);
    const int e = outer_boundary(entry_, K_);
    const BSDF &E = *m_.boundaries_[std::size_t(e)];
    const Query &qe = boundary_query(q_, e);
    if (entry_ != exit_ && !(E.lobes() & kDeltaTransmission) && ch_.ok[j]) {
        if (entry_scale > 0) {
            E.eval(wi, -ch_.u[j], kTransmission, qe, tmp_);
            for (int c = 0; c < C_; ++c) tmp_[c] *= entry_scale;
            connect(j, tmp_, m_.slabs_[std::size_t(j)].thickness, E.pdf(wi, -ch_.u[j], kTransmission, qe));
        }
    }
    BSDFSample s = sample_boundary(E, wi, kTransmission, qe, rng_, walk_.wgt);
    if (!s.lobe) return false;
    if (!walk_.enter(entry_, s.wo, walk_.wgt)) return false;
    if (entry_ != exit_) {
        covered_ = !(s.lobe & kDelta);
        exit_through(j, walk_.dir, walk_.depth, s.pdf, covered_);
    }
    return true;
}

// One event: a flight, then a scattering vertex or a boundary. False when the walk ends.
bool EvalWalk::event() {
    const bool up = walk_.heads_to_ref();
    switch (walk_.fly()) {
    case Flight::Stuck: return false;
    case Flight::Scattered: scatter_vertex(); return true;
    case Flight::Arrived: break;
    }
    const int b = walk_.arrive();
    return up ? cross_exit_side(b) : cross_far_side(b);
}

// A scattering event at walk_.depth (below the exit side): connect, then sample the phase.
void EvalWalk::scatter_vertex() {
    const int j = walk_.slab;
    const double zx = walk_.depth;
    const Slab &S = walk_.slab_here();
    const Vec3 w = walk_.dir;
    const double to_exit_pdf = ch_.ok[j] ? S.phase.eval(w, -ch_.u[j]) : 0.0;
    for (int c = 0; c < C_; ++c) tmp_[c] = to_exit_pdf;
    connect(j, tmp_, zx, to_exit_pdf);
    connect_away(j, w, zx);
    const Vec3 w2 = walk_.scatter();
    covered_ = true;
    if (heads_to(exit_, w2)) exit_through(j, w2, zx, S.phase.eval(w, w2), true);
    walk_.dir = w2;
}

// Exit-side boundary: at the stack's exit only reflect (leaving is counted by the
// connections); an interior one may also pass on toward the exit.
bool EvalWalk::cross_exit_side(int b) {
    const uint32_t mask = b == outer_boundary(exit_, K_) ? uint32_t(kReflection) : uint32_t(kAll);
    const BSDFSample s = walk_.cross(b, mask);
    if (!s.lobe) return false;
    if (s.lobe & kTransmission) {
        if (!(s.lobe & kDelta)) {
            covered_ = true; // strategy B at this boundary counted the crossing
        } else if (!covered_) {
            exit_through(walk_.slab, walk_.dir, walk_.depth, 0.0, false);
        }
    }
    return true;
}

// Non-exit side: a vertex that may be the last one before leaving.
bool EvalWalk::cross_far_side(int b) {
    const int j = walk_.slab;
    const BSDF &V = *m_.boundaries_[std::size_t(b)];
    const Query &qv = boundary_query(q_, b);
    const bool outer = b == 0 || b == K_;
    const uint32_t mask = outer ? uint32_t(kReflection) : uint32_t(kAll);
    const double zx = walk_.depth;
    if (ch_.ok[j] && (V.lobes() & (kDiffuseReflection | kGlossyReflection))) {
        V.eval(-walk_.dir, -ch_.u[j], kReflection, qv, tmp_);
        if (any_positive(tmp_, C_)) connect(j, tmp_, zx, V.pdf(-walk_.dir, -ch_.u[j], mask, qv));
    }
    const BSDFSample s = walk_.cross(b, mask);
    if (!s.lobe) return false;
    if (s.lobe & kReflection) {
        covered_ = !(s.lobe & kDelta);
        exit_through(j, walk_.dir, zx, s.pdf, covered_);
    }
    return true;
}

} // namespace bsdflab::layered
