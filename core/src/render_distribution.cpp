#include "bsdflab/render/distribution.h"
#include <algorithm>
#include <cmath>

namespace bsdflab {

Distribution1D::Distribution1D(const std::vector<double> &weights) {
    const std::size_t n = weights.size();
    cdf_.assign(n + 1, 0.0);
    prob_.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        double w = weights[i];
        cdf_[i + 1] = cdf_[i] + ((std::isfinite(w) && w > 0) ? w : 0.0);
    }
    total_ = cdf_[n];
    if (total_ <= 0.0) return;
    for (std::size_t i = 0; i < n; ++i) prob_[i] = (cdf_[i + 1] - cdf_[i]) / total_;
    for (std::size_t i = 1; i <= n; ++i) cdf_[i] /= total_;
    cdf_[n] = 1.0;
}

std::size_t Distribution1D::sample(double u, double &u_rest) const {
    // First bin whose upper CDF edge exceeds u; empty bins are never returned.
    auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), u);
    std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(it - cdf_.begin()) - 1, prob_.size() - 1);
    while (i > 0 && prob_[i] == 0.0) --i;
    double width = cdf_[i + 1] - cdf_[i];
    u_rest = width > 0 ? std::clamp((u - cdf_[i]) / width, 0.0, 0x1.fffffffffffffp-1) : 0.5;
    return i;
}

} // namespace bsdflab
