#include "bsdflab/fresnel_terms.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/complex_fresnel.h"
#include "bsdflab/thin_film.h"

namespace bsdflab {

DielectricTerm::DielectricTerm(int channels, double int_ior, double ext_ior)
    : FresnelTerm(channels, int_ior / ext_ior) {}

void DielectricTerm::eval(double cos_i, const Query &, double *R, double *T) const {
    double r = fresnel_dielectric(cos_i, eta_).R;
    for (int c = 0; c < channels_; ++c) {
        R[c] = r;
        T[c] = 1.0 - r;
    }
}

ConductorTerm::ConductorTerm(std::vector<std::complex<double>> n_int, double ext_ior)
    : FresnelTerm(static_cast<int>(n_int.size()), 0.0), n_int_(std::move(n_int)), ext_ior_(ext_ior) {}

void ConductorTerm::eval(double cos_i, const Query &, double *R, double *T) const {
    double ci = std::abs(cos_i);
    for (int c = 0; c < channels_; ++c) {
        R[c] = fresnel_reflectance(cplx(ext_ior_, 0.0), n_int_[c], ci);
        T[c] = 0.0;
    }
}

FilmTerm::FilmTerm(std::vector<double> wavelengths, double ext_ior,
                   std::vector<std::vector<std::complex<double>>> layer_n, std::vector<double> layer_d_nm,
                   std::vector<std::complex<double>> n_substrate, bool substrate_transmits)
    : FresnelTerm(static_cast<int>(wavelengths.size()),
                  substrate_transmits && !n_substrate.empty() ? n_substrate[0].real() / ext_ior : 0.0),
      wavelengths_(std::move(wavelengths)), ext_ior_(ext_ior), layer_n_(std::move(layer_n)),
      layer_d_(std::move(layer_d_nm)), n_sub_(std::move(n_substrate)), transmits_(substrate_transmits),
      total_d_(0.0), uniform_(true) {
    for (double d : layer_d_) total_d_ += d;
    if (layer_d_.size() != layer_n_.size() || layer_d_.size() > kMaxFilmLayers)
        throw std::invalid_argument("a film stack needs one index list per layer, at most 32 layers");
    for (const auto &n : layer_n_)
        if (static_cast<int>(n.size()) != channels_)
            throw std::invalid_argument("each film layer needs one index per wavelength");
    if (static_cast<int>(n_sub_.size()) != channels_)
        throw std::invalid_argument("the substrate needs one index per wavelength");
    for (int c = 1; c < channels_; ++c) {
        uniform_ = uniform_ && n_sub_[c] == n_sub_[0];
        for (const auto &n : layer_n_) uniform_ = uniform_ && n[c] == n[0];
    }
}

void FilmTerm::eval(double cos_i, const Query &q, double *R, double *T) const {
    constexpr std::size_t kMaxLayers = kMaxFilmLayers;
    std::size_t L = layer_d_.size();
    double scale = (q.film_thickness_nm >= 0 && total_d_ > 0) ? q.film_thickness_nm / total_d_ : 1.0;
    bool from_above = cos_i >= 0;
    double ci = std::abs(cos_i);
    if (!from_above && !transmits_) {
        std::fill(R, R + channels_, 0.0);
        std::fill(T, T + channels_, 0.0);
        return;
    }
    cplx n[kMaxLayers + 2];
    double d[kMaxLayers];
    // Media in the order the light meets them, at channel c.
    auto media = [&](int c) {
        n[0] = from_above ? cplx(ext_ior_, 0.0) : n_sub_[c];
        n[L + 1] = from_above ? n_sub_[c] : cplx(ext_ior_, 0.0);
        for (std::size_t j = 0; j < L; ++j) {
            std::size_t src = from_above ? j : L - 1 - j;
            n[j + 1] = layer_n_[src][c];
            d[j] = layer_d_[src] * scale;
        }
    };
    if (uniform_) {
        media(0);
        film_stack_spectrum(n, d, L, ci, wavelengths_.data(), channels_, R, T);
    } else {
        for (int c = 0; c < channels_; ++c) {
            media(c);
            FilmResponse f = film_stack(n, d, L, ci, wavelengths_[c]);
            R[c] = 0.5 * (f.R_s + f.R_p);
            T[c] = 0.5 * (f.T_s + f.T_p);
        }
    }
    for (int c = 0; c < channels_; ++c) {
        const double r = R[c], t = transmits_ ? T[c] : 0.0;
        R[c] = std::isfinite(r) ? std::min(std::max(r, 0.0), 1.0) : 0.0;
        T[c] = std::isfinite(t) ? std::min(std::max(t, 0.0), 1.0 - R[c]) : 0.0;
    }
}

} // namespace bsdflab
