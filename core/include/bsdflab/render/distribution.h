// A discrete distribution over N bins from non-negative weights: light selection
// (triangles by power) and environment-map rows/columns. Sampled by Walker's alias
// method (Vose's construction): O(1) and one random access per sample, where inverting the
// CDF costs a binary search (the environment's two searches were ~6 % of a snake render).
#pragma once
#include <cstddef>
#include <cstdint>
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

    // Picks bin i with probability prob(i) (never a zero-weight bin); `u_rest` is uniform
    // in [0, 1) given the bin and independent of which bin, so the caller can reuse it.
    std::size_t sample(double u, double &u_rest) const;

  private:
    // Slot k keeps its own bin with probability keep_[k], else gives alias_[k].
    std::vector<double> prob_, keep_;
    std::vector<uint32_t> alias_;
    double total_ = 0.0;
};

} // namespace bsdflab
