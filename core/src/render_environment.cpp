#include "bsdflab/render/environment.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/sampling.h"
#include "bsdflab/scratch.h"

namespace bsdflab {

namespace {
double luminance(const double rgb[3]) {
    return kLuminanceRGB[0] * rgb[0] + kLuminanceRGB[1] * rgb[1] + kLuminanceRGB[2] * rgb[2];
}

void uv_of(const Vec3 &d, double &u, double &v) {
    u = std::atan2(d.x, -d.z) / (2 * kPi);
    u -= std::floor(u);
    v = std::acos(std::clamp(d.y, -1.0, 1.0)) / kPi;
}
} // namespace

Environment Environment::constant(const double rgb[3]) {
    Environment e;
    e.kind_ = Kind::kConstant;
    for (int c = 0; c < 3; ++c) e.constant_[c] = std::isfinite(rgb[c]) && rgb[c] > 0 ? rgb[c] : 0.0;
    return e;
}

Environment Environment::latlong(int width, int height, std::vector<float> rgb, double scale) {
    if (width < 1 || height < 1 || rgb.size() != std::size_t(width) * height * 3)
        throw std::invalid_argument("environment map: expected an H x W x 3 image");
    if (!(std::isfinite(scale) && scale > 0))
        throw std::invalid_argument("environment map: scale must be > 0");
    Environment e;
    e.kind_ = Kind::kMap;
    e.width_ = width;
    e.height_ = height;
    for (float &x : rgb) x = std::isfinite(x) && x > 0 ? x : 0.0f; // tolerate junk texels
    e.map_ = std::move(rgb);
    e.scale_ = scale;

    std::vector<double> lum(std::size_t(width) * height);
    double mean = 0;
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i) {
            double t[3];
            e.texel(i, j, t);
            mean += lum[std::size_t(j) * width + i] = std::max(luminance(t), 0.0);
        }
    mean /= double(lum.size());
    std::vector<double> row_weights(height);
    e.columns_.resize(height);
    for (int j = 0; j < height; ++j) {
        double sin_theta = std::sin(kPi * (j + 0.5) / height);
        std::vector<double> w(width);
        for (int i = 0; i < width; ++i) {
            double m = 0;
            for (int dj = -1; dj <= 1; ++dj) {
                int jj = std::clamp(j + dj, 0, height - 1);
                for (int di = -1; di <= 1; ++di) {
                    int ii = ((i + di) % width + width) % width;
                    m = std::max(m, lum[std::size_t(jj) * width + ii]);
                }
            }
            w[i] = (m + 1e-3 * mean + 1e-12) * sin_theta;
        }
        double row_total = 0;
        for (double x : w) row_total += x;
        row_weights[j] = row_total;
        e.columns_[j] = Distribution1D(w);
    }
    e.rows_ = Distribution1D(row_weights);
    return e;
}

void Environment::texel(int i, int j, double rgb[3]) const {
    const float *t = &map_[(std::size_t(j) * width_ + i) * 3];
    for (int c = 0; c < 3; ++c) rgb[c] = scale_ * t[c];
}

void Environment::eval_uv(double u, double v, double rgb[3]) const {
    // Bilinear between texel centres: periodic in u, clamped in v.
    const double x = u * width_ - 0.5, y = std::clamp(v * height_ - 0.5, 0.0, height_ - 1.0);
    int i0 = int(std::floor(x)), j0 = int(std::floor(y));
    const double fx = x - i0, fy = y - j0;
    const int j1 = std::min(j0 + 1, height_ - 1);
    // u in [0, 1] puts i0 in [-1, W - 1]: wrap by comparison (integer division is slow).
    if (i0 < 0) i0 += width_;
    else if (i0 >= width_) i0 -= width_;
    i0 = std::clamp(i0, 0, width_ - 1);
    const int i1 = i0 + 1 < width_ ? i0 + 1 : 0;
    double a[3], b[3], c3[3], e3[3];
    texel(i0, j0, a);
    texel(i1, j0, b);
    texel(i0, j1, c3);
    texel(i1, j1, e3);
    for (int c = 0; c < 3; ++c)
        rgb[c] = (1 - fy) * ((1 - fx) * a[c] + fx * b[c]) + fy * ((1 - fx) * c3[c] + fx * e3[c]);
}

double Environment::pdf_uv(double u, double v, double sin_theta) const {
    if (!(sin_theta > 0)) return 0.0;
    const int i = std::min(int(u * width_), width_ - 1), j = std::min(int(v * height_), height_ - 1);
    const double p_uv = rows_.prob(j) * columns_[j].prob(i) * width_ * height_;
    return p_uv / (2 * kPi * kPi * sin_theta);
}

void Environment::eval(const Vec3 &d, double rgb[3]) const {
    double pdf;
    eval_pdf(d, rgb, pdf);
}

double Environment::pdf(const Vec3 &d) const {
    if (kind_ == Kind::kConstant) return 1.0 / (4 * kPi);
    if (kind_ != Kind::kMap || !all_finite(d)) return 0.0;
    double u, v;
    uv_of(d, u, v);
    return pdf_uv(u, v, std::sqrt(std::max(0.0, 1 - d.y * d.y)));
}

void Environment::eval_pdf(const Vec3 &d, double rgb[3], double &pdf) const {
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    pdf = 0.0;
    if (kind_ == Kind::kConstant) {
        for (int c = 0; c < 3; ++c) rgb[c] = constant_[c];
        pdf = 1.0 / (4 * kPi);
        return;
    }
    if (kind_ != Kind::kMap || !all_finite(d)) return;
    double u, v;
    uv_of(d, u, v);
    eval_uv(u, v, rgb);
    pdf = pdf_uv(u, v, std::sqrt(std::max(0.0, 1 - d.y * d.y)));
}

Vec3 Environment::sample(double u1, double u2, double &pdf_out, double *rgb) const {
    pdf_out = 0;
    if (rgb) rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (kind_ == Kind::kConstant) {
        double z = 1 - 2 * u1, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * kPi * u2;
        pdf_out = 1.0 / (4 * kPi);
        if (rgb)
            for (int c = 0; c < 3; ++c) rgb[c] = constant_[c];
        return {r * std::cos(phi), z, r * std::sin(phi)};
    }
    if (kind_ != Kind::kMap || rows_.empty()) return {};
    double ru, cu;
    std::size_t j = rows_.sample(u1, ru);
    std::size_t i = columns_[j].sample(u2, cu);
    const double u = (i + cu) / width_, v = (j + ru) / height_;
    const double phi = 2 * kPi * u, theta = kPi * v;
    const double st = std::sin(theta);
    if (!(st > 0)) return {};
    // The sampled texel's own density (pdf_uv(u, v) could round into the next texel).
    pdf_out = rows_.prob(j) * columns_[j].prob(i) * width_ * height_ / (2 * kPi * kPi * st);
    if (rgb) eval_uv(u, v, rgb);
    return {st * std::sin(phi), std::cos(theta), -st * std::cos(phi)};
}

} // namespace bsdflab
