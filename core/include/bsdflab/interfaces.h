// Interfaces between an exterior (above, +z) and an interior (below): smooth (delta
// lobes) or rough (GGX or Beckmann microfacets, optionally energy-compensated), each with any FresnelTerm: a bare dielectric, a bare
// conductor, or a thin-film stack on either. With several channels (wavelengths) the
// reflect/refract choice uses the channel-mean R and T, and the weights carry each
// channel's own R_c or T_c divided by that probability.
// Transmitted radiance is scaled by (n_i / n_t)^2 (radiance / n^2 is invariant).
#pragma once
#include <memory>
#include "bsdf.h"
#include "fresnel_terms.h"
#include "microfacet.h"
#include "rough_multiscatter.h"

namespace bsdflab {

class SmoothInterface final : public BSDF {
  public:
    SmoothInterface(std::vector<double> wavelengths, std::shared_ptr<const FresnelTerm> term, bool two_sided);
    uint32_t lobes() const override;
    void eval(const Vec3 &, const Vec3 &, uint32_t, const Query &, double *out) const override { zero(out); }
    double pdf(const Vec3 &, const Vec3 &, uint32_t, const Query &) const override { return 0.0; }
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes, const Query &q,
                      double *weight) const override;
    std::shared_ptr<const BSDF> with_film_lookup(double thickness_nm, FilmLookupStats &stats) const override;

  private:
    std::shared_ptr<const FresnelTerm> term_;
    bool two_sided_; // opaque terms only: reflect from below too
};

// A rough interface. multiscatter adds the Kulla-Conty energy compensation
// (rough_multiscatter.h), sampled as a mixture with the single-scattering lobe. An
// interface between (almost) equal real indices, |eta - 1| <= kMatchedEta, and no film
// is no interface: it passes light straight through (a smooth index-matched interface);
// its microfacet lobes would be narrower than double precision resolves.
class RoughInterface final : public BSDF {
  public:
    static constexpr double kMatchedEta = 1e-6;

    RoughInterface(std::vector<double> wavelengths, std::shared_ptr<const FresnelTerm> term, double alpha,
                   bool two_sided, MicrofacetType type = MicrofacetType::GGX, bool multiscatter = false);
    uint32_t lobes() const override;
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const override;
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes, const Query &q,
                      double *weight) const override;
    const Microfacet &microfacet() const { return mf_; }
    // The energy compensation, or nullptr for the single-scattering model.
    const MultiScatter *multiscatter() const { return ms_.get(); }
    bool pass_through() const { return matched_ != nullptr; }
    // nullptr with the energy compensation, whose tables are the exact term's.
    std::shared_ptr<const BSDF> with_film_lookup(double thickness_nm, FilmLookupStats &stats) const override;

  private:
    // Folds a one- or two-sided opaque interface's directions to the upper side; false
    // when the pair does not scatter.
    bool fold(Vec3 &wi, Vec3 &wo) const;
    void eval_single(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const;
    double pdf_single(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const;
    BSDFSample sample_single(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                             const Query &q, double *weight) const;
    // The half vector of a configuration (upper hemisphere) and whether it reflects.
    bool half_vector(const Vec3 &wi, const Vec3 &wo, Vec3 &m, bool &reflect, double &eta_rel) const;
    // Probability of picking reflection (reflect) or transmission (!reflect) at a
    // microfacet with reflectance R and transmittance T, among the glossy lobes in
    // `lobes` (channel means); 0 for a lobe the mask excludes.
    double choice_probability(const double *R, const double *T, uint32_t lobes, bool reflect) const;

    std::shared_ptr<const FresnelTerm> term_;
    Microfacet mf_;
    bool two_sided_;
    std::unique_ptr<const MultiScatter> ms_;
    std::unique_ptr<const SmoothInterface> matched_;
};

} // namespace bsdflab
