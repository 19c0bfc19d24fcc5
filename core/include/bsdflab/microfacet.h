// Isotropic microfacet distributions -- GGX (Trowbridge-Reitz) and Beckmann -- with the
// separable Smith shadowing-masking term (as Mitsuba's default) and visible-normal
// sampling: GGX by Heitz 2018's projected hemisphere, Beckmann by Heitz & d'Eon 2014's
// slope-space construction (the 1D visible-slope CDF inverted to double precision).
// Microfacet normals m lie in the upper hemisphere; directions use the local frame.
#pragma once
#include "vector.h"

namespace bsdflab {

enum class MicrofacetType { GGX, Beckmann };

class Microfacet {
  public:
    Microfacet(MicrofacetType type, double alpha) : type_(type), alpha_(alpha) {}
    MicrofacetType type() const { return type_; }
    double alpha() const { return alpha_; }
    // Normal distribution D(m), normalised so that the integral of D(m) cos(theta_m) is 1.
    double D(const Vec3 &m) const;
    // Smith's Lambda of a direction (by |v.z|): G1 = 1 / (1 + Lambda); +inf at grazing.
    double Lambda(const Vec3 &v) const;
    // Smith's masking for direction v seen through microfacet m (0 on the wrong side).
    double G1(const Vec3 &v, const Vec3 &m) const;
    double G(const Vec3 &wi, const Vec3 &wo, const Vec3 &m) const { return G1(wi, m) * G1(wo, m); }
    // Density of sample_visible(): G1(v, m) |v.m| D(m) / |v.z|, for v with v.z > 0.
    double pdf_visible(const Vec3 &v, const Vec3 &m) const;
    // A normal visible from v (v.z > 0) with density pdf_visible.
    Vec3 sample_visible(const Vec3 &v, double u1, double u2) const;

  private:
    Vec3 sample_visible_ggx(const Vec3 &v, double u1, double u2) const;
    Vec3 sample_visible_beckmann(const Vec3 &v, double u1, double u2) const;
    MicrofacetType type_;
    double alpha_;
};

// Beckmann's visible slopes in the alpha = 1 configuration (Heitz & d'Eon 2014): the
// slope along the incident azimuth, for cot(theta) of the stretched incident direction
// (+inf at normal incidence), and the independent Gaussian slope across it, both by
// inverting their CDFs at u in (0, 1).
double beckmann_visible_slope(double cot_theta, double u);
double beckmann_cross_slope(double u);

} // namespace bsdflab
