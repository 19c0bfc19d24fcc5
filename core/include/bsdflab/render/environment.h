// Light from infinitely far away, in linear sRGB: none, constant, or a lat-long map.
//
// Lat-long mapping (Mitsuba 3's, +Y up): a direction d towards the sky has
//   u = atan2(d.x, -d.z) / 2pi (wrapped to [0, 1)),  v = acos(d.y) / pi,
// texel (column i, row j) covers u in [i, i+1)/W and v in [j, j+1)/H. Radiance is the
// bilinear interpolation between texel centres (periodic in u, clamped in v).
//
// Sampling: a texel by a 2D piecewise-constant distribution (rows by their marginal,
// columns within the row), then uniform in (u, v) inside it; solid-angle density
// p(u, v) / (2 pi^2 sin theta). The texel weights are the luminance dilated over each
// texel's 3x3 neighbourhood (so every texel whose bilinear radiance can be non-zero is
// reachable) times sin theta at the row centre, plus a small floor; pdf() is that density
// exactly, so MIS stays unbiased whatever the map.
#pragma once
#include <vector>
#include "bsdflab/render/distribution.h"
#include "bsdflab/vector.h"

namespace bsdflab {

class Environment {
  public:
    Environment() = default; // none
    static Environment constant(const double rgb[3]);
    // rgb: H x W x 3 floats, row-major from the top row (v = 0, +Y); scale multiplies it.
    static Environment latlong(int width, int height, std::vector<float> rgb, double scale);

    bool active() const { return kind_ != Kind::kNone; }

    // Radiance arriving from direction d (unit, pointing from the scene towards the sky).
    void eval(const Vec3 &d, double rgb[3]) const;
    // Solid-angle density of sample() returning d.
    double pdf(const Vec3 &d) const;
    // Both at once: the map coordinates (an atan2 and an acos) are found once.
    void eval_pdf(const Vec3 &d, double rgb[3], double &pdf) const;
    // A direction towards the sky; its density in `pdf` (0 = failed) and, when `rgb` is
    // given, its radiance (read at the sampled map coordinates, no inverse mapping).
    Vec3 sample(double u1, double u2, double &pdf, double *rgb = nullptr) const;

  private:
    enum class Kind { kNone, kConstant, kMap };
    void texel(int i, int j, double rgb[3]) const;
    // Radiance and density at map coordinates (u, v); sin_theta = sin(pi v).
    void eval_uv(double u, double v, double rgb[3]) const;
    double pdf_uv(double u, double v, double sin_theta) const;

    Kind kind_ = Kind::kNone;
    double constant_[3] = {0, 0, 0};
    int width_ = 0, height_ = 0;
    std::vector<float> map_;
    double scale_ = 1.0;
    Distribution1D rows_;
    std::vector<Distribution1D> columns_;
};

} // namespace bsdflab
