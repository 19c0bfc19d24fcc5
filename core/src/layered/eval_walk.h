// eval's walk (PFMC, Guo et al. 2018): starts at wi, never leaves through the exit side,
// and adds the light it can send to wo at every non-delta vertex (connect.cpp):
//   strategy A   connect a vertex to the light chain (next-event estimation);
//   away         the delta region's connection away from the exit (solve_delta_region);
//   strategy B   a direction sampled toward a rough exit-side boundary evaluates its BTDF
//                toward the chain.
// Steps (eval_walk.cpp): enter, then per event: fly, and a scattering vertex or a
// crossing of the exit-side or the far boundary; survive after each.
#pragma once
#include "walk.h"

namespace bsdflab::layered {

class EvalWalk {
  public:
    EvalWalk(const LayeredBSDF &model, const Query &q, PCG32 &rng, WalkMemory &mem, Side entry, Side exit);
    // One walk from wi, adding to mem.contrib; `entry_scale` multiplies the entry vertex's
    // connection (pfmc2 adds it once per chain). True if the depth cap cut it.
    bool run(const Vec3 &wi, double entry_scale);

  private:
    // Steps.
    bool enter(const Vec3 &wi, double entry_scale);
    bool event();
    void scatter_vertex();
    bool cross_exit_side(int b);
    bool cross_far_side(int b);
    // Connections (connect.cpp). Strategy A: `value` holds the vertex term per channel (BSDF
    // eval with its cosine, or the phase function), `depth` the distance to the exit side,
    // `p_vertex` the density with which the vertex would have sampled -u_j.
    void connect(int j, const double *value, double depth, double p_vertex);
    // Delta-chain connection away from the exit (a scattering vertex at `depth` below the
    // exit side of region slab j): along mirror(-u_j) to N_j, then delta events only.
    void connect_away(int j, const Vec3 &w_in, double depth);
    // Strategy B: the walk heads along w toward slab j's rough exit-side boundary, `depth`
    // below it. `p_sampled` is the density of w at its vertex; `mis` false when no strategy
    // A competes (the vertex was a delta event, or w arrived through delta transmissions).
    void exit_through(int j, const Vec3 &w, double depth, double p_sampled, bool mis);
    bool rough_exit(int j) const;

    const LayeredBSDF &m_;
    const Query &q_;
    PCG32 &rng_;
    const Chain &ch_;
    Walk walk_;
    double *const tmp_, *const tr_, *const contrib_;
    const int C_, K_;
    const Side entry_, exit_;
    const bool nee_;
    // While the walk heads toward the exit, whether the straight continuation from its last
    // non-delta vertex (through delta exit-side boundaries) is counted by that vertex's
    // connections. False after a delta vertex: then strategy B is tried at every exit-side
    // boundary the walk reaches through delta transmissions, the paths' only strategy (Guo
    // et al.'s estimator needs a non-delta vertex to connect from).
    bool covered_ = true;
};

} // namespace bsdflab::layered
