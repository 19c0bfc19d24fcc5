// Fresnel amplitude coefficients for s and p polarisation, real or complex indices.
// Sign convention (same as the `tmm` package and Born & Wolf):
//   r_s = (n_i cos_i - n_t cos_t) / (n_i cos_i + n_t cos_t)
//   r_p = (n_t cos_i - n_i cos_t) / (n_t cos_i + n_i cos_t)
//   t_s = 2 n_i cos_i / (n_i cos_i + n_t cos_t)
//   t_p = 2 n_i cos_i / (n_t cos_i + n_i cos_t)
// Indices are n + i k with k >= 0 for absorption. The sign of r already carries the
// reflection phase; adding a separate pi shift double-counts it (docs/validation.md).
#pragma once
#include <complex>

namespace bsdflab {

using cplx = std::complex<double>;

struct FresnelAmplitudes {
    cplx r_s, r_p, t_s, t_p;
    cplx cos_t; // complex cosine of the transmitted angle (forward branch)
};

// cos(theta_t) by Snell's law, choosing the branch of the forward-propagating (or
// evanescent, decaying) wave: Im(n_t cos_t) > 0, or Re(n_t cos_t) > 0 when lossless.
cplx snell_cos(cplx n_i, cplx cos_i, cplx n_t);

// Amplitudes at one interface for light arriving with cosine `cos_i` (>= 0) from the
// medium of index n_i into the medium of index n_t.
FresnelAmplitudes fresnel_amplitudes(cplx n_i, cplx n_t, cplx cos_i);

// Unpolarised reflectance (|r_s|^2 + |r_p|^2) / 2 at one interface.
double fresnel_reflectance(cplx n_i, cplx n_t, double cos_i);

// Real-index dielectric interface, in the form samplers need. `cos_theta_i` is signed:
// negative means the light arrives from below (inside, index `eta` relative to outside).
struct DielectricFresnel {
    double R;           // unpolarised reflectance
    double cos_theta_t; // signed cosine of the refracted direction (0 under TIR)
    double eta_it;      // n_t / n_i for this crossing
    double eta_ti;      // n_i / n_t
};
DielectricFresnel fresnel_dielectric(double cos_theta_i, double eta);

} // namespace bsdflab
