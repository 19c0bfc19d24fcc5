// Emitters: emitted radiance, choosing and sampling a light (triangle emitters by power,
// the environment by its map), and the densities MIS needs (pbrt-v4's light sampler and
// Mitsuba's emitter sampling play these roles).
#include <cmath>
#include <limits>
#include "bsdflab/render/scene.h"
#include "render_scene_impl.h"

namespace bsdflab {

void RenderScene::emitted(const SurfaceHit &hit, const Vec3 &w, double rgb[3]) const {
    const double *e = meshes_[hit.mesh].in.emission;
    bool front = dot(hit.ns, w) > 0;
    for (int c = 0; c < 3; ++c) rgb[c] = front ? e[c] : 0.0;
}

double RenderScene::env_selection() const {
    if (!environment_.active()) return 0.0;
    return lights_.empty() ? 1.0 : 0.5;
}

EmitterSample RenderScene::sample_emitter(const Vec3 &ref, double u0, double u1, double u2) const {
    EmitterSample s;
    const double p_env = env_selection();
    if (p_env == 0 && lights_.empty()) return s;
    if (u0 < p_env) {
        double pdf;
        Vec3 d = environment_.sample(u1, u2, pdf, s.radiance);
        if (!(pdf > 0)) {
            s.radiance[0] = s.radiance[1] = s.radiance[2] = 0.0;
            return s;
        }
        s.wo = d;
        s.dist = std::numeric_limits<double>::infinity();
        s.pdf = pdf * p_env;
        return s;
    }
    double u_rest;
    std::size_t k = light_choice_.sample(p_env > 0 ? (u0 - p_env) / (1 - p_env) : u0, u_rest);
    auto [m, f] = lights_[k];
    // Uniform point on the triangle (square-root parameterisation).
    double su = std::sqrt(u1), b1 = 1 - su, b2 = u2 * su;
    (void)u_rest;
    SurfaceHit h;
    fill_hit(m, f, b1, b2, h);
    Vec3 to = h.p - ref;
    double d2 = dot(to, to);
    if (!(d2 > 0)) return s;
    double dist = std::sqrt(d2);
    Vec3 wo = to * (1 / dist);
    double cos_l = std::abs(dot(h.ng, wo));
    if (!(cos_l > 1e-12)) return s;
    emitted(h, -wo, s.radiance);
    s.wo = wo;
    s.dist = dist;
    s.pdf = (1 - p_env) * light_choice_.prob(k) / meshes_[m].area[f] * d2 / cos_l;
    return s;
}

double RenderScene::emitter_pdf(const Vec3 &ref, const SurfaceHit &hit) const {
    const auto &probs = light_prob_[hit.mesh];
    if (probs.empty()) return 0.0;
    Vec3 to = hit.p - ref;
    double d2 = dot(to, to);
    double cos_l = std::abs(dot(hit.ng, to)) / std::sqrt(d2);
    if (!(cos_l > 1e-12)) return 0.0;
    return (1 - env_selection()) * probs[hit.prim] / meshes_[hit.mesh].area[hit.prim] * d2 / cos_l;
}

double RenderScene::environment_pdf(const Vec3 &d) const {
    double p = env_selection();
    return p > 0 ? p * environment_.pdf(d) : 0.0;
}

void RenderScene::environment_radiance(const Vec3 &d, double rgb[3], double &pdf) const {
    environment_.eval_pdf(d, rgb, pdf);
    pdf *= env_selection();
}

} // namespace bsdflab
