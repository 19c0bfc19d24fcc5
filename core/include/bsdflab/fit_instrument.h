// Specular reflectance of a multilayer stack seen through an instrument, for fitting.
//
// Structure: media 0 (exterior), 1..L (layers, thickness d_j nm), L+1 (substrate), each of
// complex index n + i k (k >= 0), dispersive: the caller gives every medium's index at
// every evaluation wavelength. Reflectance is the core's film_stack (thin_film.h),
// unpolarised (s and p averaged).
//
// Instrument (refnx's ReflectModel practice, Nelson & Prescott 2019, J. Appl. Cryst. 52:193):
//   angle offset      the sample sees theta + offset_deg (goniometer zero, sample tilt);
//   acceptance        the incident beam fills a cone of half-angle a around that direction,
//                     uniform in solid angle: cos theta' = cos theta cos b + sin theta sin b
//                     cos psi, averaged with Gauss-Legendre in b on [0, a] (weight sin b)
//                     and the midpoint rule in psi on [0, pi] (the cone is mirror-symmetric);
//   bandwidth         the spectrometer's slit: a Gaussian of FWHM f over wavelength,
//                     R(lambda) = sum_k w_k R(lambda + sqrt(2) s x_k), s = f / (2 sqrt(2 ln 2)),
//                     Gauss-Hermite nodes x_k (the caller places the wavelengths, because the
//                     media's indices must be known there; with f = 0 only the middle node).
// Scale and background are affine and applied by the caller.
//
// All quadrature nodes come from the caller. Thread-safe and const; threads over
// (parameter set, angle); call without the GIL.
#pragma once
#include <cstddef>
#include <vector>
#include "bsdflab/complex_fresnel.h"

namespace bsdflab::fit {

class InstrumentStack {
  public:
    // angles_deg: nominal incidence angles (A); wavelengths: nominal count W; layers: L;
    // band_w: Gauss-Hermite weights (B, odd, symmetric: the middle node is x = 0);
    // cone_u, cone_w: Gauss-Legendre nodes/weights on [0, 1] for b / a; azimuths: psi nodes.
    InstrumentStack(std::vector<double> angles_deg, std::size_t wavelengths, std::size_t layers,
                    std::vector<double> band_w, std::vector<double> cone_u, std::vector<double> cone_w,
                    std::size_t azimuths);

    std::size_t angles() const { return angles_.size(); }
    std::size_t wavelengths() const { return wavelengths_; }
    std::size_t band_nodes() const { return band_w_.size(); }
    std::size_t media() const { return layers_ + 2; }
    std::size_t layers() const { return layers_; }

    // Per parameter set s (count sets):
    //   n       (count, media, W * B)   complex indices at the evaluation wavelengths
    //   wl      (count, W * B)          evaluation wavelengths, nm (wavelength-major: j * B + k)
    //   d       (count, L)              layer thicknesses, nm
    //   inst    (count, 3)              angle offset (deg), acceptance half-angle (deg), bandwidth FWHM
    //                                   (nm; only 0 or not matters here: it picks the nodes used)
    // out: (count, A, W). A set outside the domain (non-finite, d < 0, k < 0, Re n <= 0, an
    // angle with theta + offset + acceptance >= 90 deg, acceptance < 0) gives NaN rows.
    void evaluate(const cplx *n, const double *wl, const double *d, const double *inst, std::size_t count,
                  double *out) const;

  private:
    void evaluate_angle(const cplx *n, const double *wl, const double *d, const double *inst, std::size_t a,
                        double *out) const;

    std::vector<double> angles_;
    std::size_t wavelengths_, layers_;
    std::vector<double> band_w_, cone_u_, cone_w_, psi_cos_;
};

// The slit on a uniform wavelength grid (the fast path for evenly spaced data): R on the
// grid lambda_0 + i step, i in [0, G), is smoothed by a Gaussian of standard deviation
// sigma_nm (per set) sampled on the grid -- the trapezoid rule, whose error for a Gaussian of
// sd sigma >= 1.2 step is below e^(-2 pi^2 1.2^2) ~ 5e-13 relative (plus the spectrum's own
// fringes, resolved when their period exceeds a few steps) -- and read at the nominal
// wavelengths, which sit at grid points first + j stride. The kernel reaches `reach` steps
// (>= 4 sigma / step). r: (count, A, G); out: (count, A, W). Threads over sets.
void smear_uniform(const double *r, std::size_t count, std::size_t angles, std::size_t grid,
                   const double *sigma_nm, double step_nm, std::size_t first, std::size_t stride,
                   std::size_t wavelengths, std::size_t reach, double *out);

} // namespace bsdflab::fit
