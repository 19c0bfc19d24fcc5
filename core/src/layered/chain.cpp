// The light chain from wo (strategy A's and B's far end) and its exact delta-region
// continuations: built once per chain, before the walks that connect to it.
#include <algorithm>
#include <cmath>
#include "walk.h"

namespace bsdflab {

using layered::any_positive;
using layered::Chain;
using layered::kMaxSlabs;
using layered::sample_boundary;
using layered::Side;

void LayeredBSDF::build_chain(const Vec3 &wo, Side exit, const Query &q, PCG32 &rng, Chain &ch,
                              double *tr) const {
    const int K = static_cast<int>(slabs_.size()), C = channels();
    for (int j = 0; j < K; ++j) ch.ok[j] = ch.reached[j] = ch.delta[j] = false;
    std::fill(ch.a, ch.a + K * C, 0.0);
    std::fill(ch.B, ch.B + K * C, 0.0);
    double *beyond = ch.beyond, *w = ch.w;
    std::fill(beyond, beyond + C, 1.0);
    Vec3 L = wo;
    for (int step = 0; step < K; ++step) {
        const int j = slab_from(exit, step, K);
        const int xb = near_boundary(exit, j);
        ch.reached[j] = true;
        ch.L[j] = L;
        for (int c = 0; c < C; ++c) ch.B[j * C + c] = beyond[c];
        BSDFSample s = sample_boundary(*boundaries_[xb], L, kTransmission, boundary_query(q, xb), rng, w);
        if (!s.lobe || !any_positive(w, C)) break;
        double cu = std::abs(s.wo.z);
        if (!(cu > 1e-12)) break;
        ch.ok[j] = true;
        ch.delta[j] = s.lobe & kDelta;
        ch.pdf[j] = s.pdf;
        ch.u[j] = s.wo;
        // Radiance-mode weight -> adjoint value f(u, L) / pdf by generalised reciprocity.
        transmittance(j, slabs_[j].thickness / cu, tr);
        for (int c = 0; c < C; ++c) {
            ch.a[j * C + c] = w[c] * s.eta * s.eta / cu;
            beyond[c] *= tr[c] * ch.a[j * C + c] * cu;
        }
        L = -s.wo;
    }
    solve_delta_region(exit, q, ch);
}

// The delta region: the slabs (in exit order from the exit) whose whole straight chain to
// wo is delta, so that every direction in them is fixed by wo. A vertex there can leave
// through delta events only, bouncing between the region's delta boundaries any number of
// times; no other strategy counts those paths (strategy B needs a rough exit-side boundary,
// and the walk never leaves through the exit side). Their total is a deterministic
// 1-D transport problem in the chain's adjoint convention (each event the factor w eta^2
// of a boundary sample in the chain's direction of travel, as build_chain), solved exactly:
//   D_j: a beam entering slab j at its exit-side boundary X_j, travelling along u_j;
//   U_j: a beam leaving slab j's other boundary N_j, travelling back toward X_j;
//   D_j = [j exit slab ? t(X_j) : t(X_j) tau_j' D_j'] + r_in(X_j) tau_j U_j,
//   U_j = rho_j tau_j D_j,  rho_j = r(N_j) + t_dn t_up tau_j''^2 rho_j'' / (1 - r_in(X_j'') tau_j''^2 rho_j''),
// (j' the slab toward the exit, j'' the one away, tau the slab's transmittance along u).
// The straight part of D_j (the chain's a_j |u_j.z| B_j) is strategy A's; the rest
// (up_extra) and U_j (down) are new connections with MIS weight 1. Reflections keep
// |u_j.z|, so the solid-angle Jacobian 1/|u_j.z| of A applies unchanged; every crossing
// of an interior boundary carries its own eta^2 in the w eta^2 factor.
void LayeredBSDF::solve_delta_region(Side exit, const Query &q, Chain &ch) const {
    const int K = static_cast<int>(slabs_.size()), C = channels();
    int order[kMaxSlabs];
    int m = 0;
    for (int step = 0; step < K; ++step) {
        const int j = slab_from(exit, step, K);
        ch.region[j] = false;
        if (m == step && ch.ok[j] && ch.delta[j]) order[m++] = j;
    }
    if (m == 0) return;
    auto mirror = [](const Vec3 &u) { return Vec3{u.x, u.y, -u.z}; };
    auto nb = [&](int j) { return far_boundary(exit, j); };  // N_j
    auto xb = [&](int j) { return near_boundary(exit, j); }; // X_j
    double *w = ch.w, *t_up = ch.beyond;
    for (int k = 0; k < m; ++k) {
        const int j = order[k];
        ch.region[j] = true;
        const double cu = std::abs(ch.u[j].z);
        transmittance(j, slabs_[j].thickness / cu, ch.tau + j * C);
        // X_j seen from inside: a beam travelling toward the exit along mirror(u_j).
        double *rx = ch.r_exit_side + j * C;
        BSDFSample r = boundaries_[xb(j)]->sample(-mirror(ch.u[j]), 0.5, 0.5, 0.5, kDeltaReflection,
                                                  boundary_query(q, xb(j)), w);
        for (int c = 0; c < C; ++c) rx[c] = (r.lobe & kDeltaReflection) ? w[c] : 0.0;
    }
    // Inward to outward: rho_j (stored in `down`).
    for (int k = m - 1; k >= 0; --k) {
        const int j = order[k];
        double *rho = ch.down + j * C;
        BSDFSample r = boundaries_[nb(j)]->sample(-ch.u[j], 0.5, 0.5, 0.5, kDeltaReflection,
                                                  boundary_query(q, nb(j)), w);
        for (int c = 0; c < C; ++c) rho[c] = (r.lobe & kDeltaReflection) ? w[c] : 0.0;
        if (k + 1 == m) continue;
        const int j2 = order[k + 1];
        // Back across N_j from slab j2, toward the exit.
        BSDFSample t = boundaries_[nb(j)]->sample(-mirror(ch.u[j2]), 0.5, 0.5, 0.5, kDeltaTransmission,
                                                  boundary_query(q, nb(j)), t_up);
        if (!(t.lobe & kDeltaTransmission)) continue;
        const double cu2 = std::abs(ch.u[j2].z);
        for (int c = 0; c < C; ++c) {
            const double t_dn = ch.a[j2 * C + c] * cu2;
            const double g = ch.tau[j2 * C + c] * ch.tau[j2 * C + c] * ch.down[j2 * C + c];
            const double denom = 1.0 - ch.r_exit_side[j2 * C + c] * g;
            if (denom > 1e-12) rho[c] += t_dn * t_up[c] * t.eta * t.eta * g / denom;
        }
    }
    // Outward to inward: D_j (stored in `up_extra` for now), then the connection factors.
    for (int k = 0; k < m; ++k) {
        const int j = order[k];
        const double cu = std::abs(ch.u[j].z);
        for (int c = 0; c < C; ++c) {
            const int i = j * C + c;
            const double tau = ch.tau[i];
            double d_in; // the beam arriving through X_j
            if (k == 0) {
                d_in = ch.a[i] * cu;
            } else {
                const int jp = order[k - 1], ip = jp * C + c;
                d_in = ch.a[i] * cu * ch.tau[ip] * ch.up_extra[ip];
            }
            const double denom = 1.0 - ch.r_exit_side[i] * tau * tau * ch.down[i];
            const double D = denom > 1e-12 ? d_in / denom : 0.0;
            ch.up_extra[i] = D;
            ch.down[i] *= tau * D; // U_j
        }
    }
    for (int k = 0; k < m; ++k) {
        const int j = order[k];
        const double cu = std::abs(ch.u[j].z);
        for (int c = 0; c < C; ++c) {
            const int i = j * C + c;
            const double straight = ch.a[i] * cu * ch.B[i];
            ch.up_extra[i] = std::max(0.0, ch.up_extra[i] - straight) / cu;
            ch.down[i] /= cu;
        }
    }
}

} // namespace bsdflab
