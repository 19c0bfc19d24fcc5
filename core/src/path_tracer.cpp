// The render loop: passes of tiles on all cores (run), windows of one pass for work units
// (render_window), the image from the sums (finish_image), and recorded rays for the
// Embree benchmark. The integrator is path_integrator.cpp, AOVs render_aovs.cpp.
#include "bsdflab/render/path_tracer.h"
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include "bsdflab/frame.h"
#include "bsdflab/parallel.h"
#include "bsdflab/rng.h"
#include "bsdflab/sampling.h"

namespace bsdflab {

RenderJob::RenderJob(std::shared_ptr<const RenderScene> scene, const RenderSettings &settings)
    : scene_(std::move(scene)), s_(settings) {
    if (!scene_) throw std::invalid_argument("render: no scene");
    if (!scene_->committed()) throw std::invalid_argument("render: commit() the scene first");
    if (s_.spp < 1 || s_.pass_spp < 1) throw std::invalid_argument("render: spp must be >= 1");
    if (s_.max_depth < 1 || s_.rr_depth < 1) throw std::invalid_argument("render: depths must be >= 1");
    if (s_.tile < 1) throw std::invalid_argument("render: tile size must be >= 1");
    if (s_.spectral && !scene_->spectral_ready())
        throw std::invalid_argument("render: spectral mode needs a spectral form of every material "
                                    "and the scene's spectral matrices");
    tiles_x_ = (width() + s_.tile - 1) / s_.tile;
    tiles_y_ = (height() + s_.tile - 1) / s_.tile;
    passes_ = (s_.spp + s_.pass_spp - 1) / s_.pass_spp;
    sum_.assign(std::size_t(width()) * height() * 3, 0.0);
    sum_sq_.assign(sum_.size(), 0.0);
    max_channels_ = scene_->max_channels();
}

std::size_t RenderJob::render_rect(int x0, int y0, int x1, int y1, int pass, int spp, double *out_sum,
                                   double *out_sq, std::size_t stride, RayLog &log,
                                   const std::atomic<bool> *stop) const {
    const int W = width();
    std::size_t bad = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const std::size_t pixel = std::size_t(y) * W + x;
            PCG32 pixel_rng(mix64(mix64(s_.seed) ^ pixel) ^ mix64(uint64_t(pass) + 0x51ed2705ULL));
            double sum[3] = {0, 0, 0}, sq[3] = {0, 0, 0};
            for (int k = 0; k < spp; ++k) {
                // a cancelled pass is dropped whole (run()), so a partial rect is never used
                if (stop && stop->load(std::memory_order_relaxed)) return bad;
                const uint64_t hi = pixel_rng.next(), lo = pixel_rng.next(); // in this order
                const uint64_t sample_seed = (hi << 32) | lo;
                const double jx = pixel_rng.uniform(), jy = pixel_rng.uniform(); // in this order
                double L[3];
                trace_path(x + jx, y + jy, sample_seed, L, log);
                if (!(std::isfinite(L[0]) && std::isfinite(L[1]) && std::isfinite(L[2]))) {
                    ++bad; // counted, and black: a NaN must not poison the pixel
                    continue;
                }
                for (int c = 0; c < 3; ++c) {
                    sum[c] += L[c];
                    sq[c] += L[c] * L[c];
                }
            }
            const std::size_t o = (std::size_t(y - y0) * stride + (x - x0)) * 3;
            for (int c = 0; c < 3; ++c) {
                out_sum[o + c] = sum[c];
                out_sq[o + c] = sq[c];
            }
        }
    return bad;
}

void RenderJob::render_tile(std::size_t tile, int pass, int spp) {
    const int W = width(), H = height();
    const int x0 = int(tile % tiles_x_) * s_.tile, y0 = int(tile / tiles_x_) * s_.tile;
    const int x1 = std::min(x0 + s_.tile, W), y1 = std::min(y0 + s_.tile, H);
    const std::size_t first = (std::size_t(y0) * W + x0) * 3;
    RayLog log;
    invalid_ += render_rect(x0, y0, x1, y1, pass, spp, pass_sum_.data() + first, pass_sq_.data() + first, W,
                            log, &cancelled_);
    rays_ += log.rays;
}

int RenderJob::pass_samples(int pass) const {
    if (pass < 0 || std::size_t(pass) >= passes_) return 0;
    return std::min(s_.pass_spp, s_.spp - pass * s_.pass_spp);
}

std::size_t RenderJob::render_window(int x0, int y0, int x1, int y1, int pass, double *sum,
                                     double *sq) const {
    if (x0 < 0 || y0 < 0 || x1 > width() || y1 > height() || x0 >= x1 || y0 >= y1)
        throw std::invalid_argument("render: the window must be a non-empty part of the image");
    if (pass < 0 || std::size_t(pass) >= passes_) throw std::invalid_argument("render: no such pass");
    const int spp = pass_samples(pass), w = x1 - x0, t = s_.tile;
    const std::size_t tx = (w + t - 1) / t, ty = (y1 - y0 + t - 1) / t;
    std::atomic<std::size_t> bad{0};
    // The same per-pixel streams as run(): tiling only changes who computes a pixel.
    parallel_for_each(tx * ty, [&](std::size_t tile) {
        const int ax = x0 + int(tile % tx) * t, ay = y0 + int(tile / tx) * t;
        const std::size_t first = (std::size_t(ay - y0) * w + (ax - x0)) * 3;
        RayLog log;
        bad += render_rect(ax, ay, std::min(ax + t, x1), std::min(ay + t, y1), pass, spp, sum + first,
                           sq + first, std::size_t(w), log);
    });
    return bad;
}

std::vector<float> RenderJob::record_rays(std::size_t max_rays) const {
    std::vector<float> out;
    out.reserve(8 * max_rays);
    RayLog log;
    log.record = &out;
    log.max_record = max_rays;
    const std::size_t pixels = std::size_t(width()) * height();
    const std::size_t stride = 7919; // a prime: successive samples land far apart
    for (std::size_t k = 0; k < pixels && out.size() < 8 * max_rays; ++k) {
        const std::size_t pixel = (k * stride) % pixels;
        const int x = int(pixel % width()), y = int(pixel / width());
        PCG32 pixel_rng(mix64(mix64(s_.seed) ^ pixel) ^ mix64(0x51ed2705ULL));
        const uint64_t hi = pixel_rng.next(), lo = pixel_rng.next();
        const double jx = pixel_rng.uniform(), jy = pixel_rng.uniform();
        double L[3];
        trace_path(x + jx, y + jy, (hi << 32) | lo, L, log);
    }
    return out;
}

void RenderJob::run() {
    if (running_.exchange(true)) throw std::logic_error("render: this job is already running");
    struct Done {
        std::atomic<bool> &flag;
        ~Done() { flag = false; }
    } done{running_};
    for (std::size_t pass = spp_done_ / s_.pass_spp; pass < passes_ && !cancelled_; ++pass) {
        const int spp = std::min(s_.pass_spp, s_.spp - int(pass) * s_.pass_spp);
        pass_sum_.assign(sum_.size(), 0.0);
        pass_sq_.assign(sum_.size(), 0.0);
        parallel_for_each(tiles_x_ * tiles_y_, [&](std::size_t tile) {
            if (cancelled_) return;
            render_tile(tile, int(pass), spp);
            ++done_;
        });
        if (cancelled_) break; // an unfinished pass is dropped: the image stays consistent
        for (std::size_t i = 0; i < sum_.size(); ++i) {
            sum_[i] += pass_sum_[i];
            sum_sq_[i] += pass_sq_[i];
        }
        spp_done_ += spp;
    }
    pass_sum_.clear();
    pass_sq_.clear();
}

void RenderJob::finish_image(const double *sum, const double *sum_sq, std::size_t count, double n,
                             double *mean, double *variance_of_mean) {
    for (std::size_t i = 0; i < count; ++i) {
        double m = n > 0 ? sum[i] / n : 0.0;
        mean[i] = m;
        if (n < 2) {
            variance_of_mean[i] = kInf;
        } else {
            double s2 = std::max(0.0, (sum_sq[i] - n * m * m) / (n - 1));
            variance_of_mean[i] = s2 / n;
        }
    }
}

void RenderJob::image(double *mean, double *variance_of_mean) const {
    finish_image(sum_.data(), sum_sq_.data(), sum_.size(), spp_done_, mean, variance_of_mean);
}

} // namespace bsdflab
