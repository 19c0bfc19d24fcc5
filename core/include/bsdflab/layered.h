// A layered BSDF evaluated by Position-Free Monte Carlo (Guo, Hasan, Zhao 2018; pbrt-v4's
// LayeredBxDF is the two-interface special case). The stack, top to bottom:
//     boundary 0 (top interface), slab 0, boundary 1, slab 1, ..., slab K-1, boundary K (base)
// Boundaries are BSDFs whose exterior (+z) is the slab above and interior (-z) the slab
// below; the base is any BSDF (diffuse, conductor, or an interface to a medium below).
// Slabs have a thickness (um), a spectral absorption sigma_a (1/um), a grey scattering
// coefficient sigma_s (1/um) and a phase function. Lateral displacement is ignored, so a
// path vertex is just (slab, depth, direction).
//
// eval(wi, wo): random walks start at wi (the camera side, radiance transport) and carry
// a spectral throughput. A "light chain" is sampled once per walk from wo through the
// boundaries on the exit side (transmission only), giving per slab the direction u_j that
// leads straight out to wo and the factor of that unscattered path. Every non-delta vertex
// (medium scattering, reflection at the non-exit side of a slab, a rough entry in
// transmission) connects to the chain (next-event estimation, strategy A; through delta
// exit-side boundaries the chain is deterministic and A is the only strategy). After a
// vertex samples a direction toward a rough exit-side boundary, that boundary's BTDF toward
// the chain is evaluated (strategy B); A and B are combined with the power heuristic.
// A path whose last non-delta vertex cannot connect (it is followed by delta events only:
// a smooth base or interior reflection, or the rough entry of a reflection path) is
// counted by strategy B alone, at the first rough exit-side boundary the walk reaches
// through delta transmissions (the walk's `covered` flag tracks this). A path that leaves
// its last non-delta vertex through delta events only, with at least one reflection (a
// smooth exit over a smooth base or interior boundary), is counted by the exact
// delta-region connection (solve_delta_region; neither A, which goes straight, nor B,
// which needs a rough exit-side boundary, sees it). The walk itself never leaves through
// the exit side, so no path is counted twice. Russian roulette on the throughput after
// a few events ends every walk without bias; the depth cap is only a safety net, and the
// walks it cuts are counted (EstimateRequest::capped, capped_walks()). The top boundary's
// own reflection is added exactly (non-delta part); its delta part is not estimated: see
// delta_reflectance / sample. pdf() is the density with which sample() returns wo
// (estimated by sample()'s own walk; see core/src/layered/sample.cpp and docs/estimators.md).
//
// A query's film thickness (Query::film_thickness_nm) is the top boundary's film total:
// every other boundary is handed its own film (boundary_query, bsdf.h).
//
// Paths whose every vertex is a delta event (e.g. a smooth coat over a smooth mirror) form
// a delta lobe of the stack and are not part of eval.
//
// The code: core/src/layered/ (walk.h names the walk's steps; docs/estimators.md, "Where
// the walk lives").
// LayeredOptions::estimator selects the walk: 0 "pfmc" (the above; the reference) or 1
// "pfmc2" (the default: groups of kWalksPerChain walks share a chain; bright slabs fly by their smallest
// extinction so spectral weights stay <= 1); docs/estimators.md derives both.
//
// Random numbers are drawn into named locals, in program order, so that the streams (and
// every estimate) are the same whatever compiler evaluates function arguments in which order.
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>
#include "bsdf.h"
#include "estimate.h"
#include "phase.h"
#include "rng.h"

namespace bsdflab {

namespace layered { // the walk's internals, core/src/layered/
enum class Side;
class Walk;
class EvalWalk;
struct Chain;
struct WalkMemory;
} // namespace layered

struct Slab {
    double thickness = 0.0;       // um
    std::vector<double> sigma_a;  // 1/um, per channel
    double sigma_s = 0.0;         // 1/um, grey
    PhaseFunction phase;
};

struct LayeredOptions {
    int samples = 256;    // walks per eval()
    uint64_t seed = 0;
    int max_depth = 1 << 16; // events per walk: a safety net, counted when hit (capped_walks)
    bool nee = true;         // false: B alone wherever it can count a path (same BSDF, no MIS)
    int pdf_samples = 1;     // walks of one pdf() estimate (0: version 4's approximation)
    // 0: Guo et al.'s PFMC as in estimator version 5 (the reference);
    // 1: "pfmc2" (issue 21, docs/estimators.md; the default): kWalksPerChain walks share
    //    one light chain (and the entry connection) where the chain is deterministic (no
    //    non-delta transmission on its way); in thick bright slabs (albedo of the least absorbed channel
    //    >= 0.95, optical depth >= 1) free flights by the smallest extinction, spectral
    //    weights <= 1.
    int estimator = 1;
};

constexpr int kEstimatorPfmc = 0;
constexpr int kEstimatorPfmc2 = 1;
// LayeredOptions::estimator, named (the option stays an int: the Python binding's keyword).
enum class Estimator { Pfmc = kEstimatorPfmc, Pfmc2 = kEstimatorPfmc2 };
// Walks that share one light chain (and its entry connection) in estimator pfmc2.
constexpr int kWalksPerChain = 4;

class LayeredBSDF final : public BSDF, public StochasticEstimator {
  public:
    LayeredBSDF(std::vector<double> wavelengths, std::vector<std::shared_ptr<const BSDF>> boundaries,
                std::vector<Slab> slabs, LayeredOptions options);
    uint32_t lobes() const override;
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const override;
    // A transmitted sample reports eta = the product of the walk's relative indices
    // (n below / n above the stack, or its inverse from below); reflection reports 1.
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes, const Query &q,
                      double *weight) const override;
    const StochasticEstimator *stochastic() const override { return this; }
    // The same stack with every boundary's film looked up (BSDF::with_film_lookup): the
    // top's at thickness_nm, the others' at their own (a query's thickness is the top's).
    std::shared_ptr<const BSDF> with_film_lookup(double thickness_nm, FilmLookupStats &stats) const override;

    // The whole non-delta BSDF: the multiply scattered light plus the top's own reflection.
    std::uint64_t estimate(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                           const EstimateRequest &request, EstimateWorkspace &workspace, double *mean,
                           double *stderr_out) const override;
    // The estimate without the entry boundary's own (deterministic) reflection: the light
    // that entered the stack. ScatteredPart exposes it as a model of its own.
    std::uint64_t estimate_scattered(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                                     const EstimateRequest &request, EstimateWorkspace &workspace,
                                     double *mean, double *stderr_out) const;
    // Reflectance of the top boundary's delta lobe toward the mirror direction.
    void delta_reflectance(const Vec3 &wi, const Query &q, double *out) const;
    // The top boundary: its reflection is the part of the model known exactly.
    const std::shared_ptr<const BSDF> &top() const { return boundaries_.front(); }
    const LayeredOptions &options() const { return options_; }
    // Walks of eval(), sample() and pdf() cut by max_depth since construction (estimate() reports
    // its own through EstimateRequest::capped). A cut walk is biased: 0 for a sound model.
    std::uint64_t capped_walks() const { return capped_.load(std::memory_order_relaxed); }

  private:
    // The walk's steps (core/src/layered/walk.h) and eval's connecting walk (eval_walk.h).
    friend class layered::Walk;
    friend class layered::EvalWalk;
    struct ExitDensity {   // pdf(): the walk's arrivals at `boundary` heading out
        Vec3 wo;
        int boundary;
        bool rough;        // the boundary transmits through a non-delta lobe
        double sum;        // of its densities of transmitting toward wo
    };
    double approximate_pdf(const Vec3 &wi, const Vec3 &wo, bool reflect, const Query &q) const;
    // sample()'s walk after the entry boundary transmitted (sample_walk.cpp).
    BSDFSample sample_walk(const Vec3 &wi, BSDFSample entry, const Query &q, PCG32 &rng, double *buf,
                           ExitDensity *density) const;
    std::uint64_t estimate_impl(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                                const EstimateRequest &request, bool include_direct,
                                EstimateWorkspace &workspace, double *mean, double *err) const;
    layered::WalkMemory bind_walk(EstimateWorkspace &workspace, std::size_t offset) const;
    std::size_t walk_doubles() const;
    // The light chain from wo through the boundaries on the exit side (chain.cpp); `tr` a
    // buffer of channels() doubles.
    void build_chain(const Vec3 &wo, layered::Side exit, const Query &q, PCG32 &rng, layered::Chain &ch,
                     double *tr) const;
    // The exact all-delta continuations of the chain (bounces inside the delta region).
    void solve_delta_region(layered::Side exit, const Query &q, layered::Chain &ch) const;
    void transmittance(int slab, double distance, double *tr) const;
    // Advances a flight of at most `room` depth in slab j along a direction of |z| = cz,
    // sampled by spectral MIS over the channels' extinctions (so absorbing slabs scatter
    // where light actually reaches, with weights bounded by the channel count):
    // returns the travelled distance along the ray if it ends in a scattering event
    // (throughput updated), or a negative number if it reaches the boundary. `tr` is a
    // buffer of channels() doubles.
    double fly(const Slab &S, double room, double cz, PCG32 &rng, double *beta, double *tr) const;
    // pfmc2's flight: distances drawn with the slab's smallest extinction (sigma_s plus the
    // smallest sigma_a), so every channel's weight is <= 1 (docs/estimators.md).
    double fly_min_extinction(std::size_t j, double room, double cz, PCG32 &rng, double *beta,
                              double *tmp) const;
    // beta[c] *= exp(-sigma_a[c] length): a flight through a slab that does not scatter.
    void absorb(const Slab &S, double length, double *beta, double *tmp) const;

    std::vector<std::shared_ptr<const BSDF>> boundaries_;
    std::vector<Slab> slabs_;
    std::vector<double> min_sigma_a_; // per slab: the smallest sigma_a over the channels
    std::vector<bool> min_extinction_; // per slab: pfmc2 flies it by fly_min_extinction
    int walks_per_chain_[2] = {1, 1};  // pfmc2, leaving through the top (0) or the bottom (1)
    LayeredOptions options_;
    Estimator estimator_;
    mutable std::atomic<std::uint64_t> capped_{0};
};

// "The model without its top interface's own reflection": the light that entered the
// stack, as a stochastic BSDF. The tabulator stores this part of a layered model and the
// table BSDF adds top() back exactly at lookup.
class ScatteredPart final : public BSDF, public StochasticEstimator {
  public:
    explicit ScatteredPart(std::shared_ptr<const LayeredBSDF> model);
    uint32_t lobes() const override { return model_->lobes() & ~kDelta; }
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const override {
        return model_->pdf(wi, wo, lobes, q);
    }
    // Not a sampler of its own (it is a part of a BSDF): returns no sample.
    BSDFSample sample(const Vec3 &, double, double, double, uint32_t, const Query &,
                      double *weight) const override {
        zero(weight);
        return {};
    }
    const StochasticEstimator *stochastic() const override { return this; }
    std::uint64_t estimate(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                           const EstimateRequest &request, EstimateWorkspace &workspace, double *mean,
                           double *stderr_out) const override {
        return model_->estimate_scattered(wi, wo, lobes, q, request, workspace, mean, stderr_out);
    }
    const LayeredBSDF &model() const { return *model_; }
    std::shared_ptr<const BSDF> with_film_lookup(double thickness_nm, FilmLookupStats &stats) const override;

  private:
    std::shared_ptr<const LayeredBSDF> model_;
};

} // namespace bsdflab
