// Rough interfaces after Walter et al. 2007 ("Microfacet models for refraction through
// rough surfaces"), with visible-normal sampling; conventions match Mitsuba 3's
// roughconductor / roughdielectric so the two can be compared value by value. With
// multiscatter, the Kulla-Conty compensation lobe (rough_multiscatter.h) is added and
// sampled as a one-sample mixture: pdf = (1 - p) pdf_single + p pdf_lobe, weight =
// eval / pdf of the sum, whichever component drew the direction.
#include <cmath>
#include <stdexcept>
#include "bsdflab/complex_fresnel.h"
#include "bsdflab/film_lookup.h"
#include "bsdflab/frame.h"
#include "bsdflab/interfaces.h"
#include "bsdflab/sampling.h"
#include "bsdflab/scratch.h"

namespace bsdflab {

namespace {
// The compensation lobe's values (a buffer of this file: callers may hold scratch slots).
double *lobe_buffer(int n) {
    thread_local std::vector<double> buffer;
    if (static_cast<int>(buffer.size()) < n) buffer.resize(n);
    return buffer.data();
}
} // namespace

RoughInterface::RoughInterface(std::vector<double> wavelengths, std::shared_ptr<const FresnelTerm> term,
                               double alpha, bool two_sided, MicrofacetType type, bool multiscatter)
    : BSDF(std::move(wavelengths)), term_(std::move(term)), mf_(type, alpha), two_sided_(two_sided) {
    if (!term_ || term_->channels() != channels())
        throw std::invalid_argument("the Fresnel term must have one channel per wavelength");
    if (!(alpha > 0) || !std::isfinite(alpha)) throw std::invalid_argument("alpha must be > 0");
    if (term_->transmissive() && (!(term_->eta() > 0) || !std::isfinite(term_->eta())))
        throw std::invalid_argument("the relative index must be finite and > 0");
    if (term_->transmissive() && std::abs(term_->eta() - 1.0) <= kMatchedEta &&
        dynamic_cast<const DielectricTerm *>(term_.get()) != nullptr) {
        matched_ = std::make_unique<SmoothInterface>(wavelengths_, term_, false);
        return;
    }
    if (multiscatter) ms_ = std::make_unique<MultiScatter>(mf_, term_);
}

uint32_t RoughInterface::lobes() const {
    if (matched_) return matched_->lobes();
    return kGlossyReflection | (term_->transmissive() ? kGlossyTransmission : 0u);
}

bool RoughInterface::fold(Vec3 &wi, Vec3 &wo) const {
    if (term_->transmissive()) return true;
    if (two_sided_ && wi.z < 0 && wo.z < 0) {
        wi.z = -wi.z;
        wo.z = -wo.z;
    }
    return wi.z > 0 && wo.z > 0;
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

double RoughInterface::choice_probability(const double *R, const double *T, uint32_t lobes,
                                          bool reflect) const {
    const bool want_r = lobes & kGlossyReflection;
    const bool want_t = term_->transmissive() && (lobes & kGlossyTransmission);
    // A lobe outside the mask is never picked (version 4 gave transmission 1 - 0 when
    // the mask held no glossy lobe at all: a leak).
    if (!(reflect ? want_r : want_t)) return 0.0;
    if (!want_r || !want_t) return 1.0;
    double Rm = channel_mean(R, channels()), Tm = channel_mean(T, channels());
    double p_r = Rm + Tm > 0 ? Rm / (Rm + Tm) : 0.0;
    return reflect ? p_r : 1.0 - p_r;
}

void RoughInterface::eval(const Vec3 &wi_, const Vec3 &wo_, uint32_t lobes, const Query &q,
                          double *out) const {
    if (matched_) return matched_->eval(wi_, wo_, lobes, q, out);
    zero(out);
    if (!usable_direction(wi_) || !usable_direction(wo_)) return;
    Vec3 wi = wi_, wo = wo_;
    if (!fold(wi, wo)) return;
    eval_single(wi, wo, lobes, q, out);
    if (!ms_) return;
    const int C = channels();
    double *extra = lobe_buffer(C);
    ms_->eval(wi, wo, lobes, q, extra);
    for (int c = 0; c < C; ++c) out[c] += extra[c];
}

void RoughInterface::eval_single(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                                 double *out) const {
    const int C = channels();
    if (!term_->transmissive() && !(lobes & kGlossyReflection)) return;
    Vec3 m;
    bool reflect;
    double eta_rel;
    if (!half_vector(wi, wo, m, reflect, eta_rel)) return;
    if (!(lobes & (reflect ? kGlossyReflection : kGlossyTransmission))) return;
    double D = mf_.D(m), G = mf_.G(wi, wo, m);
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
    if (matched_) return matched_->pdf(wi_, wo_, lobes, q);
    if (!usable_direction(wi_) || !usable_direction(wo_)) return 0.0;
    Vec3 wi = wi_, wo = wo_;
    if (!fold(wi, wo)) return 0.0;
    double p = pdf_single(wi, wo, lobes, q);
    if (!ms_) return p;
    double p_lobe, p_reflect;
    ms_->probabilities(wi, lobes, p_lobe, p_reflect);
    double mixed = (1.0 - p_lobe) * p + ms_->pdf(wi, wo, lobes);
    return std::isfinite(mixed) ? mixed : 0.0;
}

double RoughInterface::pdf_single(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const {
    Vec3 m;
    bool reflect;
    double eta_rel;
    if (!half_vector(wi, wo, m, reflect, eta_rel)) return 0.0;
    double dim = dot(wi, m), dom = dot(wo, m);
    // The configuration must be consistent with a microfacet seen from both sides.
    if (dim * wi.z <= 0 || dom * wo.z <= 0) return 0.0;
    const int C = channels();
    double *R = scratch(0, C), *T = scratch(1, C);
    // The Fresnel term (a thin film's every channel) only sets the choice between two
    // requested lobes: with one lobe requested the probability is 0 or 1 without it.
    const bool both = (lobes & kGlossyReflection) && term_->transmissive() && (lobes & kGlossyTransmission);
    if (both) term_->eval(dim, q, R, T);
    double prob = choice_probability(R, T, lobes, reflect);
    if (!(prob > 0)) return 0.0;
    Vec3 wi_up = wi.z > 0 ? wi : -wi;
    // eta^2 |dom| / (dim + eta dom)^2, written so that no extreme index overflows.
    double shrink = dim / eta_rel + dom;
    double jacobian = reflect ? 1.0 / (4.0 * std::abs(dom)) : std::abs(dom) / (shrink * shrink);
    double p = mf_.pdf_visible(wi_up, m) * prob * jacobian;
    return std::isfinite(p) ? p : 0.0;
}

BSDFSample RoughInterface::sample(const Vec3 &wi_, double u1, double u2x, double u2y, uint32_t lobes,
                                  const Query &q, double *weight) const {
    if (matched_) return matched_->sample(wi_, u1, u2x, u2y, lobes, q, weight);
    if (!ms_) return sample_single(wi_, u1, u2x, u2y, lobes, q, weight);
    zero(weight);
    if (!usable_direction(wi_)) return {};
    const bool transmits = term_->transmissive();
    Vec3 wi = wi_;
    if (!transmits) {
        if (wi.z < 0 && !two_sided_) return {};
        wi.z = std::abs(wi.z);
    }
    double p_lobe, p_reflect;
    ms_->probabilities(wi, lobes, p_lobe, p_reflect);
    BSDFSample s;
    if (u1 < p_lobe) { // the compensation lobe: cosine-distributed on the chosen side
        bool reflect = u1 / p_lobe < p_reflect;
        s.wo = square_to_cosine_hemisphere(u2x, u2y);
        if ((wi.z > 0) != reflect) s.wo.z = -s.wo.z;
        s.lobe = reflect ? kGlossyReflection : kGlossyTransmission;
        s.eta = reflect ? 1.0 : (wi.z > 0 ? term_->eta() : 1.0 / term_->eta());
        if (!transmits && wi_.z < 0) s.wo.z = -s.wo.z;
    } else {
        double u = p_lobe > 0 ? (u1 - p_lobe) / (1.0 - p_lobe) : u1;
        s = sample_single(wi_, std::min(u, std::nextafter(1.0, 0.0)), u2x, u2y, lobes, q, weight);
        if (!s.lobe) return {};
    }
    // The weight of the mixture: eval / pdf of the sum at the drawn direction.
    s.pdf = pdf(wi_, s.wo, lobes, q);
    if (!(s.pdf > 0)) {
        zero(weight);
        return {};
    }
    eval(wi_, s.wo, lobes, q, weight);
    for (int c = 0; c < channels(); ++c) {
        weight[c] /= s.pdf;
        if (!std::isfinite(weight[c])) {
            zero(weight);
            return {};
        }
    }
    return s;
}

BSDFSample RoughInterface::sample_single(const Vec3 &wi_, double u1, double u2x, double u2y, uint32_t lobes,
                                         const Query &q, double *weight) const {
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
    Vec3 m = mf_.sample_visible(wi_up, u2x, u2y);
    double dim = dot(wi, m);
    double *R = scratch(0, C), *T = scratch(1, C);
    term_->eval(dim, q, R, T);
    const double p_r = choice_probability(R, T, lobes, true);
    const bool pick_r = u1 < p_r; // p_r is 0 or 1 unless both glossy lobes are requested
    double prob = pick_r ? p_r : choice_probability(R, T, lobes, false);
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
        double dom = dot(s.wo, m), shrink = dim * f.eta_ti + dom;
        jacobian = std::abs(dom) / (shrink * shrink);
        F = T;
    }
    double g1 = mf_.G1(s.wo, m);
    if (!(g1 > 0)) return {};
    s.pdf = mf_.pdf_visible(wi_up, m) * prob * jacobian;
    if (!(s.pdf > 0) || !std::isfinite(s.pdf)) return {};
    for (int c = 0; c < C; ++c) {
        weight[c] = F[c] / prob * g1 * scale;
        if (!std::isfinite(weight[c])) {
            zero(weight);
            return {};
        }
    }
    if (flipped) s.wo.z = -s.wo.z;
    return s;
}

std::shared_ptr<const BSDF> RoughInterface::with_film_lookup(double thickness_nm,
                                                             FilmLookupStats &stats) const {
    if (matched_ || ms_) return nullptr;
    auto lookup = film_lookup_for(term_, thickness_nm, stats);
    if (!lookup) return nullptr;
    return std::make_shared<RoughInterface>(wavelengths_, lookup, mf_.alpha(), two_sided_, mf_.type(), false);
}

} // namespace bsdflab
