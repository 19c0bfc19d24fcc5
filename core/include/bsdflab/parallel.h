// Minimal parallel loop over [0, n) in contiguous chunks on std::threads.
// Used by the vectorised bindings after the GIL is released. Small n runs inline.
#pragma once
#include <cstddef>
#include <functional>

namespace bsdflab {

// Number of worker threads: BSDFLAB_THREADS if set (>= 1), else all hardware threads.
unsigned worker_count();

// Calls body(begin, end) on disjoint chunks covering [0, n); runs inline if n < grain.
void parallel_for(std::size_t n, std::size_t grain,
                  const std::function<void(std::size_t, std::size_t)> &body);

} // namespace bsdflab
