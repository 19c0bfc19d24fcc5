// The standard error of a per-pair estimate, with walks spent on the error alone.
//
// A heavy-tailed walk (the snake's skewness 3-6, excess kurtosis 29-86) makes the sample
// spread of n walks small exactly when their mean is small: a pair whose walks missed the
// rare large values reads low in value and in error at once, so z = (value - f) / error
// has a long tail (docs/coverage.md: 46x the normal share beyond 4 sigma at 256 walks).
// estimate_pooled() runs the estimator a second time, `error_walks` walks from a seed
// stream independent of the value's (error_seed), and states the value's error from the
// per-walk spread pooled over both runs (tabulation.h pooled_error, var = se^2 n per run).
// The value is the first run's, bit for bit; only the error reads the extra walks.
#pragma once
#include <cstdint>
#include "estimate.h"

namespace bsdflab {

// The seed of the error's walks: a fixed, well-mixed function of the value's seed, so that
// the error walks of seed s are not the value walks of a nearby seed s + k.
std::uint64_t error_seed(std::uint64_t seed);

// StochasticEstimator::estimate at `request`, then, when request.error_walks > 0, the
// pooled error described above (rows: the request's output rows). Returns the non-finite
// walks of both runs; walks the depth cap cut in either run go to request.capped as usual.
std::uint64_t estimate_pooled(const StochasticEstimator &estimator, const Vec3 &wi, const Vec3 &wo,
                              uint32_t lobes, const Query &q, const EstimateRequest &request, int rows,
                              EstimateWorkspace &workspace, double *mean, double *stderr_out);

} // namespace bsdflab
