// A discrete distribution over N bins from non-negative weights, sampled by inverting its
// CDF: light selection (triangles by power) and environment-map rows/columns.
#pragma once
#include <cstddef>
#include <vector>

namespace bsdflab {

class Distribution1D {
public:
    Distribution1D() = default;
    // Non-finite or negative weights count as 0. All-zero weights give an empty distribution.
    explicit Distribution1D(const std::vector<double> &weights);

    bool empty() const { return total_ <= 0.0; }
    std::size_t size() const { return prob_.size(); }
    double total() const { return total_; }
    double prob(std::size_t i) const { return i < prob_.size() ? prob_[i] : 0.0; }

    // Picks bin i with probability prob(i); `u_rest` is u rescaled to [0, 1) within the bin,
    // so the caller can reuse it.
    std::size_t sample(double u, double &u_rest) const;

private:
    std::vector<double> cdf_, prob_;
    double total_ = 0.0;
};

} // namespace bsdflab
