// Stochastic models: BSDFs whose eval() is a Monte Carlo estimate (the PFMC layered BSDF).
// eval() answers with the model's own effort and seed; callers that need an explicit
// effort, seed, standard error or a projection of the channels (the tabulator, the Python
// bindings) use this small interface, reached through BSDF::stochastic() -- no cast to a
// concrete model.
//
// Scratch memory is explicit: every estimate takes an EstimateWorkspace owned by the
// caller (one per thread), so an estimate allocates nothing once its workspace has grown,
// and two estimates never share buffers behind each other's back. Entry points without a
// caller-owned workspace (BSDF::eval) lease one from a per-thread stack (ThreadWorkspace),
// so a stochastic model nested inside another one takes the next level instead of
// clobbering its caller's buffers.
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>
#include "bsdf.h"

namespace bsdflab {

// Bumped whenever the numbers an estimator produces for a given (model, directions, seed)
// change (a fix, a different order of random draws). Cached tables key on it.
// 4: the tabulator's walks read thin films from a per-thickness lookup (film_lookup.h).
// 5: layered walks end by roulette alone (the depth cap, now 2^16 events by default, is a
//    counted safety net); nee=false keeps the connections no other strategy replaces.
// 6: the layered default is "pfmc2" (issue 21); thin films of non-dispersive indices share
//    their angular part over the channels (closed form for one lossless film), exp and cos
//    over channels come from libmvec: values change in the last bits, "pfmc" is still
//    version 5's estimator (its golden values hold to 1e-9).
// 7: a table cell's standard error pools the pilot's walk spread with the fresh walks'
//    (tabulation.h pooled_error); values, sample counts and Layered.eval are unchanged.
// 8: a per-query film thickness is the top film's alone (boundary_query, bsdf.h); the
//    other boundaries keep their own films. Stacks with a film below the top change
//    (walks, tables, delta lobes); every other stack draws the same numbers.
constexpr int kEstimatorVersion = 8;

// Growable scratch memory of one thread's estimates.
class EstimateWorkspace {
  public:
    // At least n doubles; valid until the next call to doubles() on this workspace.
    double *doubles(std::size_t n) {
        if (buffer_.size() < n) buffer_.resize(n);
        return buffer_.data();
    }

  private:
    std::vector<double> buffer_;
};

// A workspace leased from this thread's stack for the lifetime of the object.
class ThreadWorkspace {
  public:
    ThreadWorkspace() : workspace_(acquire()) {}
    ~ThreadWorkspace() { --depth(); }
    ThreadWorkspace(const ThreadWorkspace &) = delete;
    ThreadWorkspace &operator=(const ThreadWorkspace &) = delete;
    EstimateWorkspace &get() { return *workspace_; }

  private:
    static int &depth() {
        thread_local int d = 0;
        return d;
    }
    static EstimateWorkspace *acquire() {
        thread_local std::deque<EstimateWorkspace> stack; // deque: references stay valid
        const std::size_t level = static_cast<std::size_t>(depth()++);
        if (level >= stack.size()) stack.emplace_back();
        return &stack[level];
    }
    EstimateWorkspace *workspace_;
};

// How one estimate grouped its walks, for statistics across runs (walk_statistics.h): the
// mean is over `groups` group means, so its variance is the per-walk variance over
// `effective_walks` = groups^2 / sum_i(1 / walks in group i), which is the walk count
// only when the groups are equal (pfmc2's last group may be short: 9 walks in groups of
// 4, 4, 1 give the lone walk a third of the weight, effective_walks 6).
struct WalkGroups {
    int groups = 0;
    double effective_walks = 0.0;
};

// What one estimate is asked for: `samples` independent walks seeded from (seed, wi, wo),
// the per-walk values projected by P (rows x channels, row-major) before the statistics
// so that errors of derived quantities (RGB, luminance) are exact. P null: the channels.
struct EstimateRequest {
    int samples = 1;
    uint64_t seed = 0;
    const double *P = nullptr;
    int rows = 0;
    // Optional out: walks cut by the model's depth cap are added here (a cut walk is a
    // truncated, biased sample; roulette ends walks long before the cap in sound models).
    std::uint64_t *capped = nullptr;
    // Extra walks for the standard error alone (walk_statistics.h estimate_pooled reads it;
    // StochasticEstimator::estimate itself ignores it). 0: the error of the value's walks.
    int error_walks = 0;
    // Optional out: the grouping of this estimate's walks (left as is where it returns
    // before walking, with a zero mean and error).
    WalkGroups *grouping = nullptr;
    int out_rows(int channels) const { return P ? rows : channels; }
};

class StochasticEstimator {
  public:
    virtual ~StochasticEstimator() = default;
    // Mean and standard error (per output row) of f |cos theta_o| at (wi, wo). Returns the
    // number of walks whose contribution was not finite: those walks count as zero in the
    // mean and are reported, never hidden (a correct model returns 0).
    virtual std::uint64_t estimate(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                                   const EstimateRequest &request, EstimateWorkspace &workspace, double *mean,
                                   double *stderr_out) const = 0;
};

} // namespace bsdflab
