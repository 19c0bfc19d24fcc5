// The integrator: one camera sample's radiance by unidirectional path tracing with
// next-event estimation (sample_direct) and multiple importance sampling, in RGB or over
// the spectral bins (PathColour). The tile/pass loop that calls it is path_tracer.cpp.
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
    // An emitter's colour: RGB mode always uses its RGB.
    static void light(const RenderScene &scene, const double rgb[3], const double *, double, double out[3]) {
        light(scene, rgb, out);
    }
    static void add_emitted(const RenderScene &, double L[3], const double beta[3], double w,
                            const double Le[3]) {
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
    // A light with its own spectrum uses it (times its geometric factor); others lift RGB.
    static void light(const RenderScene &scene, const double rgb[3], const double *spectrum, double factor,
                      double out[N]) {
        if (!spectrum) return scene.lift(rgb, out);
        for (int l = 0; l < N; ++l) out[l] = spectrum[l] * factor;
    }
    static void sense(const RenderScene &scene, double L[3], const double v[N]) {
        const double *W = scene.sensor();
        for (int r = 0; r < 3; ++r) {
            double s = 0;
            for (int l = 0; l < N; ++l) s += W[r * N + l] * v[l];
            L[r] += s;
        }
    }
    static void add_emitted(const RenderScene &scene, double L[3], const double beta[N], double w,
                            const double Le[N]) {
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

void RenderJob::RayLog::add(const Vec3 &o, const Vec3 &d, double tmax, bool shadow) {
    ++rays;
    if (!record || record->size() >= 8 * max_record) return;
    const float r[8] = {float(o.x),
                        float(o.y),
                        float(o.z),
                        float(d.x),
                        float(d.y),
                        float(d.z),
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

// Next-event estimation at `hit` (pbrt-v4's SampleLd): choose and sample an emitter with
// three uniforms of `rng`, trace the shadow ray, and add the light it connects to L, weighted
// by the path throughput `beta`, the BSDF and (with MIS) the power heuristic.
template <int N>
void RenderJob::sample_direct(const SurfaceHit &hit, const ShadingPoint &sp, const Vec3 &wi,
                              const double *beta, double L[3], PCG32 &rng, double *buf, RayLog &log) const {
    using Colour = PathColour<N>;
    const RenderScene &scene = *scene_;
    const RenderBSDF *rb = sp.bsdf;
    const ShadingFrame &frame = sp.frame;
    const Query &q = sp.query;
    const BSDF &bsdf = *rb->bsdf;
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
                // A delta light cannot be found by BSDF sampling: its weight is 1.
                double w = (s_.strategy == LightStrategy::kMIS && !es.delta
                                ? power_heuristic(es.pdf, bsdf.pdf(wi, wo, kAll, q))
                                : 1.0) /
                           es.pdf;
                double Le[N];
                Colour::light(scene, es.radiance, es.spectrum, es.factor, Le);
                Colour::add_connected(scene, L, beta, f, Le, w);
            }
        }
    }
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
            // Soft suns in this direction: each is its own NEE strategy, weighted by its own
            // density (delta lights are never found here).
            for (std::size_t i = 0; i < scene.soft_lights(); ++i) {
                double rgb[3], Le[N], light_pdf, factor;
                const double *spectrum;
                if (!scene.soft_light(i, d, rgb, light_pdf, spectrum, factor)) continue;
                Colour::light(scene, rgb, spectrum, factor, Le);
                double w = prev_delta ? 1.0 : mis_hit(prev_pdf, light_pdf);
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
        if ((rb->lobes & ~uint32_t(kDelta)) && scene.has_lights() && s_.strategy != LightStrategy::kBSDFOnly)
            sample_direct<N>(hit, sp, wi, beta, L, rng, buf, log);

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

} // namespace bsdflab
