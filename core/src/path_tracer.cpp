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

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
// Shadow rays stop this fraction short of the light point (float BVH precision).
constexpr double kShadowEpsilon = 1e-4;

// Ray origin just off the surface on the side `w` leaves to, scaled to float precision
// at p (the BVH works in float).
Vec3 offset_origin(const SurfaceHit &h, const Vec3 &w) {
    double m = std::max({std::abs(h.p.x), std::abs(h.p.y), std::abs(h.p.z)});
    double eps = 1e-5 * (1 + m);
    return h.p + h.ng * (dot(w, h.ng) >= 0 ? eps : -eps);
}

double *channel_buffer(int n) {
    thread_local std::vector<double> buffer;
    if (int(buffer.size()) < n) buffer.resize(n);
    return buffer.data();
}

bool any_positive(const double v[3]) { return v[0] > 0 || v[1] > 0 || v[2] > 0; }
} // namespace

// How a path carries colour. RGB: three channels, BSDFs projected by their P per
// evaluation. Spectral: the kSpectralBins bins of the default grid, BSDFs lifted by their U
// (spectral models answer in the bins themselves), RGB emission lifted by the scene's U,
// and every contribution taken to RGB by the sensor W (illuminant folded in) as it is
// added. RGB keeps its original arithmetic order (images unchanged bit for bit).
template <> struct PathColour<3> {
    static void bsdf(const RenderBSDF &rb, const double *ch, double out[3]) { rb.to_rgb(ch, out); }
    static void light(const RenderScene &, const double rgb[3], double out[3]) {
        for (int c = 0; c < 3; ++c) out[c] = rgb[c];
    }
    static void add_emitted(const RenderScene &, double L[3], const double beta[3], double w, const double Le[3]) {
        for (int c = 0; c < 3; ++c) L[c] += beta[c] * w * Le[c];
    }
    static void add_connected(const RenderScene &, double L[3], const double beta[3], const double f[3],
                              const double Le[3], double w) {
        for (int c = 0; c < 3; ++c) L[c] += beta[c] * f[c] * Le[c] * w;
    }
};

template <> struct PathColour<kSpectralBins> {
    static constexpr int N = kSpectralBins;
    static void bsdf(const RenderBSDF &rb, const double *ch, double out[N]) { rb.to_spectrum(ch, out); }
    static void light(const RenderScene &scene, const double rgb[3], double out[N]) { scene.lift(rgb, out); }
    static void sense(const RenderScene &scene, double L[3], const double v[N]) {
        const double *W = scene.sensor();
        for (int r = 0; r < 3; ++r) {
            double s = 0;
            for (int l = 0; l < N; ++l) s += W[r * N + l] * v[l];
            L[r] += s;
        }
    }
    static void add_emitted(const RenderScene &scene, double L[3], const double beta[N], double w, const double Le[N]) {
        double v[N];
        for (int l = 0; l < N; ++l) v[l] = beta[l] * w * Le[l];
        sense(scene, L, v);
    }
    static void add_connected(const RenderScene &scene, double L[3], const double beta[N], const double f[N],
                              const double Le[N], double w) {
        double v[N];
        for (int l = 0; l < N; ++l) v[l] = beta[l] * f[l] * Le[l] * w;
        sense(scene, L, v);
    }
};

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

void RenderJob::RayLog::add(const Vec3 &o, const Vec3 &d, double tmax, bool shadow) {
    ++rays;
    if (!record || record->size() >= 8 * max_record) return;
    const float r[8] = {float(o.x), float(o.y), float(o.z), float(d.x), float(d.y), float(d.z),
                        std::isinf(tmax) ? std::numeric_limits<float>::infinity() : float(tmax),
                        shadow ? 1.0f : 0.0f};
    record->insert(record->end(), r, r + 8);
}

void RenderJob::radiance(double px, double py, uint64_t sample_seed, double L[3]) const {
    RayLog log;
    trace_path(px, py, sample_seed, L, log);
}

void RenderJob::trace_path(double px, double py, uint64_t sample_seed, double L[3], RayLog &log) const {
    if (s_.spectral) trace_path_in<kSpectralBins>(px, py, sample_seed, L, log);
    else trace_path_in<3>(px, py, sample_seed, L, log);
}

template <int N>
void RenderJob::trace_path_in(double px, double py, uint64_t sample_seed, double L[3], RayLog &log) const {
    using Colour = PathColour<N>;
    PCG32 rng(sample_seed);
    const RenderScene &scene = *scene_;
    const Environment &env = scene.environment();
    L[0] = L[1] = L[2] = 0;
    double beta[N], eta = 1, prev_pdf = 0;
    std::fill(beta, beta + N, 1.0);
    bool prev_delta = true;
    Vec3 prev_p;
    Vec3 o = scene.camera().origin(), d = scene.camera().direction(px, py);
    double *buf = channel_buffer(max_channels_);
    // Weight of emission found by a BSDF-sampled ray whose light could also have been
    // sampled by next-event estimation with density `light_pdf`.
    auto mis_hit = [this](double bsdf_pdf, double light_pdf) {
        switch (s_.strategy) {
        case LightStrategy::kBSDFOnly: return 1.0;
        case LightStrategy::kLightOnly: return light_pdf > 0 ? 0.0 : 1.0;
        default: return power_heuristic(bsdf_pdf, light_pdf);
        }
    };

    for (int depth = 1;; ++depth) { // depth: index of the vertex this ray finds
        SurfaceHit hit;
        log.add(o, d, kInf, false);
        if (!scene.intersect(o, d, kInf, hit)) {
            if (env.active()) {
                double rgb[3], Le[N], env_pdf;
                scene.environment_radiance(d, rgb, env_pdf);
                Colour::light(scene, rgb, Le);
                double w = prev_delta ? 1.0 : mis_hit(prev_pdf, env_pdf);
                Colour::add_emitted(scene, L, beta, w, Le);
            }
            break;
        }
        double Le_rgb[3];
        scene.emitted(hit, -d, Le_rgb);
        if (any_positive(Le_rgb)) {
            double Le[N];
            Colour::light(scene, Le_rgb, Le);
            double w = prev_delta ? 1.0 : mis_hit(prev_pdf, scene.emitter_pdf(prev_p, hit));
            Colour::add_emitted(scene, L, beta, w, Le);
        }
        if (depth >= s_.max_depth) break;
        const Material *mat = scene.material_of(hit.mesh);
        if (!mat) break;

        const ShadingPoint sp = mat->shade(hit);
        const RenderBSDF *rb = sp.bsdf;
        const ShadingFrame &frame = sp.frame;
        const Query &q = sp.query;
        const BSDF &bsdf = *rb->bsdf;
        const Vec3 wi = frame.to_local(-d);

        // Next-event estimation (BSDFs with a non-delta lobe only).
        if ((rb->lobes & ~uint32_t(kDelta)) && scene.has_lights() && s_.strategy != LightStrategy::kBSDFOnly) {
            double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
            EmitterSample es = scene.sample_emitter(hit.p, u0, u1, u2);
            if (es.pdf > 0 && any_positive(es.radiance)) {
                Vec3 wo = frame.to_local(es.wo);
                double f[N];
                bsdf.eval(wi, wo, kAll, q, buf);
                Colour::bsdf(*rb, buf, f);
                if (std::any_of(f, f + N, [](double x) { return x != 0; })) {
                    // Aim from the offset origin at the light point itself, so the ray
                    // meets the light's plane at exactly its length (aiming along es.wo from
                    // the offset origin would cross it early, and the light would shadow
                    // itself when seen at a grazing angle).
                    Vec3 origin = offset_origin(hit, es.wo), dir = es.wo;
                    double tmax = kInf;
                    bool aimed = true;
                    if (!std::isinf(es.dist)) {
                        Vec3 to = hit.p + es.wo * es.dist - origin;
                        double len = length(to);
                        aimed = len > 0; // a light point at the origin itself: no usable ray
                        if (aimed) dir = to * (1 / len);
                        tmax = len * (1 - kShadowEpsilon);
                    }
                    if (aimed) log.add(origin, dir, tmax, true);
                    if (aimed && !scene.occluded(origin, dir, tmax)) {
                        double w = (s_.strategy == LightStrategy::kMIS ? power_heuristic(es.pdf, bsdf.pdf(wi, wo, kAll, q))
                                                                        : 1.0) / es.pdf;
                        double Le[N];
                        Colour::light(scene, es.radiance, Le);
                        Colour::add_connected(scene, L, beta, f, Le, w);
                    }
                }
            }
        }

        // Continue the path by sampling the BSDF.
        double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        BSDFSample bs = bsdf.sample(wi, u0, u1, u2, kAll, q, buf);
        if (bs.lobe == 0) break;
        double weight[N];
        Colour::bsdf(*rb, buf, weight);
        for (int c = 0; c < N; ++c) beta[c] *= weight[c];
        const double beta_max = *std::max_element(beta, beta + N);
        if (!(beta_max > 0) || !std::isfinite(beta_max)) break;
        prev_delta = (bs.lobe & kDelta) != 0;
        prev_pdf = bs.pdf;
        prev_p = hit.p;
        if (bs.lobe & kTransmission) eta *= bs.eta;
        Vec3 dw = normalized(frame.to_world(bs.wo));
        if (!(length(dw) > 0)) break;
        if (depth >= s_.rr_depth) {
            double survive = std::min(beta_max * eta * eta, 0.95);
            if (!(rng.uniform() < survive)) break;
            for (double &b : beta) b /= survive;
        }
        o = offset_origin(hit, dw);
        d = dw;
    }
}

std::size_t RenderJob::render_rect(int x0, int y0, int x1, int y1, int pass, int spp, double *out_sum,
                                   double *out_sq, std::size_t stride, RayLog &log) const {
    const int W = width();
    std::size_t bad = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const std::size_t pixel = std::size_t(y) * W + x;
            PCG32 pixel_rng(mix64(mix64(s_.seed) ^ pixel) ^ mix64(uint64_t(pass) + 0x51ed2705ULL));
            double sum[3] = {0, 0, 0}, sq[3] = {0, 0, 0};
            for (int k = 0; k < spp; ++k) {
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
    invalid_ += render_rect(x0, y0, x1, y1, pass, spp, pass_sum_.data() + first, pass_sq_.data() + first, W, log);
    rays_ += log.rays;
}

int RenderJob::pass_samples(int pass) const {
    if (pass < 0 || std::size_t(pass) >= passes_) return 0;
    return std::min(s_.pass_spp, s_.spp - pass * s_.pass_spp);
}

std::size_t RenderJob::render_window(int x0, int y0, int x1, int y1, int pass, double *sum, double *sq) const {
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

void RenderJob::aovs(int samples, double *albedo, double *normal, int *mesh_id) const {
    const int W = width(), H = height();
    const RenderScene &scene = *scene_;
    parallel_for(std::size_t(W) * H, 256, [&](std::size_t begin, std::size_t end) {
        std::vector<double> buf(std::max(max_channels_, 3));
        for (std::size_t pixel = begin; pixel < end; ++pixel) {
            double *a = &albedo[3 * pixel], *n = &normal[3 * pixel];
            a[0] = a[1] = a[2] = n[0] = n[1] = n[2] = 0;
            mesh_id[pixel] = -1;
            const int x = int(pixel % W), y = int(pixel / W);
            SurfaceHit hit;
            const Vec3 d = scene.camera().direction(x + 0.5, y + 0.5);
            if (!scene.intersect(scene.camera().origin(), d, kInf, hit)) continue;
            mesh_id[pixel] = hit.mesh;
            const Material *mat = scene.material_of(hit.mesh);
            if (!mat) { a[0] = a[1] = a[2] = 1; continue; } // emitters: white albedo
            const ShadingPoint sp = mat->shade(hit);
            n[0] = sp.frame.n.x; n[1] = sp.frame.n.y; n[2] = sp.frame.n.z;
            const Vec3 wi = sp.frame.to_local(-d);
            PCG32 rng(mix64(pixel) ^ 0xa0a5ULL);
            for (int k = 0; k < samples; ++k) {
                const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                BSDFSample bs = sp.bsdf->bsdf->sample(wi, u0, u1, u2, kAll, sp.query, buf.data());
                if (!bs.lobe) continue;
                double rgb[3];
                sp.bsdf->to_rgb(buf.data(), rgb);
                for (int c = 0; c < 3; ++c) a[c] += std::clamp(rgb[c], 0.0, 1.0) / samples;
            }
        }
    });
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
