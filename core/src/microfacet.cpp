#include "bsdflab/microfacet.h"
#include <algorithm>
#include <cmath>
#include "bsdflab/sampling.h"

namespace bsdflab {

double GGX::D(const Vec3 &m) const {
    if (m.z <= 0) return 0.0;
    double a2 = alpha_ * alpha_;
    double t = m.z * m.z * (a2 - 1.0) + 1.0;
    double d = a2 / (kPi * t * t);
    return std::isfinite(d) ? d : 0.0;
}

double GGX::G1(const Vec3 &v, const Vec3 &m) const {
    // Microfacets facing away from v cannot be seen from v.
    if (dot(v, m) * v.z <= 0) return 0.0;
    double z2 = v.z * v.z;
    double tan2 = std::max(0.0, 1.0 - z2) / z2;
    return 2.0 / (1.0 + std::sqrt(1.0 + alpha_ * alpha_ * tan2));
}

double GGX::pdf_visible(const Vec3 &v, const Vec3 &m) const {
    if (v.z <= 0) return 0.0;
    return G1(v, m) * std::abs(dot(v, m)) * D(m) / v.z;
}

Vec3 GGX::sample_visible(const Vec3 &v, double u1, double u2) const {
    // Stretch to the hemisphere configuration, sample a projected disk, unstretch.
    Vec3 vh{alpha_ * v.x, alpha_ * v.y, v.z};
    vh = vh * (1.0 / length(vh));
    double len2 = vh.x * vh.x + vh.y * vh.y;
    Vec3 t1 = len2 > 0 ? Vec3{-vh.y, vh.x, 0.0} * (1.0 / std::sqrt(len2)) : Vec3{1.0, 0.0, 0.0};
    Vec3 t2 = cross(vh, t1);
    double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
    double p1 = r * std::cos(phi), p2 = r * std::sin(phi);
    double s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * std::sqrt(std::max(0.0, 1.0 - p1 * p1)) + s * p2;
    Vec3 nh = t1 * p1 + t2 * p2 + vh * std::sqrt(std::max(0.0, 1.0 - p1 * p1 - p2 * p2));
    Vec3 m{alpha_ * nh.x, alpha_ * nh.y, std::max(0.0, nh.z)};
    double l = length(m);
    return l > 0 ? m * (1.0 / l) : Vec3{0.0, 0.0, 1.0};
}

} // namespace bsdflab
