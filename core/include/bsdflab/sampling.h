// Warps from the unit square to directions, with their solid-angle densities.
#pragma once
#include <cmath>
#include "constants.h"
#include "vector.h"

namespace bsdflab {

// Concentric (Shirley-Chiu) map of the square to the unit disk, then lifted to the
// hemisphere: density cos(theta) / pi.
Vec3 square_to_cosine_hemisphere(double u1, double u2);
inline double cosine_hemisphere_pdf(const Vec3 &w) { return w.z > 0 ? w.z * kInvPi : 0.0; }

// Veach's power heuristic (beta = 2) weight of a strategy with density a against one with
// density b; an infinite a (a delta strategy) takes all the weight.
inline double power_heuristic(double a, double b) {
    if (std::isinf(a)) return 1.0;
    const double a2 = a * a, b2 = b * b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.0;
}

} // namespace bsdflab
