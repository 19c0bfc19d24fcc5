#include <stdexcept>
#include "bsdflab/complex_fresnel.h"
#include "bsdflab/film_lookup.h"
#include "bsdflab/frame.h"
#include "bsdflab/interfaces.h"
#include "bsdflab/scratch.h"

namespace bsdflab {

SmoothInterface::SmoothInterface(std::vector<double> wavelengths, std::shared_ptr<const FresnelTerm> term,
                                 bool two_sided)
    : BSDF(std::move(wavelengths)), term_(std::move(term)), two_sided_(two_sided) {
    if (!term_ || term_->channels() != channels())
        throw std::invalid_argument("the Fresnel term must have one channel per wavelength");
}

uint32_t SmoothInterface::lobes() const {
    return kDeltaReflection | (term_->transmissive() ? kDeltaTransmission : 0u);
}

BSDFSample SmoothInterface::sample(const Vec3 &wi, double u1, double, double, uint32_t lobes, const Query &q,
                                   double *weight) const {
    zero(weight);
    const int C = channels();
    const bool transmits = term_->transmissive();
    bool want_r = lobes & kDeltaReflection, want_t = transmits && (lobes & kDeltaTransmission);
    if (!(want_r || want_t) || !usable_direction(wi)) return {};
    if (!transmits && wi.z < 0 && !two_sided_) return {};

    // An opaque interface seen from below (two-sided) behaves as seen from above.
    double cos_i = transmits ? wi.z : std::abs(wi.z);
    double *R = scratch(0, C), *T = scratch(1, C);
    term_->eval(cos_i, q, R, T);
    double Rm = channel_mean(R, C), Tm = transmits ? channel_mean(T, C) : 0.0;

    double p_r = want_r && want_t ? (Rm + Tm > 0 ? Rm / (Rm + Tm) : 0.0) : (want_r ? 1.0 : 0.0);
    bool pick_r = want_r && want_t ? u1 < p_r : want_r;
    double prob = pick_r ? p_r : 1.0 - p_r;
    if (!(prob > 0)) return {};

    BSDFSample s;
    s.pdf = prob;
    if (pick_r) {
        s.wo = reflect(wi);
        s.lobe = kDeltaReflection;
        for (int c = 0; c < C; ++c) weight[c] = R[c] / prob;
        return s;
    }
    DielectricFresnel f = fresnel_dielectric(wi.z, term_->eta());
    if (f.cos_theta_t == 0.0) {
        zero(weight);
        return {};
    } // total internal reflection
    s.wo = refract(wi, f.cos_theta_t, f.eta_ti);
    s.lobe = kDeltaTransmission;
    s.eta = f.eta_it;
    double scale = f.eta_ti * f.eta_ti / prob;
    for (int c = 0; c < C; ++c) weight[c] = T[c] * scale;
    return s;
}

std::shared_ptr<const BSDF> SmoothInterface::with_film_lookup(double thickness_nm,
                                                              FilmLookupStats &stats) const {
    auto lookup = film_lookup_for(term_, thickness_nm, stats);
    return lookup ? std::make_shared<SmoothInterface>(wavelengths_, lookup, two_sided_) : nullptr;
}

} // namespace bsdflab
