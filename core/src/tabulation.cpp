#include "bsdflab/tabulation.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/estimate.h"
#include "bsdflab/film_lookup.h"
#include "bsdflab/parallel.h"
#include "bsdflab/rng.h"
#include "bsdflab/scratch.h"

namespace bsdflab {

Tabulator::Tabulator(std::shared_ptr<const BSDF> model, TableGrid grid, std::vector<double> P, int rows,
                     TabulationSettings settings)
    : model_(std::move(model)), estimator_(model_ ? model_->stochastic() : nullptr), grid_(std::move(grid)),
      P_(std::move(P)), rows_(rows), settings_(settings) {
    if (!model_) throw std::invalid_argument("no model to tabulate");
    if (rows_ < 2 || P_.size() != std::size_t(rows_) * model_->channels())
        throw std::invalid_argument("P must have (output channels + 1) x model channels entries");
    if (settings_.min_samples < 1 || settings_.max_samples < settings_.min_samples)
        throw std::invalid_argument("need 1 <= min_samples <= max_samples");
    if (grid_.thickness.empty()) grid_.thickness = {-1.0};
    std::size_t lookup_bytes = 0;
    for (double t : grid_.thickness) {
        // Only walks gain from the lookup: a deterministic model is evaluated once per cell.
        // Nodes past the memory budget keep the exact film (a decision from sizes alone, so
        // every block and thread count makes the same one).
        FilmLookupStats stats;
        const bool want = estimator_ && settings_.film_lookup && lookup_bytes < kFilmLookupBudgetBytes;
        auto fast = want ? model_->with_film_lookup(t, stats) : nullptr;
        if (fast && lookup_bytes + stats.bytes > kFilmLookupBudgetBytes) fast = nullptr;
        if (fast) {
            lookup_bytes += stats.bytes;
            film_lookup_error_ = std::max(film_lookup_error_, stats.max_error);
        }
        node_models_.push_back(fast ? fast : model_);
        node_estimators_.push_back(node_models_.back()->stochastic());
    }
}

std::shared_ptr<Tabulator> Tabulator::with_settings(const TabulationSettings &settings) const {
    if (settings.film_lookup != settings_.film_lookup)
        throw std::invalid_argument("with_settings cannot change film_lookup (the lookups are shared)");
    if (settings.min_samples < 1 || settings.max_samples < settings.min_samples)
        throw std::invalid_argument("need 1 <= min_samples <= max_samples");
    auto copy = std::make_shared<Tabulator>(*this);
    copy->settings_ = settings;
    return copy;
}

uint64_t Tabulator::cell_seed(std::size_t cell, uint64_t stage) const {
    return mix64(settings_.seed ^ mix64(cell * 8 + stage));
}

std::uint64_t Tabulator::estimate(std::size_t cell, int n, uint64_t seed, double *mean, double *err,
                                  std::uint64_t *capped) const {
    Vec3 wi, wo;
    int lobe, t;
    grid_.cell_directions(cell, wi, wo, lobe, t);
    Query q;
    q.film_thickness_nm = grid_.thickness[t];
    const double inv_cos = 1.0 / std::abs(wo.z);
    std::uint64_t nonfinite = 0;
    if (estimator_) {
        ThreadWorkspace lease;
        EstimateRequest req{n, seed, P_.data(), rows_, capped};
        nonfinite = node_estimators_[t]->estimate(wi, wo, kAll, q, req, lease.get(), mean, err);
    } else { // deterministic model: one evaluation, no error
        ThreadWorkspace lease;
        double *v = lease.get().doubles(model_->channels());
        model_->eval(wi, wo, kAll, q, v);
        project_rows(P_.data(), rows_, model_->channels(), v, mean);
        for (int r = 0; r < rows_; ++r) err[r] = 0.0;
    }
    for (int r = 0; r < rows_; ++r) {
        mean[r] *= inv_cos;
        err[r] *= inv_cos;
    }
    return nonfinite;
}

double pooled_error(double fresh, int n, double pilot, int n0) {
    if (n < 2 || n0 < 2 || !std::isfinite(pilot)) return fresh;
    const double var0 = double(n0) * pilot * pilot, var1 = double(n) * fresh * fresh; // per walk
    const double pooled = ((n0 - 1) * var0 + (n - 1) * var1) / double(n0 + n - 2);
    return std::sqrt(pooled / n);
}

namespace {
void check_cells(const std::vector<std::size_t> &cells, std::size_t count) {
    for (std::size_t c : cells)
        if (c >= count) throw std::invalid_argument("cell index out of range");
}
} // namespace

PilotCells Tabulator::pilot(const std::vector<std::size_t> &cells, const TabulationControl &ctl) const {
    check_cells(cells, grid_.cells());
    PilotCells out;
    out.lum.assign(cells.size(), 0.0);
    out.lum_error.assign(cells.size(), 0.0);
    out.error.assign(cells.size() * out_channels(), 0.0);
    std::atomic<std::uint64_t> nonfinite{0}, capped{0};
    const int n = estimator_ ? settings_.min_samples : 1;
    parallel_for_each(cells.size(), [&](std::size_t i) {
        if (ctl.stop()) return;
        std::vector<double> m(rows_), e(rows_);
        std::uint64_t cut = 0;
        nonfinite += estimate(cells[i], n, cell_seed(cells[i], 0), m.data(), e.data(), &cut);
        capped += cut;
        out.lum[i] = m[rows_ - 1];
        out.lum_error[i] = e[rows_ - 1];
        std::copy(e.begin(), e.begin() + (rows_ - 1), out.error.begin() + i * (rows_ - 1));
        ctl.tick();
    });
    out.nonfinite = nonfinite;
    out.capped = capped;
    return out;
}

std::vector<double> Tabulator::floor_scale(const std::vector<double> &lum) const {
    const std::size_t cells = grid_.cells(), per_lobe = cells / grid_.n_lobes;
    if (lum.size() != cells) throw std::invalid_argument("floor_scale needs every cell's pilot luminance");
    std::vector<double> scale(grid_.n_lobes, 0.0);
    for (std::size_t cell = 0; cell < cells; ++cell) scale[cell / per_lobe] += std::abs(lum[cell]);
    for (double &s : scale) s /= double(per_lobe);
    return scale;
}

int Tabulator::effort(std::size_t cell, double pilot_lum, double pilot_error,
                      const std::vector<double> &scale) const {
    if (!estimator_) return 1;
    const std::size_t per_lobe = grid_.cells() / grid_.n_lobes;
    const double target =
        settings_.rel_error * std::max(std::abs(pilot_lum), settings_.floor * scale.at(cell / per_lobe));
    const int n0 = settings_.min_samples;
    if (!(target > 0) || !(pilot_error > target)) return n0;
    // 10 % above the estimated need: the pilot's error estimate is itself noisy.
    const double ratio = pilot_error / target;
    const double want = std::ceil(1.1 * n0 * ratio * ratio);
    return static_cast<int>(std::clamp<double>(want, n0, settings_.max_samples));
}

FinishedCells Tabulator::finish(const std::vector<std::size_t> &cells, const std::vector<double> &pilot_lum,
                                const std::vector<double> &pilot_error, const std::vector<double> &scale,
                                const TabulationControl &ctl,
                                const std::vector<double> &pilot_channel_error) const {
    check_cells(cells, grid_.cells());
    if (pilot_lum.size() != cells.size() || pilot_error.size() != cells.size())
        throw std::invalid_argument("pilot luminance and error must have one entry per cell");
    if (!pilot_channel_error.empty() && pilot_channel_error.size() != cells.size() * out_channels())
        throw std::invalid_argument("pilot channel errors must have out_channels entries per cell");
    if (scale.size() != std::size_t(grid_.n_lobes))
        throw std::invalid_argument("floor scale must have one entry per lobe");
    const int C = out_channels();
    FinishedCells out;
    out.value.assign(cells.size() * C, 0.0);
    out.error.assign(cells.size() * C, 0.0);
    out.lum.assign(cells.size(), 0.0);
    out.lum_error.assign(cells.size(), 0.0);
    out.samples.assign(cells.size(), 0);
    std::atomic<std::uint64_t> nonfinite{0}, capped{0};
    // Largest effort first, so that no long cell starts last and leaves the other cores
    // idle (each result goes to its own slot: the order changes no bit).
    std::vector<int> efforts(cells.size());
    std::vector<std::size_t> order(cells.size());
    for (std::size_t i = 0; i < cells.size(); ++i) {
        efforts[i] = effort(cells[i], pilot_lum[i], pilot_error[i], scale);
        order[i] = i;
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return efforts[a] > efforts[b]; });
    parallel_for_each(cells.size(), [&](std::size_t k) {
        if (ctl.stop()) return;
        const std::size_t i = order[k], cell = cells[i];
        const int n = efforts[i];
        std::vector<double> m(rows_), e(rows_);
        std::uint64_t cut = 0;
        nonfinite += estimate(cell, n, cell_seed(cell, 1), m.data(), e.data(), &cut);
        capped += cut;
        if (estimator_) {
            // Each channel pools with its own pilot error; without them (a caller of the
            // version-6 interface) every channel takes the luminance's pooled/fresh ratio
            // (one walk's channels rise and fall together) or, where the fresh luminance had
            // no spread at all, the pooled luminance error.
            const int n0 = settings_.min_samples;
            const double lum_pooled = pooled_error(e[C], n, pilot_error[i], n0);
            for (int r = 0; r < C; ++r) {
                if (!pilot_channel_error.empty())
                    e[r] = pooled_error(e[r], n, pilot_channel_error[i * C + r], n0);
                else e[r] = e[C] > 0 ? e[r] * (lum_pooled / e[C]) : std::max(e[r], lum_pooled);
            }
            e[C] = lum_pooled;
        }
        std::copy(m.begin(), m.begin() + C, out.value.begin() + i * C);
        std::copy(e.begin(), e.begin() + C, out.error.begin() + i * C);
        out.lum[i] = m[C];
        out.lum_error[i] = e[C];
        out.samples[i] = n;
        ctl.tick();
    });
    out.nonfinite = nonfinite;
    out.capped = capped;
    return out;
}

TabulationStageJob::TabulationStageJob(std::shared_ptr<const Tabulator> tabulator, Stage stage,
                                       std::vector<std::size_t> cells, std::vector<double> pilot_lum,
                                       std::vector<double> pilot_error, std::vector<double> scale,
                                       std::vector<double> pilot_channel_error)
    : tabulator_(std::move(tabulator)), stage_(stage), cells_(std::move(cells)),
      pilot_lum_(std::move(pilot_lum)), pilot_error_(std::move(pilot_error)), scale_(std::move(scale)),
      pilot_channel_error_(std::move(pilot_channel_error)) {
    if (!tabulator_) throw std::invalid_argument("no tabulator");
}

void TabulationStageJob::run() {
    TabulationControl ctl{&done_, &cancelled_};
    if (stage_ == kPilot) pilot = tabulator_->pilot(cells_, ctl);
    else finished = tabulator_->finish(cells_, pilot_lum_, pilot_error_, scale_, ctl, pilot_channel_error_);
}

} // namespace bsdflab
