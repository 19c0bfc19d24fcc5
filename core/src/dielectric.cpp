#include "bsdflab/basic_bsdfs.h"
#include "bsdflab/complex_fresnel.h"
#include "bsdflab/frame.h"

namespace bsdflab {

Dielectric::Dielectric(std::vector<double> wavelengths, double int_ior, double ext_ior)
    : BSDF(std::move(wavelengths)), eta_(int_ior / ext_ior) {}

BSDFSample Dielectric::sample(const Vec3 &wi, double u1, double, double, uint32_t lobes,
                              double *weight) const {
    BSDFSample s;
    zero(weight);
    bool want_r = lobes & kDeltaReflection, want_t = lobes & kDeltaTransmission;
    if (!(want_r || want_t) || !usable_direction(wi)) return s;

    DielectricFresnel f = fresnel_dielectric(wi.z, eta_);
    double R = f.R, T = 1.0 - f.R;
    bool pick_r;
    double value, prob;
    if (want_r && want_t) {
        pick_r = u1 <= R;
        prob = pick_r ? R : T;
        value = prob; // weight = value / prob = 1 before the radiance scaling
    } else {
        pick_r = want_r;
        prob = 1.0;
        value = pick_r ? R : T;
    }
    if (!(value > 0)) return s;

    if (pick_r) {
        s.wo = reflect(wi);
        s.lobe = kDeltaReflection;
        s.eta = 1.0;
    } else {
        s.wo = refract(wi, f.cos_theta_t, f.eta_ti);
        s.lobe = kDeltaTransmission;
        s.eta = f.eta_it;
    }
    s.pdf = prob;
    // Radiance crossing into a medium of index n_t is compressed into a smaller solid
    // angle: L_t / n_t^2 = L_i / n_i^2, hence the factor (n_i / n_t)^2 = eta_ti^2 here.
    double scale = pick_r ? 1.0 : f.eta_ti * f.eta_ti;
    double w = value / prob * scale;
    for (int c = 0; c < channels(); ++c) weight[c] = w;
    return s;
}

} // namespace bsdflab
