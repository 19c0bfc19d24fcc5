// A Fresnel term projected to a few output channels (linear sRGB for the renderer) and
// tabulated over (cos theta_i, film thickness), so that a spectral film's reflectance costs
// a bilinear lookup instead of an Airy summation per wavelength at every evaluation.
//
// Since an interface's BSDF is linear in R and T per channel (a grey microfacet factor
// times R_c or T_c), projecting R and T by P (K x C) and then evaluating the interface
// gives exactly P times the spectral evaluation; the only approximation is the bilinear
// interpolation between nodes (uniform in cos theta_i over [0, 1], uniform in thickness
// over [lo, hi]). Queries outside the thickness range are clamped to its ends (as a
// table's thickness axis is). Light from the interior (cos_i <= 0: TIR makes R kinked
// there) is evaluated exactly and projected.
#pragma once
#include <memory>
#include <vector>
#include "fresnel_terms.h"

namespace bsdflab {

class ProjectedFresnelTerm final : public FresnelTerm {
  public:
    // thickness_lo/hi: the film-thickness range (nm) tabulated; lo < 0 means the exact
    // term's own film (one node). default_thickness: used when a query gives none (< 0).
    ProjectedFresnelTerm(std::shared_ptr<const FresnelTerm> exact, std::vector<double> P, int out_channels,
                         double thickness_lo, double thickness_hi, double default_thickness, int n_cos,
                         int n_thickness);
    void eval(double cos_i, const Query &q, double *R, double *T) const override;
    bool transmissive() const override { return exact_->transmissive(); }
    int n_cos() const { return n_cos_; }
    int n_thickness() const { return n_thickness_; }

  private:
    void project(const double *spectral, double *out) const;

    std::shared_ptr<const FresnelTerm> exact_;
    std::vector<double> P_; // K x C, row-major
    double lo_, hi_, default_;
    int n_cos_, n_thickness_;
    std::vector<float> table_; // [(t * n_cos + c) * 2K + k]: R_k then T_k
};

} // namespace bsdflab
