// The walk's shared steps (walk.h): enter, fly, scatter, arrive, cross, survive.
#include "walk.h"
#include <algorithm>
#include <cmath>

namespace bsdflab::layered {

bool any_positive(const double *v, int n) {
    for (int c = 0; c < n; ++c)
        if (v[c] > 0) return true;
    return false;
}

double max_channel(const double *v, int n) {
    double m = 0;
    for (int c = 0; c < n; ++c) m = std::max(m, v[c]);
    return m;
}

BSDFSample sample_boundary(const BSDF &b, const Vec3 &wi, uint32_t mask, const Query &q, PCG32 &rng,
                           double *weight) {
    const double u1 = rng.uniform();
    const double u2 = rng.uniform();
    const double u3 = rng.uniform();
    return b.sample(wi, u1, u2, u3, mask, q, weight);
}

bool Walk::enter(Side entry, const Vec3 &w, const double *weight) {
    std::copy(weight, weight + C_, beta);
    slab = outer_slab(entry, K_);
    depth = entry == ref_ ? 0.0 : slab_here().thickness;
    dir = w;
    // Roulette compares the throughput with its value after entering, so a small entry
    // factor (grazing Fresnel transmission) does not make every walk die early.
    beta_entry = max_channel(beta, C_);
    return beta_entry > 0;
}

Flight Walk::fly() {
    const Slab &S = slab_here();
    const bool up = heads_to(ref_, dir);
    const double cz = std::abs(dir.z);
    if (!(cz > 1e-9)) return Flight::Stuck;
    const double room = up ? depth : S.thickness - depth;
    const double t = m_.estimator_ == Estimator::Pfmc2 && m_.min_extinction_[std::size_t(slab)]
                         ? m_.fly_min_extinction(std::size_t(slab), room, cz, rng_, beta, fly_tr)
                         : m_.fly(S, room, cz, rng_, beta, fly_tr);
    if (t < 0) return Flight::Arrived;
    depth += up ? -t * cz : t * cz;
    return Flight::Scattered;
}

Vec3 Walk::scatter() const {
    const double u1 = rng_.uniform();
    const double u2 = rng_.uniform();
    return slab_here().phase.sample(dir, u1, u2);
}

int Walk::arrive() {
    const bool up = heads_to(ref_, dir);
    depth = up ? 0.0 : slab_here().thickness;
    return up ? near_boundary(ref_, slab) : far_boundary(ref_, slab);
}

BSDFSample Walk::cross(int b, uint32_t mask) {
    BSDFSample s =
        sample_boundary(*m_.boundaries_[std::size_t(b)], -dir, mask, boundary_query(q_, b), rng_, wgt);
    if (!s.lobe) return s;
    for (int c = 0; c < C_; ++c) beta[c] *= wgt[c];
    dir = s.wo;
    // A transmission through an outer boundary leaves the stack: the position is moot.
    if (!(s.lobe & kTransmission) || b == 0 || b == K_) return s;
    const bool toward = b == near_boundary(ref_, slab);
    slab += toward ? step_toward(ref_) : -step_toward(ref_);
    depth = toward ? slab_here().thickness : 0.0;
    return s;
}

bool Walk::survive(int events, Roulette r) {
    if (events < r.first_event || (!r.at_cap && events >= m_.options_.max_depth)) return true;
    const double m = max_channel(beta, C_) / beta_entry;
    if (!(m > 0)) return false;
    if (m < 1) {
        const double u_survive = rng_.uniform();
        if (u_survive >= m) return false;
        for (int c = 0; c < C_; ++c) beta[c] /= m;
    }
    return true;
}

} // namespace bsdflab::layered
