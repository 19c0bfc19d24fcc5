// Pooled per-pair standard error from extra, independent walks (walk_statistics.h).
#include "bsdflab/walk_statistics.h"
#include "bsdflab/rng.h"
#include "bsdflab/tabulation.h"

namespace bsdflab {

std::uint64_t error_seed(std::uint64_t seed) {
    // Both steps are one-to-one; mix64 scatters nearby seeds far apart.
    return mix64(seed ^ 0xD1B54A32D192ED03ull);
}

std::uint64_t estimate_pooled(const StochasticEstimator &estimator, const Vec3 &wi, const Vec3 &wo,
                              uint32_t lobes, const Query &q, const EstimateRequest &request, int rows,
                              EstimateWorkspace &workspace, double *mean, double *stderr_out) {
    std::uint64_t bad = estimator.estimate(wi, wo, lobes, q, request, workspace, mean, stderr_out);
    if (request.error_walks < 1 || rows < 1) return bad;
    EstimateRequest extra = request;
    extra.samples = request.error_walks;
    extra.seed = error_seed(request.seed);
    extra.error_walks = 0;
    ThreadWorkspace scratch; // the estimator owns `workspace` while it runs
    double *extra_mean = scratch.get().doubles(2 * static_cast<std::size_t>(rows));
    double *extra_error = extra_mean + rows;
    bad += estimator.estimate(wi, wo, lobes, q, extra, workspace, extra_mean, extra_error);
    for (int r = 0; r < rows; ++r)
        stderr_out[r] = pooled_error(stderr_out[r], request.samples, extra_error[r], extra.samples);
    return bad;
}

} // namespace bsdflab
