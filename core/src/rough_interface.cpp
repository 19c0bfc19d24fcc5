// Rough interfaces after Walter et al. 2007 ("Microfacet models for refraction through
// rough surfaces"), with visible-normal sampling; conventions match Mitsuba 3's
// roughconductor / roughdielectric so the two can be compared value by value.
#include <cmath>
#include <stdexcept>
#include "bsdflab/complex_fresnel.h"
#include "bsdflab/frame.h"
#include "bsdflab/interfaces.h"
#include "bsdflab/scratch.h"

namespace bsdflab {

RoughInterface::RoughInterface(std::vector<double> wavelengths,
                               std::shared_ptr<const FresnelTerm> term, double alpha, bool two_sided)
    : BSDF(std::move(wavelengths)), term_(std::move(term)), ggx_(alpha), two_sided_(two_sided) {
    if (!term_ || term_->channels() != channels())
        throw std::invalid_argument("the Fresnel term must have one channel per wavelength");
    if (!(alpha > 0) || !std::isfinite(alpha)) throw std::invalid_argument("alpha must be > 0");
}

uint32_t RoughInterface::lobes() const {
    return kGlossyReflection | (term_->transmissive() ? kGlossyTransmission : 0u);
}

bool RoughInterface::half_vector(const Vec3 &wi, const Vec3 &wo, Vec3 &m, bool &reflect,
                                 double &eta_rel) const {
    reflect = wi.z * wo.z > 0;
    // Index of the side wo is on, relative to the side wi is on.
    eta_rel = wi.z > 0 ? term_->eta() : 1.0 / term_->eta();
    m = reflect ? wi + wo : wi + wo * eta_rel;
    double l = length(m);
    if (!(l > 0) || !std::isfinite(l)) return false;
    m = m * (1.0 / l);
    if (m.z < 0) m = -m;
    return m.z > 0;
}

double RoughInterface::reflect_probability(const double *R, const double *T, uint32_t lobes) const {
    bool want_r = lobes & kGlossyReflection, want_t = lobes & kGlossyTransmission;
    if (!want_t || !term_->transmissive()) return want_r ? 1.0 : 0.0;
    if (!want_r) return 0.0;
    double Rm = channel_mean(R, channels()), Tm = channel_mean(T, channels());
    return Rm + Tm > 0 ? Rm / (Rm + Tm) : 0.0;
}

void RoughInterface::eval(const Vec3 &wi_, const Vec3 &wo_, uint32_t lobes, const Query &q,
                          double *out) const {
    zero(out);
    if (!usable_direction(wi_) || !usable_direction(wo_)) return;
    Vec3 wi = wi_, wo = wo_;
    const int C = channels();
    if (!term_->transmissive()) {
        if (two_sided_ && wi.z < 0 && wo.z < 0) { wi.z = -wi.z; wo.z = -wo.z; }
        if (wi.z <= 0 || wo.z <= 0 || !(lobes & kGlossyReflection)) return;
    }
    Vec3 m;
    bool reflect;
    double eta_rel;
    if (!half_vector(wi, wo, m, reflect, eta_rel)) return;
    if (!(lobes & (reflect ? kGlossyReflection : kGlossyTransmission))) return;
    double D = ggx_.D(m), G = ggx_.G(wi, wo, m);
    if (!(D * G > 0)) return;
    double dim = dot(wi, m), dom = dot(wo, m);
    double *R = scratch(0, C), *T = scratch(1, C);
    term_->eval(dim, q, R, T);
    if (reflect) {
        double k = D * G / (4.0 * std::abs(wi.z));
        for (int c = 0; c < C; ++c) out[c] = R[c] * k;
    } else {
        // Walter's eta^2 and the radiance scaling 1 / eta^2 cancel.
        double denom = dim + eta_rel * dom;
        double k = D * G * std::abs(dim * dom) / (std::abs(wi.z) * denom * denom);
        if (!std::isfinite(k)) return;
        for (int c = 0; c < C; ++c) out[c] = T[c] * k;
    }
}

double RoughInterface::pdf(const Vec3 &wi_, const Vec3 &wo_, uint32_t lobes, const Query &q) const {
    if (!usable_direction(wi_) || !usable_direction(wo_)) return 0.0;
    Vec3 wi = wi_, wo = wo_;
    if (!term_->transmissive()) {
        if (two_sided_ && wi.z < 0 && wo.z < 0) { wi.z = -wi.z; wo.z = -wo.z; }
        if (wi.z <= 0 || wo.z <= 0) return 0.0;
    }
    Vec3 m;
    bool reflect;
    double eta_rel;
    if (!half_vector(wi, wo, m, reflect, eta_rel)) return 0.0;
    double dim = dot(wi, m), dom = dot(wo, m);
    // The configuration must be consistent with a microfacet seen from both sides.
    if (dim * wi.z <= 0 || dom * wo.z <= 0) return 0.0;
    const int C = channels();
    double *R = scratch(0, C), *T = scratch(1, C);
    term_->eval(dim, q, R, T);
    double p_r = reflect_probability(R, T, lobes);
    double prob = reflect ? p_r : 1.0 - p_r;
    if (!(prob > 0)) return 0.0;
    Vec3 wi_up = wi.z > 0 ? wi : -wi;
    double jacobian = reflect ? 1.0 / (4.0 * std::abs(dom))
                              : eta_rel * eta_rel * std::abs(dom) / ((dim + eta_rel * dom) * (dim + eta_rel * dom));
    double p = ggx_.pdf_visible(wi_up, m) * prob * jacobian;
    return std::isfinite(p) ? p : 0.0;
}

BSDFSample RoughInterface::sample(const Vec3 &wi_, double u1, double u2x, double u2y,
                                  uint32_t lobes, const Query &q, double *weight) const {
    zero(weight);
    if (!usable_direction(wi_)) return {};
    const bool transmits = term_->transmissive();
    Vec3 wi = wi_;
    bool flipped = false;
    if (!transmits) {
        if (!(lobes & kGlossyReflection)) return {};
        if (wi.z < 0) {
            if (!two_sided_) return {};
            wi.z = -wi.z;
            flipped = true;
        }
    }
    const int C = channels();
    Vec3 wi_up = wi.z > 0 ? wi : -wi;
    Vec3 m = ggx_.sample_visible(wi_up, u2x, u2y);
    double dim = dot(wi, m);
    double *R = scratch(0, C), *T = scratch(1, C);
    term_->eval(dim, q, R, T);
    double p_r = reflect_probability(R, T, lobes);
    bool pick_r = transmits && (lobes & kGlossyReflection) && (lobes & kGlossyTransmission) ? u1 < p_r
                                                                                             : p_r > 0;
    double prob = pick_r ? p_r : 1.0 - p_r;
    if (!(prob > 0)) return {};

    BSDFSample s;
    double scale, jacobian;
    const double *F;
    if (pick_r) {
        s.wo = m * (2.0 * dim) - wi;
        if (s.wo.z * wi.z <= 0) return {}; // reflected below the macro-surface
        s.lobe = kGlossyReflection;
        scale = 1.0;
        jacobian = 1.0 / (4.0 * std::abs(dim));
        F = R;
    } else {
        DielectricFresnel f = fresnel_dielectric(dim, term_->eta());
        if (f.cos_theta_t == 0.0) return {};
        s.wo = m * (dim * f.eta_ti + f.cos_theta_t) - wi * f.eta_ti;
        if (s.wo.z * wi.z >= 0) return {}; // refracted to the same side
        s.lobe = kGlossyTransmission;
        s.eta = f.eta_it;
        scale = f.eta_ti * f.eta_ti;
        double dom = dot(s.wo, m), denom = dim + f.eta_it * dom;
        jacobian = f.eta_it * f.eta_it * std::abs(dom) / (denom * denom);
        F = T;
    }
    double g1 = ggx_.G1(s.wo, m);
    if (!(g1 > 0)) return {};
    s.pdf = ggx_.pdf_visible(wi_up, m) * prob * jacobian;
    if (!(s.pdf > 0) || !std::isfinite(s.pdf)) return {};
    for (int c = 0; c < C; ++c) weight[c] = F[c] / prob * g1 * scale;
    if (flipped) s.wo.z = -s.wo.z;
    return s;
}

} // namespace bsdflab
