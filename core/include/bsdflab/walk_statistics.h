// The standard error of a per-pair estimate, with walks spent on the error alone.
//
// A heavy-tailed walk (the snake's skewness 3-6, excess kurtosis 29-86) makes the sample
// spread of n walks small exactly when their mean is small: a pair whose walks missed the
// rare large values reads low in value and in error at once, so z = (value - f) / error
// has a long tail (docs/coverage.md: 46x the normal share beyond 4 sigma at 256 walks).
// estimate_pooled() runs the estimator a second time, `error_walks` walks from a seed
// stream independent of the value's (error_seed), and states the value's error from the
// per-walk spread pooled over both runs (pooled_group_error below).
// The value is the first run's, bit for bit; only the error reads the extra walks.
#pragma once
#include <cstdint>
#include "estimate.h"

namespace bsdflab {

// The seed of the error's walks: a fixed, well-mixed function of the value's seed, so that
// the error walks of seed s are not the value walks of a nearby seed s + k.
std::uint64_t error_seed(std::uint64_t seed);

// The standard error of a mean with grouping `value` and own error `value_error`, from the
// per-walk variance pooled with an independent run's (var = se^2 effective_walks per run,
// weighted by its groups - 1 degrees of freedom; estimate.h WalkGroups). Per walk, not
// per walk count: a short last group weighs more in its mean than its walks (9 walks as
// 4, 4, 1 have the variance of 6 equal ones), and se^2 n would state that mean's error
// 18 % too small. A value of one group (1 walk) takes the extra run's variance alone; an
// extra run of fewer than 2 groups or a non-finite error leaves value_error.
double pooled_group_error(double value_error, const WalkGroups &value, double extra_error,
                          const WalkGroups &extra);

// StochasticEstimator::estimate at `request`, then, when request.error_walks > 0, the
// pooled error described above (rows: the request's output rows). Returns the non-finite
// walks of both runs; walks the depth cap cut in either run go to request.capped as usual.
std::uint64_t estimate_pooled(const StochasticEstimator &estimator, const Vec3 &wi, const Vec3 &wo,
                              uint32_t lobes, const Query &q, const EstimateRequest &request, int rows,
                              EstimateWorkspace &workspace, double *mean, double *stderr_out);

} // namespace bsdflab
