// Interfaces between an exterior (above, +z) and an interior (below): smooth (delta
// lobes) or rough (GGX microfacets), each with any FresnelTerm: a bare dielectric, a bare
// conductor, or a thin-film stack on either. With several channels (wavelengths) the
// reflect/refract choice uses the channel-mean R and T, and the weights carry each
// channel's own R_c or T_c divided by that probability.
// Transmitted radiance is scaled by (n_i / n_t)^2 (radiance / n^2 is invariant).
#pragma once
#include <memory>
#include "bsdf.h"
#include "fresnel_terms.h"
#include "microfacet.h"

namespace bsdflab {

class SmoothInterface final : public BSDF {
public:
    SmoothInterface(std::vector<double> wavelengths, std::shared_ptr<const FresnelTerm> term,
                    bool two_sided);
    uint32_t lobes() const override;
    void eval(const Vec3 &, const Vec3 &, uint32_t, const Query &, double *out) const override {
        zero(out);
    }
    double pdf(const Vec3 &, const Vec3 &, uint32_t, const Query &) const override { return 0.0; }
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                      const Query &q, double *weight) const override;

private:
    std::shared_ptr<const FresnelTerm> term_;
    bool two_sided_; // opaque terms only: reflect from below too
};

class RoughInterface final : public BSDF {
public:
    RoughInterface(std::vector<double> wavelengths, std::shared_ptr<const FresnelTerm> term,
                   double alpha, bool two_sided);
    uint32_t lobes() const override;
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
              double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const override;
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                      const Query &q, double *weight) const override;

private:
    // The half vector of a configuration (upper hemisphere) and whether it reflects.
    bool half_vector(const Vec3 &wi, const Vec3 &wo, Vec3 &m, bool &reflect, double &eta_rel) const;
    // Probability of picking reflection at microfacet cosine cos_im, from mean R and T.
    double reflect_probability(const double *R, const double *T, uint32_t lobes) const;

    std::shared_ptr<const FresnelTerm> term_;
    GGX ggx_;
    bool two_sided_;
};

} // namespace bsdflab
