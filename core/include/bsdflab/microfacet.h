// Isotropic GGX (Trowbridge-Reitz) microfacet distribution with the separable Smith
// shadowing-masking term (as Mitsuba's default) and visible-normal sampling (Heitz 2018).
// Microfacet normals m lie in the upper hemisphere; directions use the local frame.
#pragma once
#include "vector.h"

namespace bsdflab {

class GGX {
public:
    explicit GGX(double alpha) : alpha_(alpha) {}
    double alpha() const { return alpha_; }
    // Normal distribution D(m), normalised so that the integral of D(m) cos(theta_m) is 1.
    double D(const Vec3 &m) const;
    // Smith's masking for direction v seen through microfacet m (0 on the wrong side).
    double G1(const Vec3 &v, const Vec3 &m) const;
    double G(const Vec3 &wi, const Vec3 &wo, const Vec3 &m) const { return G1(wi, m) * G1(wo, m); }
    // Density of sample_visible(): G1(v, m) |v.m| D(m) / |v.z|, for v with v.z > 0.
    double pdf_visible(const Vec3 &v, const Vec3 &m) const;
    // A normal visible from v (v.z > 0) with density pdf_visible.
    Vec3 sample_visible(const Vec3 &v, double u1, double u2) const;

private:
    double alpha_;
};

} // namespace bsdflab
