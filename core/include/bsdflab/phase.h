// Phase functions of the scattering slabs. Directions are propagation directions of the
// walk; the functions depend only on the cosine between them, so they are reciprocal.
#pragma once
#include "vector.h"

namespace bsdflab {

class PhaseFunction {
  public:
    enum Kind { kIsotropic = 0, kHenyeyGreenstein = 1, kVonMisesFisher = 2 };
    PhaseFunction() = default;
    PhaseFunction(Kind kind, double parameter) : kind_(kind), param_(parameter) {}
    // Density over the sphere of scattering from propagation direction w into w2.
    double eval(const Vec3 &w, const Vec3 &w2) const;
    // A new propagation direction with density eval(w, .); the weight is exactly 1.
    Vec3 sample(const Vec3 &w, double u1, double u2) const;

  private:
    double eval_cos(double cos_theta) const;
    double sample_cos(double u) const;
    Kind kind_ = kIsotropic;
    double param_ = 0.0; // g for Henyey-Greenstein, kappa for von Mises-Fisher
};

} // namespace bsdflab
