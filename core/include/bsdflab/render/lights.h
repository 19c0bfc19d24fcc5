// Lights without geometry: point, spot and directional (Mitsuba 3's `point`, `spot` and
// `directional` emitters, with their parameters and units), and a directional light with an
// angular diameter (a soft sun: a cone of directions of constant radiance at infinity).
//
// Point, spot and a directional light of zero diameter are delta lights: no ray can hit
// them, so only next-event estimation finds them and its weight is 1 (no MIS). A soft
// sun has a density over directions: BSDF-sampled rays that leave the scene inside its
// cone see it, and both strategies are combined by MIS like the environment.
//
// Colours are linear sRGB; spectral mode lifts them like any RGB emission.
#pragma once
#include "bsdflab/vector.h"

namespace bsdflab {

struct AnalyticLight {
    enum class Kind : int { kPoint = 0, kSpot = 1, kDirectional = 2 };

    // point: intensity I (W/sr) at `position`, radiance-equivalent I / r^2 at distance r.
    static AnalyticLight point(const Vec3 &position, const double intensity[3]);
    // spot: a point light shining along `axis` with Mitsuba 3's falloff: I inside
    // beam_width, linear in the angle from I at beam_width to 0 at cutoff (radians,
    // 0 < beam_width <= cutoff <= pi/2).
    static AnalyticLight spot(const Vec3 &position, const Vec3 &axis, const double intensity[3],
                              double cutoff, double beam_width);
    // directional: irradiance E on a surface facing the light; light travels along `axis`.
    // half_angle > 0 (radians, < pi/2) spreads it over a cone of that half angle about -axis
    // with constant radiance E / (pi sin^2 half_angle); a cone too narrow for its density to
    // be represented (1 - cos < 1e-100) is the sharp light.
    static AnalyticLight directional(const Vec3 &axis, const double irradiance[3], double half_angle);

    Kind kind() const { return kind_; }
    bool delta() const { return kind_ != Kind::kDirectional || half_angle_ == 0.0; }

    // A direction from `ref` towards the light: unit `wo`, the distance (infinity for
    // directional lights), the solid-angle density (1 for a delta light: a discrete choice)
    // and the radiance arriving along it (for a delta light: what replaces it in the
    // estimator, I falloff / r^2 or E) as `factor` times the light's colour: rgb = factor
    // x colour (a spectral colour scales by the same factor). False when the light sends
    // nothing to `ref`.
    bool sample(const Vec3 &ref, double u1, double u2, Vec3 &wo, double &dist, double &pdf, double rgb[3],
                double &factor) const;
    // A ray leaving the scene in direction d (unit): the radiance it finds (rgb = factor x
    // colour) and sample()'s density of d. Non-zero only for soft suns, inside their cone.
    bool eval_direction(const Vec3 &d, double rgb[3], double &pdf, double &factor) const;

    // Mitsuba's spot profile at cos(angle from the axis), in [0, 1].
    double falloff(double cos_theta) const;

  private:
    Kind kind_ = Kind::kPoint;
    Vec3 position_, axis_;
    double value_[3] = {0, 0, 0}; // intensity, or irradiance
    double cutoff_ = 0, beam_ = 0, cos_cutoff_ = 0, cos_beam_ = 0;
    double half_angle_ = 0, one_minus_cos_ = 0; // 1 - cos(half_angle), kept exactly for small cones
    double cone_factor_ = 0; // radiance / irradiance of a soft sun: 1 / (pi sin^2 half_angle)
};

} // namespace bsdflab
