// The delta (unscattered) lobes of a layered stack, exactly: the light whose every event
// is a delta one (a smooth boundary's reflection or refraction, a flight through a slab
// without scattering). PFMC's sample() returns these paths as the stack's delta lobes
// (core/src/layered/sample_walk.cpp: all_delta) and eval leaves them out, so a table of
// the scattered part lacks them; the table BSDF adds them at lookup from this.
//
// Along a fixed incident direction every such path stays on one straight chain of
// directions (the refractions of wi), so its total is a 1-D adding problem per channel.
// Boundaries in order from the entry side, i = 0..K; v_i the direction travelling inward
// just before boundary i (v_0 = -wi), v_{i+1} its refraction; m(v) its mirror (z -> -z).
// Per boundary, the weights of its masked delta samples (the factors PFMC's walk
// multiplies its throughput by, radiance mode: a refraction carries T (n_i / n_t)^2):
//   r_i = sample(-v_i, delta reflection)       (back toward the entry side)
//   t_i = sample(-v_i, delta transmission)     (inward, along v_{i+1})
//   s_i = sample(-m(v_{i+1}), delta reflection) (the inside of boundary i, inward again)
//   u_i = sample(-m(v_{i+1}), delta transmission) (out through i, along m(v_i))
// and the slab between boundaries i and i+1 attenuates a crossing by
//   a_i = exp(-sum_c sigma_t d / |v_{i+1}.z|)   (sigma_t = sigma_a + sigma_s: scattering
//   removes light from the unscattered beam).
// The part of the stack from boundary i inward reflects R_i and transmits T_i:
//   R_K = r_K, T_K = t_K,
//   R_i = r_i + t_i a_i^2 R_{i+1} u_i / (1 - s_i a_i^2 R_{i+1}),
//   T_i = t_i a_i T_{i+1} / (1 - s_i a_i^2 R_{i+1}),
// the geometric series of bounces between boundary i's inside and the rest summed in
// closed form (every term is a path: t_i (a_i^2 R_{i+1} s_i)^k a_i^2 R_{i+1} u_i). R_0
// includes the entry boundary's own delta reflection r_0. For one slab between a smooth
// top and a smooth base this is T_top [R_base a^2 sum_k (R_top,inside R_base a^2)^k] T_top'
// plus R_top, and T_top a T_base / (1 - R_top,inside R_base a^2).
#pragma once
#include <memory>
#include <vector>
#include "bsdf.h"

namespace bsdflab {

class TableDeltaStack {
  public:
    // boundaries top first (K + 1), thickness_um and sigma_t (1/um, per slab, one per channel
    // of the boundaries) per slab (K).
    TableDeltaStack(std::vector<std::shared_ptr<const BSDF>> boundaries, std::vector<double> thickness_um,
                    std::vector<std::vector<double>> sigma_t);
    int channels() const { return C_; }
    // Whether a delta path can reflect (beyond the entry boundary's own) or transmit.
    bool transmits() const { return transmits_; }
    // Whether any delta path other than the entry boundary's own reflection exists, from
    // either side (a smooth entry over a boundary with a delta reflection, or transmission):
    // without one the stack's delta lobes are the boundaries' own.
    bool extends() const { return extends_; }
    // The delta lobes of light arriving along wi (the side from wi.z): reflectance R and
    // transmittance T per channel (weights toward reflect(wi) and toward `wt`, radiance
    // mode), `eta` = n_t / n_i across the stack. Returns false when nothing transmits
    // (T = 0, wt undefined). q's film thickness goes to the top boundary only, as PFMC's
    // walk passes it (boundary_query): every other boundary keeps its own film.
    bool solve(const Vec3 &wi, const Query &q, double *R, double *T, Vec3 &wt, double &eta) const;

  private:
    std::vector<std::shared_ptr<const BSDF>> boundaries_;
    std::vector<double> thickness_;
    std::vector<std::vector<double>> sigma_t_;
    int C_ = 0;
    bool transmits_ = false, extends_ = false;
};

} // namespace bsdflab
