// Coherent reflection and transmission of planar thin films and multilayer stacks.
//
// Media are numbered 0 (incident), 1..L (layers, thickness d_j in nm), L+1 (exit).
// Indices are n + i k with k >= 0 absorbing; amplitudes use the sign convention of
// complex_fresnel.h (the `tmm` package's). Light arrives in medium 0 with the real
// cosine cos0 in [0, 1] (0 gives the grazing limit r = -1, t = 0); every other cosine is
// complex, on the forward branch. Inputs are finite and of everyday size (Python checks).
//
// One film is the Airy sum, per polarisation (evaluated with its fractions cleared),
//     r = (r01 + r12 e^{2i delta}) / (1 + r01 r12 e^{2i delta}),  delta = 2 pi n1 d cos1 / lambda,
//     t = t01 t12 e^{i delta} / (1 + r01 r12 e^{2i delta}).
// The signs of r01 and r12 already hold the reflection phases; there is no extra pi term.
// A stack folds the same sum from the exit side upwards (recursive Airy). That equals the
// transfer-matrix product, but only ever multiplies by |e^{i delta}| <= 1, so thick
// absorbing or evanescent layers underflow harmlessly instead of overflowing.
//
// Power follows tmm's definitions (incident medium non-absorbing):
//     R = |r|^2,  T_s = Re(n_out cos_out) / Re(n_in cos_in) |t_s|^2,
//     T_p = Re(n_out conj(cos_out)) / Re(n_in conj(cos_in)) |t_p|^2   (0 at grazing incidence).
// Light from the exit side: reverse the index and thickness lists.
#pragma once
#include <cstddef>
#include "bsdflab/complex_fresnel.h"

namespace bsdflab {

struct FilmResponse {
    cplx r_s, r_p, t_s, t_p; // amplitude coefficients
    double R_s, R_p, T_s, T_p; // reflected and transmitted power fractions
};

// One film of index n1 and thickness d_nm between media n0 (incident) and n2 (exit).
// Allocates nothing: this is the renderer's inner loop.
FilmResponse thin_film(cplx n0, cplx n1, cplx n2, double d_nm, double cos0, double wavelength_nm);

// R_s and R_p of the same film, skipping the transmission amplitudes.
struct FilmReflectance {
    double R_s, R_p;
};
FilmReflectance thin_film_reflectance(cplx n0, cplx n1, cplx n2, double d_nm, double cos0,
                                      double wavelength_nm);

// A stack of `layers` films: n[0..layers+1] are the indices of all media in the order light
// meets them, d_nm[0..layers-1] the layer thicknesses. layers == 0 is a bare interface.
// Allocates nothing.
FilmResponse film_stack(const cplx *n, const double *d_nm, std::size_t layers, double cos0,
                        double wavelength_nm);

// Unpolarised R = (R_s + R_p) / 2 and T = (T_s + T_p) / 2 of one stack at `count`
// wavelengths, for indices that are the same at every wavelength (non-dispersive films such
// as guanine on keratin): the media and interface amplitudes depend on the angle only and
// are computed once; per wavelength only the layers' phases and the Airy folds remain.
// Equals film_stack at each wavelength bit for bit, except for one lossless film (every
// medium real and propagating) with |r01 r12| <= 0.5 for both polarisations, where the
// Airy sum's closed form
//     R_pol = (r01^2 + r12^2 + 2 r01 r12 cos 2delta) / (1 + r01^2 r12^2 + 2 r01 r12 cos 2delta),
//     T = 1 - R
// takes one cosine per wavelength (equal to film_stack to rounding; its denominator
// cancels as |r01 r12| -> 1, where the fold is kept). A stack deeper than
// kFilmSpectrumMaxLayers is evaluated by film_stack per wavelength. Allocates nothing.
constexpr std::size_t kFilmSpectrumMaxLayers = 32;
void film_stack_spectrum(const cplx *n, const double *d_nm, std::size_t layers, double cos0,
                         const double *wavelengths_nm, int count, double *R, double *T);

} // namespace bsdflab
