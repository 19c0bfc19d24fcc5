// A pinhole camera with Mitsuba 3's `perspective` conventions, so scenes convert 1:1:
// look-at frame (left = up x dir, true up = dir x left), horizontal field of view, image x
// growing towards -left (to the right), image y downwards, pixel (0, 0) top left.
#pragma once
#include <cmath>
#include <stdexcept>
#include "bsdflab/sampling.h"
#include "bsdflab/vector.h"

namespace bsdflab {

class Camera {
  public:
    Camera() = default;
    Camera(const Vec3 &origin, const Vec3 &target, const Vec3 &up, double fov_x_deg, int width, int height)
        : origin_(origin), width_(width), height_(height) {
        if (width < 1 || height < 1) throw std::invalid_argument("camera: resolution must be >= 1");
        if (!(fov_x_deg > 0 && fov_x_deg < 180))
            throw std::invalid_argument("camera: fov must be in (0, 180)");
        Vec3 d = target - origin;
        double ld = length(d);
        Vec3 left = cross(up, d);
        double ll = length(left);
        if (!(ld > 0) || !(ll > 1e-12 * ld * length(up)) || !all_finite(d))
            throw std::invalid_argument(
                "camera: degenerate look-at (origin == target or up parallel to view)");
        dir_ = d * (1 / ld);
        left_ = left * (1 / ll);
        up_ = cross(dir_, left_);
        tan_half_ = std::tan(0.5 * fov_x_deg * kPi / 180.0);
    }

    int width() const { return width_; }
    int height() const { return height_; }
    const Vec3 &origin() const { return origin_; }

    // Unit direction through film position (x, y) in pixels (continuous, [0, W) x [0, H)).
    Vec3 direction(double x, double y) const {
        double aspect = double(width_) / height_;
        double sx = 1 - 2 * x / width_, sy = (1 - 2 * y / height_) / aspect;
        Vec3 d = left_ * (sx * tan_half_) + up_ * (sy * tan_half_) + dir_;
        return d * (1 / length(d));
    }

  private:
    Vec3 origin_, dir_{0, 0, 1}, left_{1, 0, 0}, up_{0, 1, 0};
    double tan_half_ = 1;
    int width_ = 1, height_ = 1;
};

} // namespace bsdflab
