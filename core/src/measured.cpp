// The RGL measured material: Warp2D (continuous marginal/conditional warp of a bilinear
// density, after Mitsuba 3's Marginal2D<..., Continuous = true>) and MeasuredBSDF.
// See core/include/bsdflab/measured.h.
#include "bsdflab/measured.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/constants.h"

namespace bsdflab {

namespace {
constexpr double kEps = 5.9604644775390625e-08; // float32 epsilon / 2, as Mitsuba clips samples

double theta2u(double t) { return std::sqrt(std::max(t, 0.0) * (2.0 / kPi)); }
double u2theta(double u) { return u * u * (kPi / 2.0); }
double phi2u(double p) { return (p + kPi) / (2.0 * kPi); }
double u2phi(double u) { return (2.0 * u - 1.0) * kPi; }
// theta of a unit vector, accurate near the pole
double elevation(const Vec3 &d) {
    double dist = std::sqrt(d.x * d.x + d.y * d.y + (d.z - 1.0) * (d.z - 1.0));
    return 2.0 * std::asin(std::clamp(0.5 * dist, -1.0, 1.0));
}
double lerp(double a, double b, double t) { return a + (b - a) * t; }

// d / |d| in `out`; false for NaN, infinite, zero or overflowing vectors. The readers'
// angle maps (elevation, the Rusinkiewicz rotations) assume unit vectors, and the core's
// callers (the renderer) do not check them as the Python API does.
bool unit_direction(const Vec3 &d, Vec3 &out) {
    if (!all_finite(d)) return false;
    double len = length(d);
    if (!(len > 0) || !std::isfinite(len)) return false;
    out = d * (1.0 / len);
    return true;
}
} // namespace

Warp2D::Warp2D(const std::vector<float> &data, int w, int h, std::vector<std::vector<double>> params,
               bool normalize)
    : w_(w), h_(h), normalized_(normalize), params_(std::move(params)) {
    if (w < 2 || h < 2) throw std::invalid_argument("Warp2D: the grid must be at least 2 x 2");
    if (params_.size() > kMaxParams) throw std::invalid_argument("Warp2D: at most 3 parameters");
    std::size_t slices = 1;
    strides_.assign(params_.size(), 0);
    for (int i = int(params_.size()) - 1; i >= 0; --i) {
        if (params_[i].empty()) throw std::invalid_argument("Warp2D: a parameter has no nodes");
        strides_[i] = params_[i].size() > 1 ? slices : 0;
        slices *= params_[i].size();
    }
    const std::size_t nd = std::size_t(w) * h, nc = std::size_t(h) * (w - 1), nm = h - 1;
    if (data.size() != slices * nd) throw std::invalid_argument("Warp2D: data size does not match the shape");
    data_.resize(slices * nd);
    cond_.resize(slices * nc);
    marg_.resize(slices * nm);
    const double sx = 0.5 / (w - 1), sy = 0.5 / (h - 1);
    std::vector<double> cond(nc), row_total(h);
    for (std::size_t s = 0; s < slices; ++s) {
        const float *d = data.data() + s * nd;
        for (int y = 0; y < h; ++y) {
            double acc = 0.0;
            for (int x = 0; x < w - 1; ++x) {
                acc += sx * (double(d[y * w + x]) + double(d[y * w + x + 1]));
                cond[std::size_t(y) * (w - 1) + x] = acc;
            }
            row_total[y] = acc;
        }
        std::vector<double> marg(nm);
        double acc = 0.0;
        for (int y = 0; y < h - 1; ++y) {
            acc += sy * (row_total[y] + row_total[y + 1]);
            marg[y] = acc;
        }
        float norm = 1.0f;
        if (normalize) {
            double n = 1.0 / acc;
            norm = std::isfinite(n) ? float(n) : 0.0f;
        }
        for (std::size_t i = 0; i < nd; ++i) data_[s * nd + i] = d[i] * norm;
        for (std::size_t i = 0; i < nc; ++i) cond_[s * nc + i] = float(cond[i]) * norm;
        for (std::size_t i = 0; i < nm; ++i) marg_[s * nm + i] = float(marg[i]) * norm;
    }
}

Warp2D::Corners Warp2D::corners(const double *param) const {
    Corners c;
    c.slice[0] = 0;
    c.weight[0] = 1.0;
    for (std::size_t dim = 0; dim < params_.size(); ++dim) {
        const auto &v = params_[dim];
        if (v.size() == 1) continue;
        double p = param[dim];
        // the last node below p (clamped to the first interval / last interval)
        std::size_t idx = std::size_t(std::lower_bound(v.begin(), v.end(), p) - v.begin());
        idx = std::min(idx == 0 ? 0 : idx - 1, v.size() - 2);
        double w1 = (p - v[idx]) / (v[idx + 1] - v[idx]);
        w1 = std::isfinite(w1) ? std::clamp(w1, 0.0, 1.0) : 0.0;
        for (int k = 0; k < c.n; ++k) {
            c.slice[c.n + k] = c.slice[k] + (idx + 1) * strides_[dim];
            c.weight[c.n + k] = c.weight[k] * w1;
            c.slice[k] += idx * strides_[dim];
            c.weight[k] *= 1.0 - w1;
        }
        c.n *= 2;
    }
    return c;
}

double Warp2D::at(const std::vector<float> &t, std::size_t per_slice, const Corners &c, std::size_t i) const {
    double v = 0.0;
    for (int k = 0; k < c.n; ++k) v += c.weight[k] * double(t[c.slice[k] * per_slice + i]);
    return v;
}

double Warp2D::eval(double x, double y, const double *param) const {
    Corners c = corners(param);
    const std::size_t nd = std::size_t(w_) * h_;
    x = std::clamp(x, 0.0, 1.0) * (w_ - 1);
    y = std::clamp(y, 0.0, 1.0) * (h_ - 1);
    int ix = std::min(int(x), w_ - 2), iy = std::min(int(y), h_ - 2);
    x -= ix;
    y -= iy;
    std::size_t i = std::size_t(iy) * w_ + ix;
    double v00 = at(data_, nd, c, i), v10 = at(data_, nd, c, i + 1), v01 = at(data_, nd, c, i + w_),
           v11 = at(data_, nd, c, i + w_ + 1);
    return lerp(lerp(v00, v10, x), lerp(v01, v11, x), y);
}

double Warp2D::segment(double u, double inv_width, double v0, double v1) const {
    bool non_const = std::abs(v0 - v1) > 1e-4 * (v0 + v1);
    double s = u * 2.0 * inv_width;
    double t =
        non_const ? (v0 - std::sqrt(std::max(v0 * v0 + s * (v1 - v0), 0.0))) / (v0 - v1) : s / (v0 + v1);
    return std::isfinite(t) ? t : 0.0;
}

double Warp2D::sample(double ux, double uy, const double *param, double &x, double &y) const {
    Corners c = corners(param);
    const std::size_t nd = std::size_t(w_) * h_, nc = std::size_t(h_) * (w_ - 1), nm = h_ - 1;
    ux = std::clamp(ux, kEps, 1.0 - kEps);
    uy = std::clamp(uy, kEps, 1.0 - kEps);
    if (!normalized_) uy *= at(marg_, nm, c, nm - 1);
    int row = 0;
    while (row < h_ - 2 && at(marg_, nm, c, row) < uy) ++row; // h is small (<= a few hundred)
    if (row > 0) uy -= at(marg_, nm, c, row - 1);
    const std::size_t r = std::size_t(row) * (w_ - 1);
    double r0 = at(cond_, nc, c, r + w_ - 2), r1 = at(cond_, nc, c, r + 2 * (w_ - 1) - 1);
    double ty = segment(uy, h_ - 1, r0, r1);
    ux *= lerp(r0, r1, ty);
    auto cdf = [&](int k) { return lerp(at(cond_, nc, c, r + k), at(cond_, nc, c, r + (w_ - 1) + k), ty); };
    // binary search over the blended conditional CDF
    int lo = 0, hi = w_ - 2;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (cdf(mid) < ux) lo = mid + 1;
        else hi = mid;
    }
    int col = lo;
    if (col > 0) ux -= cdf(col - 1);
    const std::size_t i = std::size_t(row) * w_ + col;
    double v00 = at(data_, nd, c, i), v10 = at(data_, nd, c, i + 1), v01 = at(data_, nd, c, i + w_),
           v11 = at(data_, nd, c, i + w_ + 1);
    double c0 = lerp(v00, v01, ty), c1 = lerp(v10, v11, ty);
    double tx = segment(ux, w_ - 1, c0, c1);
    x = (col + tx) / (w_ - 1);
    y = (row + ty) / (h_ - 1);
    return lerp(c0, c1, tx);
}

double Warp2D::invert(double x, double y, const double *param, double &ux, double &uy) const {
    Corners c = corners(param);
    const std::size_t nd = std::size_t(w_) * h_, nc = std::size_t(h_) * (w_ - 1), nm = h_ - 1;
    x = std::clamp(x, 0.0, 1.0) * (w_ - 1);
    y = std::clamp(y, 0.0, 1.0) * (h_ - 1);
    int ix = std::min(int(x), w_ - 2), iy = std::min(int(y), h_ - 2);
    double fx = x - ix, fy = y - iy;
    const std::size_t i = std::size_t(iy) * w_ + ix;
    double v00 = at(data_, nd, c, i), v10 = at(data_, nd, c, i + 1), v01 = at(data_, nd, c, i + w_),
           v11 = at(data_, nd, c, i + w_ + 1);
    double c0 = lerp(v00, v01, fy), c1 = lerp(v10, v11, fy), pdf = lerp(c0, c1, fx);
    const std::size_t r = std::size_t(iy) * (w_ - 1);
    ux = fx * lerp(c0, c1, 0.5 * fx) / (w_ - 1);
    if (ix > 0) ux += lerp(at(cond_, nc, c, r + ix - 1), at(cond_, nc, c, r + (w_ - 1) + ix - 1), fy);
    double r0 = at(cond_, nc, c, r + w_ - 2), r1 = at(cond_, nc, c, r + 2 * (w_ - 1) - 1);
    ux /= lerp(r0, r1, fy);
    uy = fy * lerp(r0, r1, 0.5 * fy) / (h_ - 1);
    if (iy > 0) uy += at(marg_, nm, c, iy - 1);
    if (!normalized_) uy /= at(marg_, nm, c, nm - 1);
    if (!std::isfinite(ux)) ux = 0.0;
    if (!std::isfinite(uy)) uy = 0.0;
    return pdf;
}

MeasuredBSDF::MeasuredBSDF(std::vector<double> channel_ids, const MeasuredArrays &a)
    : BSDF(std::move(channel_ids)), jacobian_(a.jacobian), ndf_(a.ndf, a.ndf_w, a.ndf_h, {}, false),
      sigma_(a.sigma, a.sigma_w, a.sigma_h, {}, false),
      vndf_(a.vndf, a.vndf_w, a.vndf_h, {a.phi_i, a.theta_i}, true),
      luminance_(a.luminance, a.n, a.n, {a.phi_i, a.theta_i}, true),
      values_(a.values, a.n, a.n, {a.phi_i, a.theta_i, a.channel_nodes}, false) {}

void MeasuredBSDF::values(double sx, double sy, const double *param, double ux_m, double uy_m, double ux_i,
                          double uy_i, double *out) const {
    double scale = 1.0;
    if (jacobian_) scale = ndf_.eval(ux_m, uy_m, nullptr) / (4.0 * sigma_.eval(ux_i, uy_i, nullptr));
    for (int c = 0; c < channels(); ++c) {
        double p[3] = {param[0], param[1], wavelengths_[c]};
        out[c] = values_.eval(sx, sy, p) * scale;
    }
}

namespace {
struct Frame {
    Vec3 m;
    double param[2];          // phi_i, theta_i
    double ux_i, uy_i, ux_m, uy_m;
};
bool frame(const Vec3 &wi, const Vec3 &wo, Frame &f) {
    Vec3 h = wi + wo;
    double len = length(h);
    if (!(len > 0) || !std::isfinite(len)) return false;
    f.m = h * (1.0 / len);
    double theta_i = elevation(wi), phi_i = std::atan2(wi.y, wi.x);
    double theta_m = elevation(f.m), phi_m = std::atan2(f.m.y, f.m.x);
    f.param[0] = phi_i;
    f.param[1] = theta_i;
    f.ux_i = theta2u(theta_i);
    f.uy_i = phi2u(phi_i);
    f.ux_m = theta2u(theta_m);
    f.uy_m = phi2u(phi_m - phi_i);
    f.uy_m -= std::floor(f.uy_m);
    return true;
}
double jacobian(double ux_m, const Vec3 &m, const Vec3 &wi) {
    double sin_m = std::sqrt(std::max(1.0 - m.z * m.z, 0.0));
    return std::max(2.0 * kPi * kPi * ux_m * sin_m, 1e-6) * 4.0 * dot(wi, m);
}
} // namespace

void MeasuredBSDF::eval(const Vec3 &wi_, const Vec3 &wo_, uint32_t lobes, const Query &, double *out) const {
    zero(out);
    Frame f;
    Vec3 wi, wo;
    if (!(lobes & kGlossyReflection) || !unit_direction(wi_, wi) || !unit_direction(wo_, wo) || !(wi.z > 0) ||
        !(wo.z > 0) || !frame(wi, wo, f))
        return;
    double sx, sy;
    vndf_.invert(f.ux_m, f.uy_m, f.param, sx, sy);
    values(sx, sy, f.param, f.ux_m, f.uy_m, f.ux_i, f.uy_i, out);
    for (int c = 0; c < channels(); ++c)
        if (!std::isfinite(out[c])) out[c] = 0.0;
}

double MeasuredBSDF::pdf(const Vec3 &wi_, const Vec3 &wo_, uint32_t lobes, const Query &) const {
    Frame f;
    Vec3 wi, wo;
    if (!(lobes & kGlossyReflection) || !unit_direction(wi_, wi) || !unit_direction(wo_, wo) || !(wi.z > 0) ||
        !(wo.z > 0) || !frame(wi, wo, f))
        return 0.0;
    double sx, sy;
    double vndf_pdf = vndf_.invert(f.ux_m, f.uy_m, f.param, sx, sy);
    double p = vndf_pdf * luminance_.eval(sx, sy, f.param) / jacobian(f.ux_m, f.m, wi);
    return std::isfinite(p) && p > 0 ? p : 0.0;
}

BSDFSample MeasuredBSDF::sample(const Vec3 &wi_, double, double u2x, double u2y, uint32_t lobes,
                                const Query &, double *weight) const {
    BSDFSample s;
    zero(weight);
    Vec3 wi;
    if (!(lobes & kGlossyReflection) || !unit_direction(wi_, wi) || !(wi.z > 0)) return s;
    double theta_i = elevation(wi), phi_i = std::atan2(wi.y, wi.x);
    double param[2] = {phi_i, theta_i};
    double sx, sy, ux_m, uy_m;
    double lum_pdf = luminance_.sample(u2y, u2x, param, sx, sy); // Mitsuba's order: (u2.y, u2.x)
    double vndf_pdf = vndf_.sample(sx, sy, param, ux_m, uy_m);
    double theta_m = u2theta(ux_m), phi_m = u2phi(uy_m) + phi_i;
    Vec3 m(std::cos(phi_m) * std::sin(theta_m), std::sin(phi_m) * std::sin(theta_m), std::cos(theta_m));
    double jac = std::max(2.0 * kPi * kPi * ux_m * std::sin(theta_m), 1e-6) * 4.0 * dot(wi, m);
    Vec3 wo = m * (2.0 * dot(m, wi)) - wi;
    double pdf = vndf_pdf * lum_pdf / jac;
    if (!(wo.z > 0) || !(pdf > 0) || !std::isfinite(pdf)) return s;
    values(sx, sy, param, ux_m, uy_m, theta2u(theta_i), phi2u(phi_i), weight);
    for (int c = 0; c < channels(); ++c) {
        weight[c] /= pdf;
        if (!std::isfinite(weight[c])) {
            zero(weight);
            return s;
        }
    }
    s.wo = wo;
    s.pdf = pdf;
    s.lobe = kGlossyReflection;
    s.eta = 1.0;
    return s;
}

} // namespace bsdflab

namespace bsdflab {

namespace {
constexpr int kThetaH = 90, kThetaD = 90, kPhiD = 180;
// Rusinkiewicz's (theta_h, theta_d, phi_d) -> the MERL cell index
std::size_t merl_index(const Vec3 &wi, const Vec3 &wo) {
    Vec3 h = wi + wo;
    h = h * (1.0 / length(h));
    double theta_h = std::acos(std::clamp(h.z, -1.0, 1.0)), phi_h = std::atan2(h.y, h.x);
    double c = std::cos(-phi_h), s = std::sin(-phi_h);
    double x = c * wi.x - s * wi.y, y = s * wi.x + c * wi.y, z = wi.z;
    double ct = std::cos(-theta_h), st = std::sin(-theta_h);
    double dx = ct * x + st * z, dz = -st * x + ct * z;
    double theta_d = std::acos(std::clamp(dz, -1.0, 1.0)), phi_d = std::atan2(y, dx);
    if (phi_d < 0) phi_d += kPi;
    int ih = std::clamp(int(std::sqrt(std::clamp(theta_h / (kPi / 2), 0.0, 1.0)) * kThetaH), 0, kThetaH - 1);
    int id = std::clamp(int(theta_d / (kPi / 2) * kThetaD), 0, kThetaD - 1);
    int ip = std::clamp(int(phi_d / kPi * kPhiD), 0, kPhiD - 1);
    return (std::size_t(ih) * kThetaD + id) * kPhiD + ip;
}
} // namespace

MerlBSDF::MerlBSDF(std::vector<float> values) : BSDF({0.0, 1.0, 2.0}), values_(std::move(values)) {
    if (values_.size() != std::size_t(3) * kThetaH * kThetaD * kPhiD)
        throw std::invalid_argument("MerlBSDF: values must hold 3 x 90 x 90 x 180 entries");
}

void MerlBSDF::eval(const Vec3 &wi_, const Vec3 &wo_, uint32_t lobes, const Query &, double *out) const {
    zero(out);
    Vec3 wi, wo;
    if (!(lobes & kGlossyReflection) || !unit_direction(wi_, wi) || !unit_direction(wo_, wo) || !(wi.z > 0) ||
        !(wo.z > 0))
        return;
    const std::size_t i = merl_index(wi, wo), n = std::size_t(kThetaH) * kThetaD * kPhiD;
    for (int c = 0; c < 3; ++c) out[c] = double(values_[c * n + i]) * wo.z;
}

double MerlBSDF::pdf(const Vec3 &wi_, const Vec3 &wo_, uint32_t lobes, const Query &) const {
    Vec3 wi, wo;
    if (!(lobes & kGlossyReflection) || !unit_direction(wi_, wi) || !unit_direction(wo_, wo) || !(wi.z > 0) ||
        !(wo.z > 0))
        return 0.0;
    return wo.z / kPi;
}

BSDFSample MerlBSDF::sample(const Vec3 &wi, double, double u2x, double u2y, uint32_t lobes, const Query &q,
                            double *weight) const {
    BSDFSample s;
    zero(weight);
    Vec3 unit;
    if (!(lobes & kGlossyReflection) || !unit_direction(wi, unit) || !(unit.z > 0)) return s;
    double r = std::sqrt(u2x), phi = 2.0 * kPi * u2y;
    Vec3 wo(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(1.0 - u2x, 0.0)));
    double p = pdf(wi, wo, lobes, q);
    if (!(p > 0)) return s;
    eval(wi, wo, lobes, q, weight);
    for (int c = 0; c < 3; ++c) weight[c] /= p;
    s.wo = wo;
    s.pdf = p;
    s.lobe = kGlossyReflection;
    return s;
}

} // namespace bsdflab
