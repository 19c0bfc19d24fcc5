#include "bsdflab/phase.h"
#include <algorithm>
#include <cmath>
#include "bsdflab/sampling.h"

namespace bsdflab {

double PhaseFunction::eval_cos(double c) const {
    switch (kind_) {
    case kHenyeyGreenstein: {
        double g = param_, d = 1.0 + g * g - 2.0 * g * c;
        return (1.0 - g * g) / (4.0 * kPi * d * std::sqrt(d));
    }
    case kVonMisesFisher: {
        double k = param_;
        if (k < 1e-6) return 1.0 / (4.0 * kPi);
        // kappa / (4 pi sinh kappa) e^{kappa c}, written to stay finite for large kappa
        return k / (2.0 * kPi * (1.0 - std::exp(-2.0 * k))) * std::exp(k * (c - 1.0));
    }
    default: return 1.0 / (4.0 * kPi);
    }
}

double PhaseFunction::sample_cos(double u) const {
    switch (kind_) {
    case kHenyeyGreenstein: {
        double g = param_;
        if (std::abs(g) < 1e-4) return 1.0 - 2.0 * u;
        double s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
        return std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
    }
    case kVonMisesFisher: {
        double k = param_;
        if (k < 1e-6) return 1.0 - 2.0 * u;
        return std::clamp(1.0 + std::log(u + (1.0 - u) * std::exp(-2.0 * k)) / k, -1.0, 1.0);
    }
    default: return 1.0 - 2.0 * u;
    }
}

double PhaseFunction::eval(const Vec3 &w, const Vec3 &w2) const {
    return eval_cos(std::clamp(dot(w, w2), -1.0, 1.0));
}

Vec3 PhaseFunction::sample(const Vec3 &w, double u1, double u2) const {
    double c = sample_cos(u1), s = std::sqrt(std::max(0.0, 1.0 - c * c));
    double phi = 2.0 * kPi * u2;
    // Orthonormal basis around w (Duff et al. 2017).
    double sign = std::copysign(1.0, w.z);
    double a = -1.0 / (sign + w.z), b = w.x * w.y * a;
    Vec3 t1{1.0 + sign * w.x * w.x * a, sign * b, -sign * w.x};
    Vec3 t2{b, sign + w.y * w.y * a, -w.y};
    return t1 * (s * std::cos(phi)) + t2 * (s * std::sin(phi)) + w * c;
}

} // namespace bsdflab
