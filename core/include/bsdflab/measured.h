// An RGL measured material (Dupuy & Jakob 2018, "An Adaptive Parameterization for
// Efficient Material Acquisition and Representation"; the layout Mitsuba 3's `measured`
// plugin reads): an isotropic, one-sided glossy reflection stored as a warp plus values.
//
// Warp2D is the continuous marginal/conditional warp of a bilinear density on [0, 1]^2
// whose grid depends on up to three parameters (blended linearly between parameter
// nodes, clamped at the ends). MeasuredBSDF (see docs/measured.md):
//   eval  = values(s; phi_i, theta_i, lambda) * D(u_m) / (4 sigma(u_wi))   [jacobian files]
//           with s = VNDF^-1(u_m; phi_i, theta_i), u = (sqrt(2 theta / pi), (phi + pi) / 2 pi)
//   pdf   = vndf(u_m) * luminance(s) / (2 pi^2 u_m.x sin(theta_m) * 4 (wi . m))
//   sample: luminance warp of (u2y, u2x) -> s, VNDF warp -> u_m -> m, reflect wi.
// bsdflab/measured/rgl_reference.py is the numpy statement of the same arithmetic.
// Immutable after construction, so safe to share between threads.
#pragma once
#include <array>
#include <cstddef>
#include <vector>
#include "bsdf.h"

namespace bsdflab {

class Warp2D {
  public:
    static constexpr int kMaxParams = 3;
    Warp2D() = default;
    // data: (*param nodes, h, w) row-major; params: the node positions of each parameter.
    Warp2D(const std::vector<float> &data, int w, int h, std::vector<std::vector<double>> params,
           bool normalize);
    // The interpolated value (a density when normalised) at (x, y).
    double eval(double x, double y, const double *param) const;
    // Uniforms -> point; returns the density there.
    double sample(double ux, double uy, const double *param, double &x, double &y) const;
    // Point -> uniforms (the inverse of sample); returns the density at the point.
    double invert(double x, double y, const double *param, double &ux, double &uy) const;

  private:
    struct Corners {
        int n = 1;
        std::array<std::size_t, 8> slice{};
        std::array<double, 8> weight{};
    };
    Corners corners(const double *param) const;
    double at(const std::vector<float> &t, std::size_t per_slice, const Corners &c, std::size_t i) const;
    double segment(double u, double inv_width, double v0, double v1) const;

    int w_ = 0, h_ = 0;
    bool normalized_ = true;
    std::vector<std::vector<double>> params_;
    std::vector<std::size_t> strides_;
    std::vector<float> data_, cond_, marg_; // per slice: h*w, h*(w-1), h-1
};

struct MeasuredArrays {
    bool jacobian = true;
    std::vector<double> theta_i, phi_i, channel_nodes; // rad, rad, nm (or 0, 1, 2 for RGB)
    std::vector<float> ndf, sigma, vndf, luminance, values;
    int ndf_w = 0, ndf_h = 0, sigma_w = 0, sigma_h = 0, vndf_w = 0, vndf_h = 0, n = 0;
};

class MeasuredBSDF final : public BSDF {
  public:
    // channel_ids: what each output channel is (wavelengths in nm, or 0, 1, 2 for RGB files),
    // looked up linearly between a.channel_nodes.
    MeasuredBSDF(std::vector<double> channel_ids, const MeasuredArrays &a);
    uint32_t lobes() const override { return kGlossyReflection; }
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const override;
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes, const Query &q,
                      double *weight) const override;

  private:
    void values(double sx, double sy, const double *param, double ux_m, double uy_m, double ux_i, double uy_i,
                double *out) const;
    bool jacobian_;
    Warp2D ndf_, sigma_, vndf_, luminance_, values_;
};

// A MERL database BRDF (Matusik et al. 2003): f in 1/sr, RGB, on 90 theta_h (square-root
// spacing) x 90 theta_d x 180 phi_d cells of Rusinkiewicz's half/difference angles,
// nearest-cell lookup as the dataset's reader; cosine-weighted sampling.
class MerlBSDF final : public BSDF {
  public:
    // values: 3 x 90 x 90 x 180, scales applied, negatives already zeroed
    explicit MerlBSDF(std::vector<float> values);
    uint32_t lobes() const override { return kGlossyReflection; }
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const override;
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes, const Query &q,
                      double *weight) const override;

  private:
    std::vector<float> values_;
};

} // namespace bsdflab
