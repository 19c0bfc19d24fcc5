#include "bsdflab/tabulation.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/layered.h"
#include "bsdflab/parallel.h"
#include "bsdflab/rng.h"

namespace bsdflab {


TabulationJob::TabulationJob(std::shared_ptr<const BSDF> model, TableGrid grid, std::vector<double> P,
                             int rows, TabulationSettings settings)
    : model_(std::move(model)), grid_(std::move(grid)), P_(std::move(P)), rows_(rows),
      settings_(settings) {
    if (!model_) throw std::invalid_argument("no model to tabulate");
    if (rows_ < 2 || P_.size() != std::size_t(rows_) * model_->channels())
        throw std::invalid_argument("P must have (output channels + 1) x model channels entries");
    if (grid_.thickness.empty()) grid_.thickness = {-1.0};
    value.assign(grid_.cells() * out_channels(), 0.0);
    error.assign(grid_.cells() * out_channels(), 0.0);
    samples.assign(grid_.cells(), 0);
    lum_value.assign(grid_.cells(), 0.0);
    lum_error.assign(grid_.cells(), 0.0);
}

// Mean and standard error of f (no cosine) for one cell, all rows of P (luminance last).
void TabulationJob::estimate(std::size_t cell, int n, uint64_t seed, double *mean, double *err) const {
    Vec3 wi, wo;
    int lobe, t;
    grid_.cell_directions(cell, wi, wo, lobe, t);
    Query q;
    q.film_thickness_nm = grid_.thickness[t];
    const double inv_cos = 1.0 / std::abs(wo.z);
    if (auto *layered = dynamic_cast<const LayeredBSDF *>(model_.get())) {
        layered->eval_projected(wi, wo, kAll, q, n, seed, P_.data(), rows_, !settings_.split_direct,
                                mean, err);
    } else { // deterministic model: one evaluation, no error
        std::vector<double> v(model_->channels());
        model_->eval(wi, wo, kAll, q, v.data());
        for (int r = 0; r < rows_; ++r) {
            double acc = 0;
            for (int c = 0; c < model_->channels(); ++c) acc += P_[r * model_->channels() + c] * v[c];
            mean[r] = acc;
            err[r] = 0.0;
        }
    }
    for (int r = 0; r < rows_; ++r) { mean[r] *= inv_cos; err[r] *= inv_cos; }
}

void TabulationJob::run() {
    const std::size_t cells = grid_.cells();
    const int C = out_channels();
    const bool stochastic = dynamic_cast<const LayeredBSDF *>(model_.get()) != nullptr;
    std::vector<double> &lum = lum_value, &lum_err = lum_error;

    auto cell_seed = [&](std::size_t cell, uint64_t pass) {
        return mix64(settings_.seed ^ mix64(cell * 8 + pass));
    };
    // Pass 1: every cell at the base effort.
    parallel_for_each(cells, [&](std::size_t cell) {
        std::vector<double> m(rows_), er(rows_);
        if (!cancelled_) {
            int n = stochastic ? settings_.min_samples : 1;
            estimate(cell, n, cell_seed(cell, 0), m.data(), er.data());
            std::copy(m.begin(), m.begin() + C, value.begin() + cell * C);
            std::copy(er.begin(), er.begin() + C, error.begin() + cell * C);
            lum[cell] = m[C];
            lum_err[cell] = er[C];
            samples[cell] = n;
            ++done_;
        }
    });
    if (cancelled_) return;
    if (!stochastic) { done_ = total(); return; }

    // Error floor per lobe: a fraction of the lobe's mean luminance.
    std::vector<double> scale(grid_.n_lobes, 0.0);
    std::size_t per_lobe = cells / grid_.n_lobes;
    for (std::size_t cell = 0; cell < cells; ++cell) scale[cell / per_lobe] += std::abs(lum[cell]) / per_lobe;

    // Refinement passes: each cell still above its target gets the walks its estimated
    // variance asks for, pooled with the earlier ones. The variance estimate is itself
    // noisy, so a couple of passes bring stragglers in.
    for (int pass = 1; pass <= kRefinePasses && !cancelled_; ++pass)
    parallel_for_each(cells, [&](std::size_t cell) {
        std::vector<double> m(rows_), er(rows_);
        if (!cancelled_) {
            double target = settings_.rel_error *
                            std::max(std::abs(lum[cell]), settings_.floor * scale[cell / per_lobe]);
            int n1 = samples[cell];
            if (target > 0 && lum_err[cell] > target) {
                double want = n1 * (lum_err[cell] / target) * (lum_err[cell] / target);
                int n_total = static_cast<int>(std::min<double>(settings_.max_samples, std::ceil(want * 1.1)));
                int n2 = n_total - n1;
                if (n2 > 0) {
                    estimate(cell, n2, cell_seed(cell, pass), m.data(), er.data());
                    // Chan et al.: combine two (mean, M2) summaries; M2 = se^2 n (n - 1).
                    for (int c = 0; c <= C; ++c) { // c == C: the luminance row
                        double &mean1 = c < C ? value[cell * C + c] : lum[cell];
                        double &se1 = c < C ? error[cell * C + c] : lum_err[cell];
                        double M2a = se1 * se1 * n1 * (n1 - 1.0), M2b = er[c] * er[c] * n2 * (n2 - 1.0);
                        double d = m[c] - mean1, n = double(n1) + n2;
                        double M2 = M2a + M2b + d * d * double(n1) * n2 / n;
                        mean1 += d * n2 / n;
                        se1 = std::sqrt(M2 / (n * (n - 1.0)));
                    }
                    samples[cell] = n1 + n2;
                }
            }
            ++done_;
        }
    });
}

} // namespace bsdflab
