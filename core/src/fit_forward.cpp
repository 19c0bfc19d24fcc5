#include "bsdflab/fit_forward.h"
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include "bsdflab/constants.h"
#include "bsdflab/parallel.h"
#include "bsdflab/thin_film.h"

namespace bsdflab::fit {

namespace {

constexpr std::size_t kFilmEvalsPerThread = 4000; // ~0.5 ms of work

bool finite_params(const double *p) {
    for (int i = 0; i < kParamCount; ++i)
        if (!std::isfinite(p[i])) return false;
    return p[kThickness] >= 0 && p[kSpread] >= 0 && p[kExterior] > 0 && p[kSubstrate] > p[kExterior] &&
           p[kSigma550] >= 0 && p[kSlabUm] >= 0 && p[kAlbedo] >= 0 && p[kAlbedo] <= 1;
}

// Unpolarised film powers for light from the exterior at cosine c.
struct Powers {
    double R, T;
};

Powers film_powers(double n_e, double n_f, double n_s, double d, double c, double wl) {
    FilmResponse f = thin_film(n_e, n_f, n_s, d, c, wl);
    return {0.5 * (f.R_s + f.R_p), 0.5 * (f.T_s + f.T_p)};
}

} // namespace

ForwardModel::ForwardModel(std::vector<double> wavelengths_nm, std::vector<Observation> rows,
                           std::vector<double> gh_x, std::vector<double> gh_w, std::vector<double> gl_x,
                           std::vector<double> gl_w)
    : wavelengths_(std::move(wavelengths_nm)), rows_(std::move(rows)), rows_at_(wavelengths_.size()),
      hemisphere_at_(wavelengths_.size(), false), gh_x_(std::move(gh_x)), gh_w_(std::move(gh_w)) {
    if (gh_x_.empty() || gh_x_.size() != gh_w_.size())
        throw std::invalid_argument("Gauss-Hermite nodes and weights must be non-empty, same length");
    if (gl_x.empty() || gl_x.size() != gl_w.size())
        throw std::invalid_argument("Gauss-Legendre nodes and weights must be non-empty, same length");
    for (double wl : wavelengths_)
        if (!(wl > 0) || !std::isfinite(wl)) throw std::invalid_argument("wavelengths must be > 0");
    double sum = std::accumulate(gh_w_.begin(), gh_w_.end(), 0.0);
    for (double &w : gh_w_) w /= sum; // the normal density's quadrature: weights sum to 1
    for (std::size_t q = 0; q < gl_x.size(); ++q) {
        c_.push_back(0.5 * (gl_x[q] + 1.0));
        c_w_.push_back(0.5 * gl_w[q]);
    }
    for (std::size_t r = 0; r < rows_.size(); ++r) {
        const Observation &o = rows_[r];
        if (o.wavelength < 0 || static_cast<std::size_t>(o.wavelength) >= wavelengths_.size())
            throw std::invalid_argument("observation wavelength index out of range");
        if (o.geometry < kSpecular || o.geometry > kTotal)
            throw std::invalid_argument("observation geometry must be 0, 1 or 2");
        if (!(o.cos_in > 0 && o.cos_in <= 1) ||
            (o.geometry == kDiffuse && !(o.cos_out > 0 && o.cos_out <= 1)))
            throw std::invalid_argument("observation cosines must lie in (0, 1]");
        rows_at_[o.wavelength].push_back(r);
        if (o.geometry != kSpecular) hemisphere_at_[o.wavelength] = true;
    }
}

void ForwardModel::evaluate(const double *params, std::size_t count, double *out) const {
    const std::size_t nw = wavelengths_.size(), nr = rows_.size();
    // Film evaluations per (set, wavelength) at most; threads only pay off for a few
    // hundred microseconds of work per thread (starting them costs ~tens of microseconds).
    const std::size_t per_item = gh_x_.size() * (c_.size() + 2 * nr / std::max<std::size_t>(nw, 1) + 1);
    const std::size_t grain =
        std::max<std::size_t>(1, kFilmEvalsPerThread / std::max<std::size_t>(per_item, 1));
    parallel_for(count * nw, grain, [&](std::size_t s, std::size_t e) {
        for (std::size_t i = s; i < e; ++i) {
            std::size_t set = i / nw;
            evaluate_wavelength(params + set * kParamCount, i % nw, out + set * nr);
        }
    });
}

void ForwardModel::evaluate_wavelength(const double *p, std::size_t j, double *out) const {
    const std::vector<std::size_t> &rows = rows_at_[j];
    if (rows.empty()) return;
    const double wl = wavelengths_[j];
    const double n_e = p[kExterior], n_s = p[kSubstrate];
    const double n_f = p[kCauchyA] + p[kCauchyB] / (wl * wl);
    if (!finite_params(p) || !(n_f > 0)) {
        for (std::size_t r : rows) out[r] = kNaN;
        return;
    }
    for (std::size_t r : rows) out[r] = 0.0;

    const double tau = p[kSigma550] * std::pow(wl / 550.0, -p[kExponent]) * p[kSlabUm];
    const double rho = p[kAlbedo];
    const double ratio_sq = (n_e / n_s) * (n_e / n_s); // 1 / eta^2
    const auto slab_cos = [&](double c) { return std::sqrt(1.0 - ratio_sq * (1.0 - c * c)); };
    const auto attenuation = [&](double c) { return std::exp(-tau / slab_cos(c)); };

    // Slab-side light beyond the critical angle is totally reflected whatever the film.
    double gamma_tir = 0.0;
    if (hemisphere_at_[j]) {
        const double mu_c = std::sqrt(1.0 - ratio_sq);
        for (std::size_t q = 0; q < c_.size(); ++q)
            gamma_tir += 2.0 * c_w_[q] * mu_c * mu_c * c_[q] * std::exp(-2.0 * tau / (mu_c * c_[q]));
    }

    const bool spread = p[kSpread] > 0;
    const std::size_t nodes = spread ? gh_x_.size() : 1;
    for (std::size_t k = 0; k < nodes; ++k) {
        const double d =
            spread ? std::max(0.0, p[kThickness] + std::sqrt(2.0) * p[kSpread] * gh_x_[k]) : p[kThickness];
        const double w = spread ? gh_w_[k] : 1.0;
        double gamma = gamma_tir, leaving = 0.0;
        if (hemisphere_at_[j]) {
            for (std::size_t q = 0; q < c_.size(); ++q) {
                const double c = c_[q], mu = slab_cos(c);
                const double T = film_powers(n_e, n_f, n_s, d, c, wl).T;
                gamma += 2.0 * ratio_sq * c_w_[q] * c * std::exp(-2.0 * tau / mu) * (1.0 - T);
                leaving += 2.0 * c_w_[q] * c * std::exp(-tau / mu) * T;
            }
        }
        // Base light summed over all its returns to the base, per unit of entering power.
        const double base = rho * ratio_sq / (1.0 - rho * gamma);
        for (std::size_t r : rows) {
            const Observation &o = rows_[r];
            const Powers in = film_powers(n_e, n_f, n_s, d, o.cos_in, wl);
            double value;
            if (o.geometry == kSpecular) {
                value = in.R;
            } else if (o.geometry == kDiffuse) {
                const double T_out = film_powers(n_e, n_f, n_s, d, o.cos_out, wl).T;
                value = in.T * attenuation(o.cos_in) * base * attenuation(o.cos_out) * T_out;
            } else {
                value = in.R + in.T * attenuation(o.cos_in) * base * leaving;
            }
            out[r] += w * value;
        }
    }
}

} // namespace bsdflab::fit
