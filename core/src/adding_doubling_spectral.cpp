// Spectral interpolation for the adding-doubling solve (adding_doubling_parts.h): what lies
// below a rough top, solved at every stride-th channel, cubic in wavelength between.
#include <algorithm>
#include "adding_doubling_parts.h"
#include "bsdflab/parallel.h"

namespace bsdflab::ad {

namespace {

// sum_i w_i a_i over operators of one grid (an empty part counts as zero).
Op combine(const std::vector<const Op *> &ops, const std::vector<double> &w) {
    Op r;
    for (std::size_t i = 0; i < ops.size(); ++i) {
        auto acc = [&](std::vector<double> &dst, const std::vector<double> &src) {
            if (src.empty()) return;
            if (dst.empty()) dst.assign(src.size(), 0.0);
            for (std::size_t p = 0; p < src.size(); ++p) dst[p] += w[i] * src[p];
        };
        acc(r.D, ops[i]->D);
        acc(r.K, ops[i]->K);
    }
    return r;
}

} // namespace

std::vector<int> solved_channels(int C, int stride) {
    std::vector<int> out;
    for (int c = 0; c < C; c += std::max(1, stride)) out.push_back(c);
    if (out.back() != C - 1) out.push_back(C - 1);
    if (stride <= 1 || out.size() < 4) {
        out.resize(C);
        for (int c = 0; c < C; ++c) out[c] = c;
    }
    return out;
}

void interpolate_channels(std::vector<Op> &R, const std::vector<double> &wavelengths,
                          const std::vector<int> &solved, int M) {
    const int C = static_cast<int>(wavelengths.size());
    const std::size_t S = solved.size();
    std::vector<char> is_solved(C, 0);
    for (int c : solved) is_solved[c] = 1;
    parallel_for_each(static_cast<std::size_t>(C) * M, [&](std::size_t task) {
        const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
        if (is_solved[c]) return;
        std::size_t hi = std::upper_bound(solved.begin(), solved.end(), c) - solved.begin();
        std::size_t j0 = std::min(S - 4, hi < 2 ? 0 : hi - 2);
        std::vector<const Op *> ops;
        std::vector<double> w;
        for (std::size_t i = j0; i < j0 + 4; ++i) {
            double l = 1.0, x = wavelengths[c];
            for (std::size_t j = j0; j < j0 + 4; ++j)
                if (j != i)
                    l *= (x - wavelengths[solved[j]]) / (wavelengths[solved[i]] - wavelengths[solved[j]]);
            ops.push_back(&R[static_cast<std::size_t>(solved[i]) * M + m]);
            w.push_back(l);
        }
        R[task] = combine(ops, w);
    });
}

} // namespace bsdflab::ad
