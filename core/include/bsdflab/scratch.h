// Per-thread scratch buffers for per-channel intermediate values (the hot loops must not
// allocate, and channel counts are only known at run time), and per-channel arithmetic
// shared by the core (luminance weights, projections, means).
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

// Rec. 709 / sRGB luminance weights of linear RGB.
constexpr double kLuminanceRGB[3] = {0.2126, 0.7152, 0.0722};

// dst = P v for P (rows x n, row-major); P null copies v (rows = n).
inline void project_rows(const double *P, int rows, int n, const double *v, double *dst) {
    if (!P) {
        for (int c = 0; c < n; ++c) dst[c] = v[c];
        return;
    }
    for (int r = 0; r < rows; ++r) {
        double acc = 0;
        for (int c = 0; c < n; ++c) acc += P[r * n + c] * v[c];
        dst[r] = acc;
    }
}

inline double channel_mean(const double *v, int n) {
    double s = 0;
    for (int c = 0; c < n; ++c) s += v[c];
    return n > 0 ? s / n : 0.0;
}

} // namespace bsdflab
