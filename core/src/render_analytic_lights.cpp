// Point, spot and directional lights (render/lights.h): construction checks, sampling from
// a reference point and the radiance a ray escaping to infinity finds in a soft sun's cone.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include "bsdflab/frame.h"
#include "bsdflab/render/lights.h"
#include "bsdflab/sampling.h"

namespace bsdflab {

namespace {
// 1 - cos(half angle) below which a soft sun is a delta light: keeps its density (~1e99) and
// that squared finite (the cone's half angle is then ~1e-50 rad, far below any scene's detail).
constexpr double kMinConeOneMinusCos = 1e-100;

void check_colour(const double v[3], const char *what) {
    for (int c = 0; c < 3; ++c)
        if (!(std::isfinite(v[c]) && v[c] >= 0))
            throw std::invalid_argument(std::string("light: ") + what + " must be finite and >= 0");
}

Vec3 unit_axis(const Vec3 &v, const char *what) {
    const double l = length(v);
    if (!all_finite(v) || !(l > 0) || !std::isfinite(l))
        throw std::invalid_argument(std::string("light: ") + what + " must be a finite, non-zero vector");
    return v * (1 / l);
}
} // namespace

AnalyticLight AnalyticLight::point(const Vec3 &position, const double intensity[3]) {
    if (!all_finite(position)) throw std::invalid_argument("light: position must be finite");
    check_colour(intensity, "intensity");
    AnalyticLight l;
    l.kind_ = Kind::kPoint;
    l.position_ = position;
    std::copy(intensity, intensity + 3, l.value_);
    return l;
}

AnalyticLight AnalyticLight::spot(const Vec3 &position, const Vec3 &axis, const double intensity[3],
                                  double cutoff, double beam_width) {
    AnalyticLight l = point(position, intensity);
    if (!(cutoff > 0 && cutoff <= 0.5 * kPi))
        throw std::invalid_argument("light: cutoff angle must be in (0, 90] deg");
    if (!(beam_width > 0 && beam_width <= cutoff))
        throw std::invalid_argument("light: beam width must be in (0, cutoff angle]");
    l.kind_ = Kind::kSpot;
    l.axis_ = unit_axis(axis, "direction");
    l.cutoff_ = cutoff;
    l.beam_ = beam_width;
    l.cos_cutoff_ = std::cos(cutoff);
    l.cos_beam_ = std::cos(beam_width);
    return l;
}

AnalyticLight AnalyticLight::directional(const Vec3 &axis, const double irradiance[3], double half_angle) {
    check_colour(irradiance, "irradiance");
    if (!(half_angle >= 0 && half_angle < 0.5 * kPi))
        throw std::invalid_argument("light: angular diameter must be in [0, 180) deg");
    AnalyticLight l;
    l.kind_ = Kind::kDirectional;
    l.axis_ = unit_axis(axis, "direction");
    std::copy(irradiance, irradiance + 3, l.value_);
    const double s = std::sin(0.5 * half_angle), sin_max = std::sin(half_angle);
    // A cone so narrow that its density 1 / (2 pi (1 - cos)) would overflow when MIS squares
    // it (or be infinite) is the sharp light it cannot be told from.
    if (2 * s * s >= kMinConeOneMinusCos) {
        l.half_angle_ = half_angle;
        l.one_minus_cos_ = 2 * s * s;
        l.cone_factor_ = 1 / (kPi * sin_max * sin_max);
    }
    return l;
}

double AnalyticLight::falloff(double cos_theta) const {
    if (kind_ != Kind::kSpot) return 1.0;
    if (!(cos_theta > cos_cutoff_)) return 0.0;
    if (cos_theta >= cos_beam_) return 1.0;
    const double f = (cutoff_ - std::acos(std::min(cos_theta, 1.0))) / (cutoff_ - beam_);
    return std::clamp(f, 0.0, 1.0);
}

bool AnalyticLight::sample(const Vec3 &ref, double u1, double u2, Vec3 &wo, double &dist, double &pdf,
                           double rgb[3], double &factor) const {
    if (kind_ == Kind::kDirectional) {
        dist = std::numeric_limits<double>::infinity();
        if (half_angle_ == 0) {
            wo = -axis_;
            pdf = 1.0;
            factor = 1.0;
            std::copy(value_, value_ + 3, rgb);
            return true;
        }
        // Uniform in the cone about -axis: cos theta uniform in [cos max, 1].
        const double t = u1 * one_minus_cos_, cos_t = 1 - t, sin_t = std::sqrt(std::max(0.0, t * (2 - t)));
        const double phi = 2 * kPi * u2;
        Vec3 s, b;
        const Vec3 n = -axis_;
        orthonormal_basis(n, s, b);
        wo = normalized(s * (sin_t * std::cos(phi)) + b * (sin_t * std::sin(phi)) + n * cos_t);
        pdf = 1 / (2 * kPi * one_minus_cos_);
        factor = cone_factor_;
        for (int c = 0; c < 3; ++c) rgb[c] = value_[c] * factor;
        return true;
    }
    const Vec3 to = position_ - ref;
    const double d2 = dot(to, to);
    if (!(d2 > 0) || !std::isfinite(d2)) return false;
    dist = std::sqrt(d2);
    wo = to * (1 / dist);
    const double f = falloff(-dot(wo, axis_));
    if (!(f > 0)) return false;
    pdf = 1.0;
    factor = f / d2;
    for (int c = 0; c < 3; ++c) rgb[c] = value_[c] * factor;
    return true;
}

bool AnalyticLight::eval_direction(const Vec3 &d, double rgb[3], double &pdf, double &factor) const {
    if (delta() || !all_finite(d)) return false;
    // 1 - cos, from the chord |d + axis|^2 = 2 (1 - cos): exact for tiny cones.
    const Vec3 chord = d + axis_;
    if (!(0.5 * dot(chord, chord) <= one_minus_cos_)) return false;
    factor = cone_factor_;
    for (int c = 0; c < 3; ++c) rgb[c] = value_[c] * factor;
    pdf = 1 / (2 * kPi * one_minus_cos_);
    return true;
}

} // namespace bsdflab
