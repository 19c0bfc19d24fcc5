// Unidirectional path tracing with next-event estimation, power-heuristic MIS and
// Russian roulette, over image tiles on all cores.
//
// Conventions follow Mitsuba 3's `path` integrator so the two renderers estimate the same
// image: max_depth counts path vertices from the camera (1 = emitters seen directly,
// 2 = direct lighting, ...); from rr_depth on, a path survives with probability
// min(max(throughput) * eta^2, 0.95). A pixel is the box-filtered mean over its area.
//
// Progressive: the job renders `spp` samples per pixel in passes of `pass_spp`; each pass
// visits every tile once (tiles handed to whichever thread is free), so a pixel's sums are
// only ever touched by one thread at a time and the image is the same for any thread
// count. Each (pixel, pass) seeds its own PCG32 from (seed, pixel, pass).
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>
#include "bsdflab/render/scene.h"
#include "bsdflab/rng.h"

namespace bsdflab {

// Which estimator of direct light: both strategies with MIS (the renderer), or one alone
// (each is unbiased by itself: tests compare them against closed forms and each other).
enum class LightStrategy : int { kMIS = 0, kBSDFOnly = 1, kLightOnly = 2 };

struct RenderSettings {
    LightStrategy strategy = LightStrategy::kMIS;
    int spp = 16;
    int pass_spp = 4;
    int max_depth = 8;
    int rr_depth = 5;
    uint64_t seed = 0;
    int tile = 16;
    // Spectral transport over the default grid's bins instead of RGB (see path_tracer.cpp).
    bool spectral = false;
};

template <int N> struct PathColour;

class RenderJob {
  public:
    RenderJob(std::shared_ptr<const RenderScene> scene, const RenderSettings &settings);

    // Renders every pass not yet done (call once; returns early after cancel()).
    void run();
    void cancel() { cancelled_ = true; }
    bool cancelled() const { return cancelled_; }
    // Progress in (tile, pass) units.
    std::size_t total() const { return tiles_x_ * tiles_y_ * passes_; }
    std::size_t done() const { return done_; }
    int spp_done() const { return spp_done_; }
    std::size_t invalid_samples() const { return invalid_; }

    int width() const { return scene_->camera().width(); }
    int height() const { return scene_->camera().height(); }
    // Per pixel and channel: the mean, and the variance of that mean (sample variance / n),
    // over the passes completed so far. Call only while run() is not executing.
    void image(double *mean, double *variance_of_mean) const;

    // One camera sample's radiance (exposed for tests).
    void radiance(double px, double py, uint64_t sample_seed, double rgb[3]) const;

    // Work units for distributed rendering: pass `pass` over the pixel window
    // [x0, x1) x [y0, y1), tiles on all cores, into window-sized row-major RGB sums of the
    // samples and of their squares. The numbers are exactly those run() computes for these
    // pixels in this pass, so summing units pass by pass in order reproduces run()'s image.
    // Returns the number of invalid (non-finite) samples, which are left out as in run().
    std::size_t render_window(int x0, int y0, int x1, int y1, int pass, double *sum, double *sq) const;
    std::size_t passes() const { return passes_; }
    int pass_samples(int pass) const;
    // The image from accumulated sums over n samples (what image() reports): shared by
    // run() and by drivers that accumulate render_window() units themselves.
    static void finish_image(const double *sum, const double *sum_sq, std::size_t count, double n,
                             double *mean, double *variance_of_mean);
    // Rays traced by run() so far (camera, bounce and shadow rays).
    std::size_t rays_traced() const { return rays_; }
    // The rays one sample per pixel of the first pass traces, over pixels spread evenly
    // across the image, up to max_rays: 8 floats per ray (origin, direction, tmax,
    // 0 = closest hit / 1 = shadow), for timing Embree alone on the renderer's own rays.
    std::vector<float> record_rays(std::size_t max_rays) const;
    // First-hit auxiliary images for a denoiser, (H, W, 3) each: the BSDF's albedo (mean
    // sample weight over `samples` draws at the pixel centre's hit) and the shading normal;
    // mesh_id (H, W) is the mesh hit first (-1: none).
    void aovs(int samples, double *albedo, double *normal, int *mesh_id) const;

  private:
    struct RayLog {
        std::size_t rays = 0;
        std::vector<float> *record = nullptr;
        std::size_t max_record = 0;
        void add(const Vec3 &o, const Vec3 &d, double tmax, bool shadow);
    };
    void trace_path(double px, double py, uint64_t sample_seed, double L[3], RayLog &log) const;
    template <int N>
    void trace_path_in(double px, double py, uint64_t sample_seed, double L[3], RayLog &log) const;
    // Next-event estimation at a path vertex (pbrt-v4's SampleLd): adds the sampled
    // emitter's contribution to L.
    template <int N>
    void sample_direct(const SurfaceHit &hit, const ShadingPoint &sp, const Vec3 &wi, const double *beta,
                       double L[3], PCG32 &rng, double *buf, RayLog &log) const;
    void render_tile(std::size_t tile, int pass, int spp);
    // Pixels [x0, x1) x [y0, y1) of one pass; out_sum/out_sq point at pixel (x0, y0) of
    // row-major buffers whose rows are `stride` pixels long. With `stop`, the rect is
    // abandoned (its sums incomplete) as soon as *stop reads true, checked before every camera
    // sample: cancel latency is one path per thread, whatever the tile size or pass_spp.
    std::size_t render_rect(int x0, int y0, int x1, int y1, int pass, int spp, double *out_sum,
                            double *out_sq, std::size_t stride, RayLog &log,
                            const std::atomic<bool> *stop = nullptr) const;

    std::shared_ptr<const RenderScene> scene_;
    RenderSettings s_;
    std::size_t tiles_x_, tiles_y_, passes_;
    std::vector<double> sum_, sum_sq_;     // completed passes
    std::vector<double> pass_sum_, pass_sq_; // the pass in progress
    std::atomic<std::size_t> done_{0}, invalid_{0}, rays_{0};
    std::atomic<bool> cancelled_{false}, running_{false};
    int spp_done_ = 0;
    int max_channels_ = 3;
};

} // namespace bsdflab
