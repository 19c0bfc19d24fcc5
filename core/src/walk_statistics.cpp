// Pooled per-pair standard error from extra, independent walks (walk_statistics.h).
#include "bsdflab/walk_statistics.h"
#include <algorithm>
#include <cmath>
#include "bsdflab/rng.h"

namespace bsdflab {

std::uint64_t error_seed(std::uint64_t seed) {
    // Both steps are one-to-one; mix64 scatters nearby seeds far apart.
    return mix64(seed ^ 0xD1B54A32D192ED03ull);
}

double pooled_group_error(double value_error, const WalkGroups &value, double extra_error,
                          const WalkGroups &extra) {
    if (extra.groups < 2 || !std::isfinite(extra_error) || !(value.effective_walks > 0) ||
        !(extra.effective_walks > 0))
        return value_error;
    const double dv = std::max(value.groups - 1, 0), de = extra.groups - 1;
    const double var_v = value_error * value_error * value.effective_walks; // per walk
    const double var_e = extra_error * extra_error * extra.effective_walks;
    return std::sqrt((dv * var_v + de * var_e) / (dv + de) / value.effective_walks);
}

std::uint64_t estimate_pooled(const StochasticEstimator &estimator, const Vec3 &wi, const Vec3 &wo,
                              uint32_t lobes, const Query &q, const EstimateRequest &request, int rows,
                              EstimateWorkspace &workspace, double *mean, double *stderr_out) {
    if (request.error_walks < 1 || rows < 1)
        return estimator.estimate(wi, wo, lobes, q, request, workspace, mean, stderr_out);
    // Defaults for an estimate that returns before walking (its mean and error are 0).
    WalkGroups value_groups{request.samples, double(request.samples)};
    WalkGroups extra_groups{request.error_walks, double(request.error_walks)};
    EstimateRequest first = request;
    first.grouping = &value_groups;
    std::uint64_t bad = estimator.estimate(wi, wo, lobes, q, first, workspace, mean, stderr_out);
    EstimateRequest extra = request;
    extra.samples = request.error_walks;
    extra.seed = error_seed(request.seed);
    extra.error_walks = 0;
    extra.grouping = &extra_groups;
    ThreadWorkspace scratch; // the estimator owns `workspace` while it runs
    double *extra_mean = scratch.get().doubles(2 * static_cast<std::size_t>(rows));
    double *extra_error = extra_mean + rows;
    bad += estimator.estimate(wi, wo, lobes, q, extra, workspace, extra_mean, extra_error);
    for (int r = 0; r < rows; ++r)
        stderr_out[r] = pooled_group_error(stderr_out[r], value_groups, extra_error[r], extra_groups);
    return bad;
}

} // namespace bsdflab
