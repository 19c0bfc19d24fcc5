// The basic materials of the seed's appendix A (with its amplitude-averaging error
// corrected: energy goes with |r|^2). Parameters are per channel.
#pragma once
#include <complex>
#include "bsdf.h"

namespace bsdflab {

// Lambertian reflector, f = reflectance / pi. One-sided unless `two_sided`, in which
// case incidence from below is treated as the mirror-image configuration.
class Diffuse final : public BSDF {
public:
    Diffuse(std::vector<double> wavelengths, std::vector<double> reflectance, bool two_sided);
    uint32_t lobes() const override { return kDiffuseReflection; }
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes) const override;
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                      double *weight) const override;

private:
    std::vector<double> reflectance_;
    bool two_sided_;
};

// Smooth conductor: a mirror weighted by the unpolarised Fresnel reflectance of the
// complex index eta + i k (relative to the exterior medium of real index ext_ior).
class Conductor final : public BSDF {
public:
    Conductor(std::vector<double> wavelengths, std::vector<double> eta, std::vector<double> k,
              double ext_ior, bool two_sided);
    uint32_t lobes() const override { return kDeltaReflection; }
    void eval(const Vec3 &, const Vec3 &, uint32_t, double *out) const override { zero(out); }
    double pdf(const Vec3 &, const Vec3 &, uint32_t) const override { return 0.0; }
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                      double *weight) const override;
    double reflectance(double cos_theta_i, int channel) const;

private:
    std::vector<std::complex<double>> eta_; // relative complex index per channel
    double ext_ior_;
    bool two_sided_;
};

// Smooth dielectric interface between an exterior (above, +z) of index ext_ior and an
// interior (below) of index int_ior. Reflection and refraction by Snell's law, exact
// unpolarised Fresnel weights, total internal reflection from inside. Transmitted
// radiance is scaled by (n_i/n_t)^2 (radiance transport: radiance / n^2 is invariant).
class Dielectric final : public BSDF {
public:
    Dielectric(std::vector<double> wavelengths, double int_ior, double ext_ior);
    uint32_t lobes() const override { return kDeltaReflection | kDeltaTransmission; }
    void eval(const Vec3 &, const Vec3 &, uint32_t, double *out) const override { zero(out); }
    double pdf(const Vec3 &, const Vec3 &, uint32_t) const override { return 0.0; }
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                      double *weight) const override;

private:
    double eta_; // int_ior / ext_ior
};

} // namespace bsdflab
