#include "bsdflab/sampling.h"
#include <algorithm>
#include <cmath>

namespace bsdflab {

Vec3 square_to_cosine_hemisphere(double u1, double u2) {
    // Concentric map keeps strata compact (less distortion than the polar map).
    double a = 2.0 * u1 - 1.0, b = 2.0 * u2 - 1.0;
    double r, phi;
    if (a == 0 && b == 0) {
        r = 0;
        phi = 0;
    } else if (std::abs(a) > std::abs(b)) {
        r = a;
        phi = (kPi / 4.0) * (b / a);
    } else {
        r = b;
        phi = kPi / 2.0 - (kPi / 4.0) * (a / b);
    }
    double x = r * std::cos(phi), y = r * std::sin(phi);
    double z = std::sqrt(std::max(0.0, 1.0 - x * x - y * y));
    return {x, y, z};
}

} // namespace bsdflab
