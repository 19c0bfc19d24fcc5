// The random walk of the layered model (core/include/bsdflab/layered.h), as named steps
// shared by eval's estimate (eval_walk.cpp) and sample()/pdf() (sample_walk.cpp):
//   enter    the entry boundary transmitted: the walk starts in the outer slab;
//   fly      a free flight in the current slab: a scattering event, or the boundary ahead;
//   scatter  the phase function draws the next direction;
//   arrive / cross  the boundary ahead samples reflection or transmission into the next slab;
//   survive  Russian roulette on the throughput.
// The position is (slab, depth below the walk's reference side, direction); lateral
// displacement is ignored. Random numbers are drawn in program order, so that every
// estimate is the same whatever the compiler (tests/layered/test_walk_goldens.py).
#pragma once
#include <cstdint>
#include "bsdflab/layered.h"
#include "side.h"

namespace bsdflab::layered {

constexpr int kMaxSlabs = 16;
// A boundary that transmits through a non-delta lobe: strategy B can evaluate it.
constexpr uint32_t kNonDeltaTransmission = kDiffuseTransmission | kGlossyTransmission;

bool any_positive(const double *v, int n);
// The largest channel (0 if none is positive; NaN channels are skipped).
double max_channel(const double *v, int n);
// One boundary sample with its three random numbers drawn in a fixed order.
BSDFSample sample_boundary(const BSDF &b, const Vec3 &wi, uint32_t mask, const Query &q, PCG32 &rng,
                           double *weight);

// When the walk plays Russian roulette: after its `first_event`-th event and every later one,
// and after the last event the depth cap allows only if `at_cap`. eval's walk and sample()'s
// walk keep the schedules they were tuned and tested with (docs/estimators.md, "Where the walk
// lives"): one step, two schedules, so that no estimate changed when they became one.
struct Roulette {
    int first_event;
    bool at_cap;
};
constexpr int kRouletteDepth = 4;
constexpr Roulette kEvalRoulette{kRouletteDepth + 1, true};
constexpr Roulette kSampleRoulette{kRouletteDepth, false};

enum class Flight { Scattered, Arrived, Stuck };

class Walk {
  public:
    // beta, wgt, fly_tr: per-channel buffers (throughput, a boundary sample's weight, the
    // flight's scratch). `ref`: the side depths are measured from.
    Walk(const LayeredBSDF &model, const Query &q, PCG32 &rng, Side ref, double *beta, double *wgt,
         double *fly_tr)
        : m_(model), q_(q), rng_(rng), ref_(ref), C_(model.channels()), K_(int(model.slabs_.size())),
          beta(beta), wgt(wgt), fly_tr(fly_tr) {}

    // The entry boundary on side `entry` transmitted along `w` with weight `weight`:
    // beta = weight. False if nothing entered.
    bool enter(Side entry, const Vec3 &w, const double *weight);
    // A free flight along dir: Scattered (depth moved to the event, beta weighted), Arrived
    // at the boundary ahead, or Stuck (a direction in the slab's plane: the walk ends).
    Flight fly();
    // The phase function's sample of the next direction (dir unchanged until then).
    Vec3 scatter() const;
    // At the boundary ahead: depth set to it; returns its index.
    int arrive();
    // The boundary b just arrived at samples the walk's continuation from -dir under `mask`:
    // beta *= its weight, dir = its direction, and a transmission moves into the next slab.
    BSDFSample cross(int b, uint32_t mask);
    // Russian roulette after `events` events: false when the walk ends.
    bool survive(int events, Roulette r);

    bool heads_to_ref() const { return heads_to(ref_, dir); }
    const Slab &slab_here() const { return m_.slabs_[std::size_t(slab)]; }

    int slab = 0;          // the slab the walk is in
    double depth = 0.0;    // below the reference side of that slab
    Vec3 dir;              // direction of travel
    double beta_entry = 0; // the largest channel of beta after entering (roulette's scale)

  private:
    const LayeredBSDF &m_;
    const Query &q_;
    PCG32 &rng_;
    const Side ref_;
    const int C_, K_;

  public:
    double *const beta, *const wgt, *const fly_tr;
};

// The light chain from wo, sampled once per chain (build_chain, chain.cpp): per slab j, the
// direction u_j leading from the exit side into slab j, the light direction L_j just beyond
// slab j's exit-side boundary, the last-step factor a_j = f_adjoint / pdf and the factor
// B_j of everything beyond that boundary. Its memory is carved from the caller's
// EstimateWorkspace (bind_walk), so walks allocate nothing.
struct Chain {
    bool reached[kMaxSlabs]; // L_j and B_j known (strategy B possible)
    bool ok[kMaxSlabs];      // u_j sampled too (strategy A possible)
    bool delta[kMaxSlabs];
    double pdf[kMaxSlabs];
    Vec3 u[kMaxSlabs], L[kMaxSlabs];
    double *a, *B; // [slab * C + c]
    // Delta-chain connections (all-delta exit side, see solve_delta_region): per slab, the
    // factor (over |u_j.z|) of leaving along -u_j and coming back by at least one delta
    // reflection (up_extra), and of leaving along the mirror of -u_j, away from the exit
    // (down). Zero outside the region.
    double *up_extra, *down;   // [slab * C + c]
    double *tau, *r_exit_side; // region solve: slab transmittance, X_j's reflection
    bool region[kMaxSlabs];
    double *beyond, *w; // chain construction
};

// Everything one of eval's walks uses: the chain and the per-channel buffers.
struct WalkMemory {
    Chain chain;
    double *beta, *tmp, *tr, *wgt, *fly_tr;
    double *contrib; // the walk's contribution, per channel
};

} // namespace bsdflab::layered
