// Tabulation of an isotropic BSDF on a grid of (film thickness, theta_i, theta_o, phi)
// for reflection and, if the model transmits, transmission (layout in table_grid.h).
// Values are stored without the cosine (f, 1/sr) after projecting the model's channels by
// P (e.g. spectra -> linear sRGB); the last row of P is the luminance that drives effort.
//
// Stochastic models (BSDF::stochastic() non-null) get an adaptive effort in two stages:
//   pilot   `min_samples` walks per cell estimate the cell's luminance and its standard
//           error (seed stream 0 of the cell);
//   finish  each cell gets n = clamp(1.1 min_samples (se / target)^2, min_samples,
//           max_samples) walks, target = rel_error max(|pilot luminance|, floor x the mean
//           pilot luminance of the cell's lobe), from a FRESH seed stream (1 of the cell).
//           The stored value and sample count are those of the fresh walks alone; the
//           error is the fresh mean's, with the walks' spread pooled over the pilot's and
//           the fresh walks (pooled_error below).
// Why this is unbiased: the pilot only chooses n. Given n, the finish walks are
// independent of the pilot, so E[value | n] = f for every n, hence E[value] = f. (Pooling
// the pilot into the value, as version 1 did, is biased low for heavy-tailed cells: a
// pilot that reads low also understates its error and stops its cell early.)
//
// Decomposition (a distributed driver runs blocks of cells; results are bit-identical to
// a whole run): a cell's pilot is a pure function of (model, grid, cell, settings, seed);
// the only cross-cell quantity, the per-lobe floor scale, is reduced from the pilot
// luminances in cell-index order (floor_scale); a cell's finish is a pure function of
// (model, grid, cell, settings, seed, its pilot luminance and error, the floor scale).
// Each cell is computed by one thread, so thread counts do not change any bit either.
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>
#include "bsdf.h"
#include "table_grid.h"

namespace bsdflab {

// Memory the film lookups of one Tabulator may take (a snake node: ~1 MB); nodes beyond
// it keep the exact film.
constexpr std::size_t kFilmLookupBudgetBytes = std::size_t(256) << 20;

struct TabulationSettings {
    double rel_error = 0.01;
    double floor = 0.05;   // fraction of the lobe's mean luminance below which error is absolute
    int min_samples = 512; // pilot walks, and the least number of final walks (docs/coverage.md)
    int max_samples = 1 << 16;
    uint64_t seed = 0;
    // Walks of a thickness node use the model's with_film_lookup copy at that thickness
    // (film R and T interpolated, error measured at construction: film_lookup.h); false
    // evaluates every film exactly (the reference).
    bool film_lookup = true;
};

// Progress and cancellation shared by the stages of one job (both may be null).
struct TabulationControl {
    std::atomic<std::size_t> *done = nullptr;
    const std::atomic<bool> *cancelled = nullptr;
    bool stop() const { return cancelled && cancelled->load(); }
    void tick() const {
        if (done) ++*done;
    }
};

// The standard error of a mean of `n` fresh walks whose own standard error is `fresh`,
// with the per-walk spread pooled with an independent pilot of `n0` walks (standard error
// `pilot`): sqrt(((n0 - 1) n0 pilot^2 + (n - 1) n fresh^2) / (n0 + n - 2) / n). Why: a
// heavy-tailed cell whose fresh walks miss their rare large contributions reads low in
// value AND in spread, so its own z is skewed toward large negative values (issue 32:
// 15x the normal share beyond 4 sigma for the snake); the pilot's walks are independent
// of the value, and twice the walks give the spread twice the degrees of freedom
// (docs/coverage.md measures it). n0 or n < 2: the fresh error.
double pooled_error(double fresh, int n, double pilot, int n0);

// Outputs of the pilot stage, one entry per listed cell.
struct PilotCells {
    std::vector<double> lum, lum_error;
    std::vector<double> error; // out_channels per cell: each channel's standard error
    std::uint64_t nonfinite = 0;
    std::uint64_t capped = 0; // walks cut by the model's depth cap (biased; 0 for a sound model)
};

// Outputs of the finish stage, one entry per listed cell (value/error: out_channels each).
struct FinishedCells {
    std::vector<double> value, error, lum, lum_error;
    std::vector<int> samples;
    std::uint64_t nonfinite = 0;
    std::uint64_t capped = 0;
};

// The stage functions. Immutable after construction: safe to share between threads;
// each stage runs its cells on all cores (call without the GIL).
class Tabulator {
  public:
    // P: (rows x model channels) row-major; rows - 1 output channels plus luminance last.
    Tabulator(std::shared_ptr<const BSDF> model, TableGrid grid, std::vector<double> P, int rows,
              TabulationSettings settings);
    // The same model, grid and film lookups (shared, not rebuilt) with other settings:
    // the stages of one table differ only in effort and target. `settings.film_lookup`
    // must equal this one's (the lookups are what is shared).
    std::shared_ptr<Tabulator> with_settings(const TabulationSettings &settings) const;
    std::size_t cells() const { return grid_.cells(); }
    int out_channels() const { return rows_ - 1; }
    bool stochastic() const { return estimator_ != nullptr; }
    const TableGrid &grid() const { return grid_; }
    const TabulationSettings &settings() const { return settings_; }
    // Largest measured |error| of the film lookups in use (film_lookup.h); -1: none in use.
    double film_lookup_error() const { return film_lookup_error_; }

    PilotCells pilot(const std::vector<std::size_t> &cells, const TabulationControl &ctl = {}) const;
    // Per lobe: the mean |pilot luminance| over the lobe's cells, summed in cell order.
    // `lum` holds every cell's pilot luminance (cells() entries, cell order).
    std::vector<double> floor_scale(const std::vector<double> &lum) const;
    // The number of final walks of a cell from its pilot (1 for a deterministic model).
    int effort(std::size_t cell, double pilot_lum, double pilot_error,
               const std::vector<double> &scale) const;
    // pilot_lum / pilot_error: aligned with `cells`. pilot_channel_error: the pilot's
    // per-channel errors (out_channels per cell, PilotCells::error) for the pooled errors,
    // or empty: each channel then takes the luminance's pooled/fresh ratio.
    FinishedCells finish(const std::vector<std::size_t> &cells, const std::vector<double> &pilot_lum,
                         const std::vector<double> &pilot_error, const std::vector<double> &scale,
                         const TabulationControl &ctl = {},
                         const std::vector<double> &pilot_channel_error = {}) const;

  private:
    // Mean and standard error of f (no cosine) for one cell, all rows of P (luminance last).
    std::uint64_t estimate(std::size_t cell, int n, uint64_t seed, double *mean, double *err,
                           std::uint64_t *capped) const;
    uint64_t cell_seed(std::size_t cell, uint64_t stage) const;

    std::shared_ptr<const BSDF> model_;
    const StochasticEstimator *estimator_;
    // Per thickness node: the model whose walks estimate that node's cells (model_ or its
    // film-lookup copy) and its estimator.
    std::vector<std::shared_ptr<const BSDF>> node_models_;
    std::vector<const StochasticEstimator *> node_estimators_;
    double film_lookup_error_ = -1;
    TableGrid grid_;
    std::vector<double> P_;
    int rows_;
    TabulationSettings settings_;
};

// One stage over a list of cells as a job (progress, cancel) for the bindings: the
// Python tabulate() runs the pilot job over every cell, floor_scale, then the finish job
// over every cell -- the same calls a distributed driver makes on blocks of cells.
class TabulationStageJob {
  public:
    enum Stage { kPilot = 0, kFinish = 1 };
    TabulationStageJob(std::shared_ptr<const Tabulator> tabulator, Stage stage,
                       std::vector<std::size_t> cells, std::vector<double> pilot_lum = {},
                       std::vector<double> pilot_error = {}, std::vector<double> scale = {},
                       std::vector<double> pilot_channel_error = {});
    void run();  // blocking; call without the GIL
    void cancel() { cancelled_ = true; }
    bool cancelled() const { return cancelled_; }
    std::size_t done() const { return done_; }
    std::size_t total() const { return cells_.size(); }

    PilotCells pilot;       // after a pilot run
    FinishedCells finished; // after a finish run

  private:
    std::shared_ptr<const Tabulator> tabulator_;
    Stage stage_;
    std::vector<std::size_t> cells_;
    std::vector<double> pilot_lum_, pilot_error_, scale_, pilot_channel_error_;
    std::atomic<std::size_t> done_{0};
    std::atomic<bool> cancelled_{false};
};

} // namespace bsdflab
