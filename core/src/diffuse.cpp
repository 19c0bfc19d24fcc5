#include "bsdflab/basic_bsdfs.h"
#include "bsdflab/frame.h"
#include "bsdflab/sampling.h"

namespace bsdflab {

Diffuse::Diffuse(std::vector<double> wavelengths, std::vector<double> reflectance, bool two_sided)
    : BSDF(std::move(wavelengths)), reflectance_(std::move(reflectance)), two_sided_(two_sided) {
    reflectance_.resize(wavelengths_.size(), 0.0);
}

// Maps a configuration to the upper hemisphere when two-sided; false if not reflective.
static bool upper_pair(Vec3 &wi, Vec3 &wo, bool two_sided) {
    if (two_sided && wi.z < 0) {
        wi.z = -wi.z;
        wo.z = -wo.z;
    }
    return wi.z > 0 && wo.z > 0;
}

void Diffuse::eval(const Vec3 &wi_, const Vec3 &wo_, uint32_t lobes, const Query &, double *out) const {
    Vec3 wi = wi_, wo = wo_;
    if (!(lobes & kDiffuseReflection) || !usable_direction(wi) || !usable_direction(wo) ||
        !upper_pair(wi, wo, two_sided_)) {
        zero(out);
        return;
    }
    for (int c = 0; c < channels(); ++c) out[c] = reflectance_[c] * kInvPi * wo.z;
}

double Diffuse::pdf(const Vec3 &wi_, const Vec3 &wo_, uint32_t lobes, const Query &) const {
    Vec3 wi = wi_, wo = wo_;
    if (!(lobes & kDiffuseReflection) || !usable_direction(wi) || !usable_direction(wo) ||
        !upper_pair(wi, wo, two_sided_))
        return 0.0;
    return cosine_hemisphere_pdf(wo);
}

BSDFSample Diffuse::sample(const Vec3 &wi, double, double u2x, double u2y, uint32_t lobes, const Query &,
                           double *weight) const {
    BSDFSample s;
    zero(weight);
    if (!(lobes & kDiffuseReflection) || !usable_direction(wi)) return s;
    if (wi.z < 0 && !two_sided_) return s;
    s.wo = square_to_cosine_hemisphere(u2x, u2y);
    s.pdf = cosine_hemisphere_pdf(s.wo);
    if (!(s.pdf > 0)) return BSDFSample{};
    if (wi.z < 0) s.wo.z = -s.wo.z;
    s.lobe = kDiffuseReflection;
    for (int c = 0; c < channels(); ++c) weight[c] = reflectance_[c];
    return s;
}

} // namespace bsdflab
