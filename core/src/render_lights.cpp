// Emitters: emitted radiance, choosing and sampling a light (triangle emitters by power,
// the environment by its map, point/spot/directional lights by lights.h), and the densities
// MIS needs (pbrt-v4's light sampler and Mitsuba's emitter sampling play these roles).
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include "bsdflab/render/scene.h"
#include "render_scene_impl.h"

namespace bsdflab {

void RenderScene::emitted(const SurfaceHit &hit, const Vec3 &w, double rgb[3]) const {
    const double *e = meshes_[hit.mesh].in.emission;
    bool front = dot(hit.ns, w) > 0;
    for (int c = 0; c < 3; ++c) rgb[c] = front ? e[c] : 0.0;
}

// Each strategy (the environment, the area lights as a group, each analytic light) is
// chosen with probability 1 / strategies_, as Mitsuba 3 picks emitters uniformly. With only
// an environment and area lights this is the 1/2 : 1/2 split, with the same arithmetic.
double RenderScene::env_selection() const {
    if (!environment_.active()) return 0.0;
    return 1.0 / double(strategies_);
}

double RenderScene::area_selection() const {
    if (lights_.empty()) return 0.0;
    return 1.0 / double(strategies_);
}

void RenderScene::add_light(const AnalyticLight &light, std::vector<double> spectrum) {
    if (committed_) throw std::logic_error("scene already committed: add lights before commit()");
    if (!spectrum.empty() && spectrum.size() != std::size_t(kSpectralBins))
        throw std::invalid_argument("light: a spectrum needs one value per spectral bin (81)");
    for (double v : spectrum)
        if (!(std::isfinite(v) && v >= 0))
            throw std::invalid_argument("light: spectrum must be finite and >= 0");
    if (!light.delta()) soft_.push_back(analytic_.size());
    analytic_.push_back(light);
    analytic_spectra_.push_back(std::move(spectrum));
}

EmitterSample RenderScene::sample_emitter(const Vec3 &ref, double u0, double u1, double u2) const {
    EmitterSample s;
    if (strategies_ == 0) return s;
    const double n = double(strategies_);
    std::size_t k = std::min(std::size_t(u0 * n), strategies_ - 1);
    const double u_next = u0 * n - double(k); // uniform in [0, 1) given k
    if (environment_.active()) {
        if (k == 0) {
            double pdf;
            Vec3 d = environment_.sample(u1, u2, pdf, s.radiance);
            if (!(pdf > 0)) {
                s.radiance[0] = s.radiance[1] = s.radiance[2] = 0.0;
                return s;
            }
            s.wo = d;
            s.dist = std::numeric_limits<double>::infinity();
            s.pdf = pdf / n;
            return s;
        }
        --k;
    }
    if (!lights_.empty()) {
        if (k == 0) return sample_area(ref, u_next, u1, u2, 1 / n);
        --k;
    }
    const AnalyticLight &light = analytic_[k];
    double pdf;
    if (!light.sample(ref, u1, u2, s.wo, s.dist, pdf, s.radiance, s.factor) || !(pdf > 0)) {
        s.radiance[0] = s.radiance[1] = s.radiance[2] = 0.0;
        return s;
    }
    s.pdf = pdf / n;
    s.delta = light.delta();
    if (!analytic_spectra_[k].empty()) s.spectrum = analytic_spectra_[k].data();
    return s;
}

EmitterSample RenderScene::sample_area(const Vec3 &ref, double u0, double u1, double u2,
                                       double p_area) const {
    EmitterSample s;
    double u_rest;
    std::size_t k = light_choice_.sample(u0, u_rest);
    auto [m, f] = lights_[k];
    // Uniform point on the triangle (square-root parameterisation).
    double su = std::sqrt(u1), b1 = 1 - su, b2 = u2 * su;
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
    s.pdf = p_area * light_choice_.prob(k) / meshes_[m].area[f] * d2 / cos_l;
    return s;
}

bool RenderScene::soft_light(std::size_t i, const Vec3 &d, double rgb[3], double &pdf,
                             const double *&spectrum, double &factor) const {
    const std::size_t k = soft_[i];
    if (!analytic_[k].eval_direction(d, rgb, pdf, factor)) return false;
    pdf /= double(strategies_);
    spectrum = analytic_spectra_[k].empty() ? nullptr : analytic_spectra_[k].data();
    return true;
}

double RenderScene::emitter_pdf(const Vec3 &ref, const SurfaceHit &hit) const {
    const auto &probs = light_prob_[hit.mesh];
    if (probs.empty()) return 0.0;
    Vec3 to = hit.p - ref;
    double d2 = dot(to, to);
    double cos_l = std::abs(dot(hit.ng, to)) / std::sqrt(d2);
    if (!(cos_l > 1e-12)) return 0.0;
    return area_selection() * probs[hit.prim] / meshes_[hit.mesh].area[hit.prim] * d2 / cos_l;
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
