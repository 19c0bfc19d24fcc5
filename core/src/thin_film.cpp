#include "bsdflab/thin_film.h"
#include <cmath>
#include "bsdflab/constants.h"
#include "bsdflab/vector_math.h"

namespace bsdflab {

namespace {

// Complex numbers with plain arithmetic. std::complex's operator* and operator/ follow C's
// Annex G and check every result for NaN to rescue infinities; inputs here are finite and
// of moderate size, and skipping those checks makes the single-film kernel ~15% faster.
struct Z {
    double re, im;
    Z(double r = 0.0, double i = 0.0) : re(r), im(i) {}
    Z(cplx z) : re(z.real()), im(z.imag()) {}
    operator cplx() const { return {re, im}; }
};
inline Z operator+(Z a, Z b) { return {a.re + b.re, a.im + b.im}; }
inline Z operator-(Z a, Z b) { return {a.re - b.re, a.im - b.im}; }
inline Z operator-(Z a) { return {-a.re, -a.im}; }
inline Z operator*(Z a, Z b) { return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re}; }
inline Z operator*(double s, Z a) { return {s * a.re, s * a.im}; }
inline double norm(Z a) { return a.re * a.re + a.im * a.im; }
inline Z conj(Z a) { return {a.re, -a.im}; }
inline Z reciprocal(Z a) {
    double s = 1.0 / norm(a);
    return {a.re * s, -a.im * s};
}

// Principal square root (Re >= 0, Im carrying the sign of Im z, -0 included) without the
// library's scaling for huge or tiny magnitudes, which indices and cosines never reach.
// A real argument (lossless media) takes one real square root.
Z principal_sqrt(Z z) {
    if (z.im == 0)
        return z.re >= 0 ? Z(std::sqrt(z.re), z.im) : Z(0.0, std::copysign(std::sqrt(-z.re), z.im));
    double r = std::sqrt(norm(z));
    if (z.re >= 0) {
        double t = std::sqrt(0.5 * (r + z.re));
        return {t, 0.5 * z.im / t};
    }
    double t = std::sqrt(0.5 * (r - z.re));
    return {0.5 * std::abs(z.im) / t, std::copysign(t, z.im)};
}

// A medium as the wave sees it: index n, permittivity eps = n^2 and q = n cos(theta),
// the normal wavenumber in units of the vacuum wavenumber.
struct Medium {
    Z n, eps, q;
};

// Everything Snell's law needs from the incident medium.
struct Incidence {
    Medium m0;
    Z q0_sq;
};

Incidence incidence(Z n0, double cos0) {
    Incidence in;
    in.m0 = {n0, n0 * n0, cos0 * n0};
    in.q0_sq = in.m0.q * in.m0.q;
    return in;
}

// q = sqrt(eps - (n0 sin theta0)^2), written as sqrt((eps - eps0) + q0^2) so that a medium
// matching the incident one gets q == q0 exactly, even at grazing angles.
// Forward branch as in snell_cos: decaying into the medium, else propagating away from it.
Medium medium(Z n, const Incidence &in) {
    Z eps = n * n;
    Z q = principal_sqrt((eps - in.m0.eps) + in.q0_sq);
    double scale = std::abs(q.re) + std::abs(q.im);
    bool forward = std::abs(q.im) > 1e-12 * scale ? q.im > 0 : q.re >= 0;
    return {n, eps, forward ? q : -q};
}

struct Interface {
    Z r_s, r_p, t_s, t_p;
};

// Fresnel amplitudes from medium a into medium b, in the q/eps form of complex_fresnel.h's
// formulas (p multiplied through by n_a n_b), which needs no divisions by n.
Interface interface(const Medium &a, const Medium &b) {
    Z inv_s = reciprocal(a.q + b.q);
    Z pa = b.eps * a.q, pb = a.eps * b.q;
    Z inv_p = reciprocal(pa + pb);
    return {(a.q - b.q) * inv_s, (pa - pb) * inv_p, 2.0 * a.q * inv_s, 2.0 * (a.n * b.n * a.q) * inv_p};
}

// e^{i delta} for one pass through a layer; |e| <= 1 on the forward branch.
Z phase(const Medium &m, double d_nm, double wavelength_nm) {
    double k = kTwoPi * d_nm / wavelength_nm;
    double decay = m.q.im == 0 ? 1.0 : std::exp(-k * m.q.im);
    double angle = k * m.q.re;
    return {decay * std::cos(angle), decay * std::sin(angle)};
}

// Reflection g and transmission tau of everything below a layer, seen from inside it,
// folded through the layer (phase e) and the interface `top` above it (the Airy sum).
void fold(Z r_top, Z t_top, Z e, Z &g, Z &tau) {
    Z ge2 = g * (e * e);
    Z inv = reciprocal(1.0 + r_top * ge2);
    g = (r_top + ge2) * inv;
    tau = t_top * tau * e * inv;
}

// Power fractions from the amplitudes (tmm's definitions; see thin_film.h).
FilmResponse with_power(Z r_s, Z r_p, Z t_s, Z t_p, const Medium &in, const Medium &out) {
    FilmResponse f{r_s, r_p, t_s, t_p, norm(r_s), norm(r_p), 0.0, 0.0};
    double incoming = in.q.re; // Re(n_in cos_in) = Re(n_in conj(cos_in)): cos_in is real
    if (incoming > 0) {
        f.T_s = out.q.re / incoming * norm(t_s);
        // Re(n conj(cos)) with cos = q / n, rewritten as Re(eps conj(q)) / |n|^2.
        f.T_p = (out.eps * conj(out.q)).re / (norm(out.n) * incoming) * norm(t_p);
    }
    return f;
}

// The limit cos0 -> 0: every interface reflects r = -1 and nothing enters.
FilmResponse grazing() { return {cplx(-1.0), cplx(-1.0), cplx(0.0), cplx(0.0), 1.0, 1.0, 0.0, 0.0}; }

// One film by the Airy sums with r01, r12, t01, t12 written as fractions and the fractions
// cleared: r = (m01 p12 + p01 m12 e2) / D, t = (numerators of t01 t12) e / D, where
// D = p01 p12 + m01 m12 e2; one division per polarisation instead of six. Without
// `kTransmission` only R_s = |num|^2 / |D|^2 and R_p are filled in (the rest is left zero).
template <bool kTransmission>
FilmResponse one_film(Z n0, Z n1, Z n2, double d_nm, double cos0, double wavelength_nm) {
    if (!(cos0 > 0)) return grazing();
    const Incidence in = incidence(n0, cos0);
    const Medium &m0 = in.m0, film = medium(n1, in), exit = medium(n2, in);
    const Z e = phase(film, d_nm, wavelength_nm), e2 = e * e;
    Z p01 = m0.q + film.q, m01 = m0.q - film.q, p12 = film.q + exit.q;
    Z m12e2 = (film.q - exit.q) * e2;
    const Z num_s = m01 * p12 + p01 * m12e2, den_s = p01 * p12 + m01 * m12e2;
    // p: the same with n_b^2 q_a and n_a^2 q_b in place of q_a and q_b (see interface()).
    Z a01 = film.eps * m0.q, b01 = m0.eps * film.q;
    Z a12 = exit.eps * film.q, b12 = film.eps * exit.q;
    p01 = a01 + b01, m01 = a01 - b01, p12 = a12 + b12, m12e2 = (a12 - b12) * e2;
    const Z num_p = m01 * p12 + p01 * m12e2, den_p = p01 * p12 + m01 * m12e2;
    if constexpr (!kTransmission) {
        FilmResponse f{};
        f.R_s = norm(num_s) / norm(den_s);
        f.R_p = norm(num_p) / norm(den_p);
        return f;
    } else {
        const Z inv_s = reciprocal(den_s), inv_p = reciprocal(den_p);
        const Z w = 4.0 * (m0.q * film.q * e); // shared by t_s and t_p
        return with_power(num_s * inv_s, num_p * inv_p, w * inv_s, w * (m0.n * exit.n * film.eps) * inv_p, m0,
                          exit);
    }
}

} // namespace

FilmResponse thin_film(cplx n0, cplx n1, cplx n2, double d_nm, double cos0, double wavelength_nm) {
    return one_film<true>(n0, n1, n2, d_nm, cos0, wavelength_nm);
}

FilmReflectance thin_film_reflectance(cplx n0, cplx n1, cplx n2, double d_nm, double cos0,
                                      double wavelength_nm) {
    const FilmResponse f = one_film<false>(n0, n1, n2, d_nm, cos0, wavelength_nm);
    return {f.R_s, f.R_p};
}

namespace {

// Everything of a stack that does not depend on the wavelength when no index does: the
// media (media[0] incident, media[layers + 1] exit) and the interfaces between neighbours.
struct StackAtAngle {
    std::size_t layers;
    Medium media[kFilmSpectrumMaxLayers + 2];
    Interface faces[kFilmSpectrumMaxLayers + 1]; // faces[j]: media[j] -> media[j + 1]

    StackAtAngle(const cplx *n, std::size_t L, double cos0) : layers(L) {
        const Incidence in = incidence(n[0], cos0);
        media[0] = in.m0;
        for (std::size_t j = 1; j <= L + 1; ++j) media[j] = medium(n[j], in);
        for (std::size_t j = 0; j <= L; ++j) faces[j] = interface(media[j], media[j + 1]);
    }

    // The stack folded from the exit side upwards at one wavelength: film_stack's
    // operations in its order, with the media and interfaces taken from above.
    FilmResponse at(const double *d_nm, double wavelength_nm) const {
        const Interface &bottom = faces[layers];
        Z g_s = bottom.r_s, g_p = bottom.r_p, tau_s = bottom.t_s, tau_p = bottom.t_p;
        for (std::size_t j = layers; j >= 1; --j) {
            const Interface &top = faces[j - 1];
            const Z e = phase(media[j], d_nm[j - 1], wavelength_nm);
            fold(top.r_s, top.t_s, e, g_s, tau_s);
            fold(top.r_p, top.t_p, e, g_p, tau_p);
        }
        return with_power(g_s, g_p, tau_s, tau_p, media[0], media[layers + 1]);
    }

    // One film with every medium real and propagating (real amplitudes, no loss), whose
    // closed form is well conditioned: its denominator 1 + p^2 + 2 p cos 2delta, p = r01 r12,
    // falls to (1 - |p|)^2 and loses digits as |p| -> 1 (a film between equal media at
    // grazing incidence, or at its own critical angle); the fold keeps them there.
    bool closed_form() const {
        if (layers != 1) return false;
        for (std::size_t j = 0; j < 3; ++j)
            if (media[j].q.im != 0 || !(media[j].q.re > 0) || media[j].eps.im != 0) return false;
        return std::abs(faces[0].r_s.re * faces[1].r_s.re) <= kMaxAiryProduct &&
               std::abs(faces[0].r_p.re * faces[1].r_p.re) <= kMaxAiryProduct;
    }
    // (1 - 0.5)^2: at most 2 bits lost to the denominator's cancellation.
    static constexpr double kMaxAiryProduct = 0.5;
};

// |r01 + r12 e|^2 / |1 + r01 r12 e|^2 for real r01, r12 and |e| = 1 as (a + b c) / (d + b c),
// c = Re e.
struct AirySum {
    double a, b, d;
    AirySum(double r01, double r12)
        : a(r01 * r01 + r12 * r12), b(2.0 * r01 * r12), d(1.0 + r01 * r01 * r12 * r12) {}
    double at(double c) const { return (a + b * c) / (d + b * c); }
};

} // namespace

FilmResponse film_stack(const cplx *n, const double *d_nm, std::size_t layers, double cos0,
                        double wavelength_nm) {
    if (!(cos0 > 0)) return grazing();
    const Incidence in = incidence(n[0], cos0);
    const Medium exit = medium(n[layers + 1], in);
    // Start at the bottom interface and fold the layers in from the exit side upwards.
    Medium below = layers == 0 ? in.m0 : medium(n[layers], in);
    const Interface bottom = interface(below, exit);
    Z g_s = bottom.r_s, g_p = bottom.r_p, tau_s = bottom.t_s, tau_p = bottom.t_p;
    for (std::size_t j = layers; j >= 1; --j) {
        const Medium above = j == 1 ? in.m0 : medium(n[j - 1], in);
        const Interface top = interface(above, below);
        const Z e = phase(below, d_nm[j - 1], wavelength_nm);
        fold(top.r_s, top.t_s, e, g_s, tau_s);
        fold(top.r_p, top.t_p, e, g_p, tau_p);
        below = above;
    }
    return with_power(g_s, g_p, tau_s, tau_p, in.m0, exit);
}

void film_stack_spectrum(const cplx *n, const double *d_nm, std::size_t layers, double cos0,
                         const double *wavelengths_nm, int count, double *R, double *T) {
    if (!(cos0 > 0) || layers > kFilmSpectrumMaxLayers) { // the grazing limit; a deep stack
        for (int c = 0; c < count; ++c) {
            const FilmResponse f = film_stack(n, d_nm, layers, cos0, wavelengths_nm[c]);
            R[c] = 0.5 * (f.R_s + f.R_p);
            T[c] = 0.5 * (f.T_s + f.T_p);
        }
        return;
    }
    const StackAtAngle stack(n, layers, cos0);
    if (stack.closed_form()) {
        const AirySum s(stack.faces[0].r_s.re, stack.faces[1].r_s.re);
        const AirySum p(stack.faces[0].r_p.re, stack.faces[1].r_p.re);
        // 2 delta = 4 pi d q1 / lambda (phase(): e = e^{i delta}, the fold's e^2).
        const double two_delta_nm = 2.0 * kTwoPi * d_nm[0] * stack.media[1].q.re;
        for (int c = 0; c < count; ++c) R[c] = two_delta_nm / wavelengths_nm[c];
        cos_array(R, R, count); // R holds cos 2delta per wavelength until overwritten
        for (int c = 0; c < count; ++c) {
            R[c] = 0.5 * (s.at(R[c]) + p.at(R[c]));
            T[c] = 1.0 - R[c];
        }
        return;
    }
    for (int c = 0; c < count; ++c) {
        const FilmResponse f = stack.at(d_nm, wavelengths_nm[c]);
        R[c] = 0.5 * (f.R_s + f.R_p);
        T[c] = 0.5 * (f.T_s + f.T_p);
    }
}

} // namespace bsdflab
