// A Fresnel term given as a table: reflectance per channel on a uniform grid of |cos theta|
// in [0, 1], linearly interpolated; opaque (T = 0). For comparison models whose reflectance
// is known only as numbers (e.g. a renderer's own thin-film approximation, tabulated in
// Python), so the path tracer can render them beside the exact terms.
#pragma once

#include <vector>

#include "bsdflab/fresnel_terms.h"

namespace bsdflab {

class TabulatedTerm final : public FresnelTerm {
  public:
    // reflectance[i][c]: channel c at cos theta = i / (n - 1), n >= 2, values in [0, 1].
    explicit TabulatedTerm(std::vector<std::vector<double>> reflectance);
    void eval(double cos_i, const Query &q, double *R, double *T) const override;
    bool transmissive() const override { return false; }

  private:
    std::vector<double> table_;   // n x channels, row-major
    int rows_;
};

}  // namespace bsdflab
