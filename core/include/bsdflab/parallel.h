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

// Calls body(i) for every i in [0, n), handing out indices one at a time to whichever
// thread is free: for loops whose iterations vary a lot in cost (adaptive estimates).
void parallel_for_each(std::size_t n, const std::function<void(std::size_t)> &body);

} // namespace bsdflab
