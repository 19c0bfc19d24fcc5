#include "bsdflab/tabulated_term.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bsdflab {

namespace {
int channels_of(const std::vector<std::vector<double>> &r) {
    if (r.size() < 2 || r[0].empty())
        throw std::invalid_argument("a tabulated term needs at least 2 rows of at least 1 channel");
    return static_cast<int>(r[0].size());
}
}  // namespace

TabulatedTerm::TabulatedTerm(std::vector<std::vector<double>> reflectance)
    : FresnelTerm(channels_of(reflectance), 0.0), rows_(static_cast<int>(reflectance.size())) {
    table_.reserve(reflectance.size() * channels_);
    for (const auto &row : reflectance) {
        if (static_cast<int>(row.size()) != channels_)
            throw std::invalid_argument("every row of a tabulated term must have the same channels");
        for (double v : row) {
            if (!(v >= 0.0 && v <= 1.0))
                throw std::invalid_argument("tabulated reflectance must be in [0, 1]");
            table_.push_back(v);
        }
    }
}

void TabulatedTerm::eval(double cos_i, const Query &, double *R, double *T) const {
    double c = std::abs(cos_i);
    c = std::isfinite(c) ? std::min(c, 1.0) : 0.0;   // degenerate directions: the grazing row
    double x = c * (rows_ - 1);
    int i = std::min(static_cast<int>(x), rows_ - 2);
    double f = x - i;
    const double *a = &table_[static_cast<size_t>(i) * channels_];
    const double *b = a + channels_;
    for (int k = 0; k < channels_; ++k) {
        R[k] = a[k] + f * (b[k] - a[k]);
        T[k] = 0.0;
    }
}

}  // namespace bsdflab
