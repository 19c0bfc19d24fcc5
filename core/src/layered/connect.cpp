// eval's connections to the light chain (eval_walk.h): strategy A, the delta region's
// connection away from the exit, and strategy B, combined by the power heuristic.
#include "eval_walk.h"
#include <cmath>
#include "bsdflab/sampling.h"

namespace bsdflab::layered {

void EvalWalk::connect(int j, const double *value, double depth, double p_vertex) {
    // Without nee, A is kept only through a delta chain (B cannot count those paths).
    if (!ch_.ok[j] || (!nee_ && !ch_.delta[j])) return;
    const double wA = ch_.delta[j] ? 1.0 : power_heuristic(ch_.pdf[j], p_vertex);
    if (!(wA > 0)) return;
    const double *beta = walk_.beta;
    m_.transmittance(j, depth / std::abs(ch_.u[j].z), tr_);
    for (int c = 0; c < C_; ++c)
        contrib_[c] += beta[c] * value[c] * tr_[c] * ch_.a[j * C_ + c] * ch_.B[j * C_ + c] * wA;
    // In the delta region (wA is 1 there): the same departure, back by delta reflections
    // before it leaves.
    if (ch_.region[j])
        for (int c = 0; c < C_; ++c) contrib_[c] += beta[c] * value[c] * tr_[c] * ch_.up_extra[j * C_ + c];
}

void EvalWalk::connect_away(int j, const Vec3 &w_in, double depth) {
    if (!ch_.region[j]) return;
    const Vec3 &u = ch_.u[j];
    const Slab &S = m_.slabs_[std::size_t(j)];
    const double p = S.phase.eval(w_in, Vec3{-u.x, -u.y, u.z});
    if (!(p > 0)) return;
    m_.transmittance(j, (S.thickness - depth) / std::abs(u.z), tr_);
    for (int c = 0; c < C_; ++c) contrib_[c] += walk_.beta[c] * p * tr_[c] * ch_.down[j * C_ + c];
}

bool EvalWalk::rough_exit(int j) const {
    return (m_.boundaries_[std::size_t(near_boundary(exit_, j))]->lobes() & kNonDeltaTransmission) != 0;
}

void EvalWalk::exit_through(int j, const Vec3 &w, double depth, double p_sampled, bool mis) {
    if (!ch_.reached[j] || !rough_exit(j)) return;
    const int xb = near_boundary(exit_, j);
    const BSDF &X = *m_.boundaries_[std::size_t(xb)];
    const Query &qx = boundary_query(q_, xb);
    const Vec3 &L = ch_.L[j];
    X.eval(-w, L, kTransmission, qx, tmp_);
    if (!any_positive(tmp_, C_)) return;
    double wB = 1.0;
    if (nee_ && mis) wB = power_heuristic(p_sampled, X.pdf(L, -w, kTransmission, qx));
    m_.transmittance(j, depth / std::abs(w.z), tr_);
    const double inv_cos = 1.0 / std::abs(L.z);
    for (int c = 0; c < C_; ++c)
        contrib_[c] += walk_.beta[c] * tr_[c] * tmp_[c] * inv_cos * ch_.B[j * C_ + c] * wB;
}

} // namespace bsdflab::layered
