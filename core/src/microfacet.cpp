#include "bsdflab/microfacet.h"
#include <algorithm>
#include <cmath>
#include <limits>
#include "bsdflab/sampling.h"

namespace bsdflab {

namespace {
const double kSqrtPi = std::sqrt(kPi);

// Root of an increasing function f on [lo, hi] (f(lo) <= 0 <= f(hi)) by Newton steps
// that fall back to bisection when they leave the bracket: double precision in ~10 steps.
template <class F> double increasing_root(F f, double lo, double hi, double x) {
    for (int i = 0; i < 200; ++i) {
        double value, slope;
        f(x, value, slope);
        if (value == 0) return x;
        (value < 0 ? lo : hi) = x;
        double next = x - value / slope;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (std::abs(next - x) <= 1e-15 * std::max(1.0, std::abs(x)) || hi - lo <= 0) return next;
        x = next;
    }
    return x;
}

// A start for Newton on the CDF of exp(-s^2) / sqrt(pi): the tail form
// s ~ sqrt(-log(2 u)) (within ~0.3 for u <= 0.5), mirrored above one half.
double gaussian_guess(double u) {
    double t = std::min(u, 1.0 - u);
    double s = std::sqrt(std::max(0.0, -std::log(2.0 * t))) * 0.8;
    return u < 0.5 ? -s : s;
}

// Keep uniforms strictly inside (0, 1): the slopes of 0 and 1 are infinite.
double open_unit(double u) {
    constexpr double eps = std::numeric_limits<double>::epsilon();
    return std::min(std::max(u, eps), 1.0 - eps);
}
} // namespace

double beckmann_cross_slope(double u) {
    // CDF erfc(-s) / 2; the tails hold ~1e-16 beyond |s| = 8.3.
    u = open_unit(u);
    auto f = [u](double s, double &value, double &slope) {
        value = 0.5 * std::erfc(-s) - u;
        slope = std::exp(-s * s) / kSqrtPi;
    };
    return increasing_root(f, -9.0, 9.0, gaussian_guess(u));
}

double beckmann_visible_slope(double cot_theta, double u) {
    if (!(cot_theta < 1e8)) return beckmann_cross_slope(u); // normal incidence: a Gaussian
    u = open_unit(u);
    const double c = std::max(cot_theta, 0.0);
    // Slopes s <= c, density (c - s) exp(-s^2) (the projected area of visible facets):
    // CDF proportional to c sqrt(pi) erfc(-s) + exp(-s^2).
    auto cdf = [c](double s) { return c * kSqrtPi * std::erfc(-s) + std::exp(-s * s); };
    const double total = cdf(c);
    auto f = [&](double s, double &value, double &slope) {
        value = cdf(s) / total - u;
        slope = 2.0 * std::exp(-s * s) * (c - s) / total;
    };
    double lo = std::min(c, 0.0) - 1.0;
    for (int i = 0; i < 8 && cdf(lo) / total > u; ++i) lo -= 2.0; // (1 - u) >= eps: s > -9
    return increasing_root(f, lo, c, std::min(gaussian_guess(u), 0.5 * (lo + c)));
}

double Microfacet::D(const Vec3 &m) const {
    if (m.z <= 0) return 0.0;
    double a2 = alpha_ * alpha_, z2 = m.z * m.z, d;
    if (type_ == MicrofacetType::GGX) {
        double t = z2 * (a2 - 1.0) + 1.0;
        d = a2 / (kPi * t * t);
    } else {
        double tan2 = std::max(0.0, 1.0 - z2) / z2;
        d = std::exp(-tan2 / a2) / (kPi * a2 * z2 * z2);
    }
    return std::isfinite(d) ? d : 0.0;
}

double Microfacet::Lambda(const Vec3 &v) const {
    double z = std::abs(v.z), sin2 = std::max(0.0, v.x * v.x + v.y * v.y);
    if (sin2 == 0) return 0.0;
    if (z == 0) return std::numeric_limits<double>::infinity();
    if (type_ == MicrofacetType::GGX) {
        double a2tan2 = alpha_ * alpha_ * sin2 / (z * z);
        return 0.5 * (std::sqrt(1.0 + a2tan2) - 1.0);
    }
    double a = z / (alpha_ * std::sqrt(sin2)); // 1 / (alpha tan theta)
    if (a > 26.0) return 0.0;                  // exp(-a^2) underflows the double range
    return 0.5 * (std::exp(-a * a) / (a * kSqrtPi) - std::erfc(a));
}

double Microfacet::G1(const Vec3 &v, const Vec3 &m) const {
    // Microfacets facing away from v cannot be seen from v.
    if (dot(v, m) * v.z <= 0) return 0.0;
    return 1.0 / (1.0 + Lambda(v));
}

double Microfacet::pdf_visible(const Vec3 &v, const Vec3 &m) const {
    if (v.z <= 0) return 0.0;
    return G1(v, m) * std::abs(dot(v, m)) * D(m) / v.z;
}

Vec3 Microfacet::sample_visible(const Vec3 &v, double u1, double u2) const {
    return type_ == MicrofacetType::GGX ? sample_visible_ggx(v, u1, u2) : sample_visible_beckmann(v, u1, u2);
}

Vec3 Microfacet::sample_visible_ggx(const Vec3 &v, double u1, double u2) const {
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

Vec3 Microfacet::sample_visible_beckmann(const Vec3 &v, double u1, double u2) const {
    // Stretch to alpha = 1, draw the visible slopes there (u1 along the incident
    // azimuth, u2 across it), rotate to the azimuth, unstretch, and form the normal.
    Vec3 vs{alpha_ * v.x, alpha_ * v.y, v.z};
    vs = vs * (1.0 / length(vs));
    double sin_t = std::sqrt(vs.x * vs.x + vs.y * vs.y);
    double cos_phi = sin_t > 0 ? vs.x / sin_t : 1.0, sin_phi = sin_t > 0 ? vs.y / sin_t : 0.0;
    double cot = sin_t > 0 ? vs.z / sin_t : std::numeric_limits<double>::infinity();
    double sx = beckmann_visible_slope(cot, u1), sy = beckmann_cross_slope(u2);
    double x = alpha_ * (cos_phi * sx - sin_phi * sy), y = alpha_ * (sin_phi * sx + cos_phi * sy);
    Vec3 m{-x, -y, 1.0};
    double l = length(m);
    return std::isfinite(l) ? m * (1.0 / l) : Vec3{0.0, 0.0, 1.0};
}

} // namespace bsdflab
