#include "bsdflab/basic_bsdfs.h"
#include "bsdflab/complex_fresnel.h"
#include "bsdflab/frame.h"

namespace bsdflab {

Conductor::Conductor(std::vector<double> wavelengths, std::vector<double> eta,
                     std::vector<double> k, double ext_ior, bool two_sided)
    : BSDF(std::move(wavelengths)), ext_ior_(ext_ior), two_sided_(two_sided) {
    eta_.resize(wavelengths_.size());
    for (std::size_t c = 0; c < eta_.size(); ++c)
        eta_[c] = {c < eta.size() ? eta[c] : 1.0, c < k.size() ? k[c] : 0.0};
}

double Conductor::reflectance(double cos_theta_i, int channel) const {
    return fresnel_reflectance(cplx(ext_ior_, 0.0), eta_[channel], cos_theta_i);
}

BSDFSample Conductor::sample(const Vec3 &wi, double, double, double, uint32_t lobes,
                             double *weight) const {
    BSDFSample s;
    zero(weight);
    if (!(lobes & kDeltaReflection) || !usable_direction(wi)) return s;
    if (wi.z < 0 && !two_sided_) return s;
    double ci = std::abs(wi.z);
    for (int c = 0; c < channels(); ++c) weight[c] = reflectance(ci, c);
    s.wo = reflect(wi);
    s.pdf = 1.0;
    s.lobe = kDeltaReflection;
    return s;
}

} // namespace bsdflab
