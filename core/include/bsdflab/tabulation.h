// Tabulation of an isotropic BSDF on a grid of (film thickness, theta_i, theta_o, phi)
// for reflection and, if the model transmits, transmission (layout in table_grid.h).
// Stochastic models (LayeredBSDF) get an adaptive effort: a first pass of `min_samples`
// walks per cell, then each cell is refined until the standard error of its luminance is
// below rel_error * max(|luminance|, floor * mean luminance of the lobe), or max_samples.
// Values are stored without the cosine (f, 1/sr) after projecting the model's channels by
// P (e.g. spectra -> linear sRGB); the last row of P is the luminance that drives effort.
#pragma once
#include <atomic>
#include <memory>
#include <vector>
#include "bsdf.h"
#include "table_grid.h"

namespace bsdflab {

struct TabulationSettings {
    double rel_error = 0.01;
    double floor = 0.05;   // fraction of the lobe's mean luminance below which error is absolute
    int min_samples = 64;
    int max_samples = 1 << 16;
    uint64_t seed = 0;
    bool split_direct = false; // leave the top boundary's own reflection out (layered models)
};

class TabulationJob {
public:
    // P: (rows x model channels) row-major; rows - 1 output channels plus luminance last.
    TabulationJob(std::shared_ptr<const BSDF> model, TableGrid grid, std::vector<double> P, int rows,
                  TabulationSettings settings);
    void run();  // blocking; call without the GIL
    void cancel() { cancelled_ = true; }
    bool cancelled() const { return cancelled_; }
    std::size_t done() const { return done_; }
    static constexpr int kRefinePasses = 3;
    std::size_t total() const { return (1 + kRefinePasses) * grid_.cells(); }

    const TableGrid &grid() const { return grid_; }
    int out_channels() const { return rows_ - 1; }
    // [cell * out_channels + c]; cell order as in TableGrid::cell_index.
    std::vector<double> value, error;
    std::vector<int> samples;
    std::vector<double> lum_value, lum_error; // per cell: luminance and its standard error

private:
    void estimate(std::size_t cell, int n, uint64_t seed, double *mean, double *err) const;

    std::shared_ptr<const BSDF> model_;
    TableGrid grid_;
    std::vector<double> P_;
    int rows_;
    TabulationSettings settings_;
    std::atomic<std::size_t> done_{0};
    std::atomic<bool> cancelled_{false};
};

} // namespace bsdflab
