// The Lambertian reflector. The smooth conductor and dielectric are SmoothInterface
// objects with a ConductorTerm / DielectricTerm (interfaces.h).
#pragma once
#include "bsdf.h"

namespace bsdflab {

// Lambertian reflector, f = reflectance / pi. One-sided unless `two_sided`, in which
// case incidence from below is treated as the mirror-image configuration.
class Diffuse final : public BSDF {
  public:
    Diffuse(std::vector<double> wavelengths, std::vector<double> reflectance, bool two_sided);
    uint32_t lobes() const override { return kDiffuseReflection; }
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const override;
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes, const Query &q,
                      double *weight) const override;

  private:
    std::vector<double> reflectance_;
    bool two_sided_;
};

} // namespace bsdflab
