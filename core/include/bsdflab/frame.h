// Local shading frame conventions, written once:
//   +z is the surface normal; wi and wo both point *away* from the surface;
//   cos(theta) = z; a direction with z < 0 lies below the surface (transmission side).
#pragma once
#include "vector.h"

namespace bsdflab {

inline double cos_theta(const Vec3 &w) { return w.z; }
inline double abs_cos_theta(const Vec3 &w) { return std::abs(w.z); }

// v scaled to unit length; the zero vector stays zero.
inline Vec3 normalized(const Vec3 &v) {
    const double l = length(v);
    return l > 0 ? v * (1 / l) : Vec3{0, 0, 0};
}

// An orthonormal basis (s, t) with s x t = n for a unit n (Duff et al. 2017, branchless).
inline void orthonormal_basis(const Vec3 &n, Vec3 &s, Vec3 &t) {
    const double sign = std::copysign(1.0, n.z), a = -1 / (sign + n.z), b = n.x * n.y * a;
    s = {1 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    t = {b, sign + n.y * n.y * a, -n.y};
}

// Mirror direction about the normal (both directions pointing away).
inline Vec3 reflect(const Vec3 &wi) { return {-wi.x, -wi.y, wi.z}; }

// Refraction through the interface z = 0. `cos_theta_t` is signed (opposite side to wi),
// `eta_ti` is the relative index n_i / n_t of the incident over the transmitted medium.
inline Vec3 refract(const Vec3 &wi, double cos_theta_t, double eta_ti) {
    return {-eta_ti * wi.x, -eta_ti * wi.y, cos_theta_t};
}

// A direction the core can work with: finite, not tangent to the surface, roughly unit.
// Anything else (NaN, inf, zero length, exactly grazing) yields zero contributions.
inline bool usable_direction(const Vec3 &w) {
    if (!all_finite(w) || w.z == 0.0) return false;
    double l2 = dot(w, w);
    return l2 > 0.5 && l2 < 1.5;
}

} // namespace bsdflab
