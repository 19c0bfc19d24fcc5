#include "bsdflab/render/distribution.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bsdflab {

Distribution1D::Distribution1D(const std::vector<double> &weights) {
    const std::size_t n = weights.size();
    if (n > UINT32_MAX) throw std::invalid_argument("distribution: too many bins");
    prob_.assign(n, 0.0);
    double largest = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double w = weights[i];
        prob_[i] = (std::isfinite(w) && w > 0) ? w : 0.0;
        largest = std::max(largest, prob_[i]);
    }
    if (!(largest > 0.0)) return;
    // Summed relative to the largest weight, so finite weights near DBL_MAX cannot overflow.
    double relative = 0.0;
    for (double &p : prob_) relative += (p /= largest);
    total_ = relative * largest; // may be inf for such weights; the probabilities stay exact
    for (double &p : prob_) p /= relative;

    // Vose: pair each under-full slot with an over-full bin that tops it up.
    keep_.assign(n, 1.0);
    alias_.resize(n);
    std::vector<double> scaled(n);
    std::vector<uint32_t> small, large;
    std::size_t heaviest = 0;
    for (std::size_t i = 0; i < n; ++i) {
        scaled[i] = prob_[i] * double(n);
        alias_[i] = uint32_t(i);
        (scaled[i] < 1.0 ? small : large).push_back(uint32_t(i));
        if (prob_[i] > prob_[heaviest]) heaviest = i;
    }
    while (!small.empty() && !large.empty()) {
        const uint32_t s = small.back(), l = large.back();
        small.pop_back();
        keep_[s] = scaled[s];
        alias_[s] = l;
        scaled[l] -= 1.0 - scaled[s];
        if (scaled[l] < 1.0) {
            large.pop_back();
            small.push_back(l);
        }
    }
    // Left-overs are full to rounding error; a zero-weight one must still never be kept.
    for (uint32_t i : small) {
        keep_[i] = prob_[i] > 0 ? 1.0 : 0.0;
        if (prob_[i] == 0) alias_[i] = uint32_t(heaviest);
    }
    for (uint32_t i : large) keep_[i] = 1.0;
}

std::size_t Distribution1D::sample(double u, double &u_rest) const {
    const std::size_t n = prob_.size();
    u_rest = 0.5;
    if (n == 0 || empty()) return 0;
    const double x = (u > 0 ? (u < 1 ? u : 1.0) : 0.0) * double(n); // NaN -> 0
    const std::size_t k = std::min(std::size_t(x), n - 1);
    const double f = std::clamp(x - double(k), 0.0, 0x1.fffffffffffffp-1);
    const double keep = keep_[k];
    if (f < keep) {
        u_rest = f / keep;
        return k;
    }
    u_rest = std::min((f - keep) / (1.0 - keep), 0x1.fffffffffffffp-1);
    return alias_[k];
}

} // namespace bsdflab
