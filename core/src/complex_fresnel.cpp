#include "bsdflab/complex_fresnel.h"
#include <cmath>

namespace bsdflab {

cplx snell_cos(cplx n_i, cplx cos_i, cplx n_t) {
    cplx sin_i2 = 1.0 - cos_i * cos_i;
    cplx cos_t = std::sqrt(1.0 - (n_i / n_t) * (n_i / n_t) * sin_i2);
    // Pick the forward branch: decaying into the medium, or propagating away from it.
    cplx nc = n_t * cos_t;
    double scale = std::abs(nc) + 1e-300;
    bool forward = std::abs(nc.imag()) > 1e-12 * scale ? nc.imag() > 0 : nc.real() > 0;
    return forward ? cos_t : -cos_t;
}

FresnelAmplitudes fresnel_amplitudes(cplx n_i, cplx n_t, cplx cos_i) {
    FresnelAmplitudes a;
    a.cos_t = snell_cos(n_i, cos_i, n_t);
    cplx ni_ci = n_i * cos_i, nt_ct = n_t * a.cos_t;
    cplx nt_ci = n_t * cos_i, ni_ct = n_i * a.cos_t;
    a.r_s = (ni_ci - nt_ct) / (ni_ci + nt_ct);
    a.r_p = (nt_ci - ni_ct) / (nt_ci + ni_ct);
    a.t_s = 2.0 * ni_ci / (ni_ci + nt_ct);
    a.t_p = 2.0 * ni_ci / (nt_ci + ni_ct);
    return a;
}

double fresnel_reflectance(cplx n_i, cplx n_t, double cos_i) {
    FresnelAmplitudes a = fresnel_amplitudes(n_i, n_t, cplx(cos_i, 0.0));
    double R = 0.5 * (std::norm(a.r_s) + std::norm(a.r_p));
    return std::isfinite(R) ? R : 0.0;
}

DielectricFresnel fresnel_dielectric(double cos_theta_i, double eta) {
    DielectricFresnel f;
    bool outside = cos_theta_i >= 0;
    f.eta_it = outside ? eta : 1.0 / eta;
    f.eta_ti = 1.0 / f.eta_it;
    double ci = std::abs(cos_theta_i);
    // (eta_ti sin_i)^2: at normal incidence 0 even for an overflowing eta_ti.
    double sin_ti = f.eta_ti * std::sqrt(std::max(0.0, 1.0 - ci * ci));
    double sin_t2 = sin_ti * sin_ti;
    if (sin_t2 >= 1.0) { // total internal reflection
        f.R = 1.0;
        f.cos_theta_t = 0.0;
        return f;
    }
    double ct = std::sqrt(1.0 - sin_t2);
    // Real-index forms of the s/p amplitudes; n_i = 1, n_t = eta_it (relative).
    double r_s = (ci - f.eta_it * ct) / (ci + f.eta_it * ct);
    double r_p = (f.eta_it * ci - ct) / (f.eta_it * ci + ct);
    f.R = 0.5 * (r_s * r_s + r_p * r_p);
    f.cos_theta_t = outside ? -ct : ct;
    return f;
}

} // namespace bsdflab
