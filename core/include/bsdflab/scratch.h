// Per-thread scratch buffers for per-channel intermediate values: the hot loops must not
// allocate, and channel counts are only known at run time.
#pragma once
#include <vector>

namespace bsdflab {

// Returns a buffer of at least `n` doubles, distinct for each `slot` (0..3) and thread.
inline double *scratch(int slot, int n) {
    thread_local std::vector<double> buffers[4];
    std::vector<double> &b = buffers[slot];
    if (static_cast<int>(b.size()) < n) b.resize(n);
    return b.data();
}

inline double channel_mean(const double *v, int n) {
    double s = 0;
    for (int c = 0; c < n; ++c) s += v[c];
    return n > 0 ? s / n : 0.0;
}

} // namespace bsdflab
