#include "bsdflab/fit_instrument.h"
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <vector>
#include "bsdflab/constants.h"
#include "bsdflab/parallel.h"
#include "bsdflab/thin_film.h"

namespace bsdflab::fit {

namespace {

constexpr std::size_t kStacksPerThread = 2000; // ~0.3 ms of work per chunk
constexpr std::size_t kMaxMedia = 2 * kFilmSpectrumMaxLayers + 2;
constexpr std::size_t kMaxCone = 64;

} // namespace

InstrumentStack::InstrumentStack(std::vector<double> angles_deg, std::size_t wavelengths, std::size_t layers,
                                 std::vector<double> band_w, std::vector<double> cone_u,
                                 std::vector<double> cone_w, std::size_t azimuths)
    : angles_(std::move(angles_deg)), wavelengths_(wavelengths), layers_(layers), band_w_(std::move(band_w)),
      cone_u_(std::move(cone_u)), cone_w_(std::move(cone_w)) {
    if (band_w_.empty() || band_w_.size() % 2 == 0)
        throw std::invalid_argument("bandwidth weights: an odd, non-zero count (the middle node is x = 0)");
    if (cone_u_.empty() || cone_u_.size() != cone_w_.size() || azimuths == 0)
        throw std::invalid_argument("cone nodes and weights must be non-empty, same length; azimuths >= 1");
    if (cone_u_.size() > kMaxCone || azimuths > kMaxCone)
        throw std::invalid_argument("at most 64 cone nodes and 64 azimuths");
    if (layers_ + 2 > kMaxMedia) throw std::invalid_argument("too many layers");
    for (double a : angles_)
        if (!(a >= 0 && a < 90)) throw std::invalid_argument("angles must lie in [0, 90) degrees");
    const double sum = std::accumulate(band_w_.begin(), band_w_.end(), 0.0);
    for (double &w : band_w_) w /= sum;
    for (std::size_t m = 0; m < azimuths; ++m)
        psi_cos_.push_back(std::cos(kPi * (m + 0.5) / static_cast<double>(azimuths)));
}

void InstrumentStack::evaluate(const cplx *n, const double *wl, const double *d, const double *inst,
                               std::size_t count, double *out) const {
    const std::size_t na = angles_.size();
    const std::size_t per_item = wavelengths_ * band_w_.size();
    const std::size_t grain = std::max<std::size_t>(1, kStacksPerThread / std::max<std::size_t>(per_item, 1));
    const std::size_t M = media(), E = wavelengths_ * band_w_.size();
    parallel_for(count * na, grain, [&](std::size_t s, std::size_t e) {
        for (std::size_t i = s; i < e; ++i) {
            const std::size_t set = i / na, a = i % na;
            evaluate_angle(n + set * M * E, wl + set * E, d + set * layers_, inst + set * 3, a,
                           out + (set * na + a) * wavelengths_);
        }
    });
}

void InstrumentStack::evaluate_angle(const cplx *n, const double *wl, const double *d, const double *inst,
                                     std::size_t a, double *out) const {
    const std::size_t M = media(), B = band_w_.size(), E = wavelengths_ * B;
    const double offset = inst[0], accept = inst[1], fwhm = inst[2];
    bool ok =
        std::isfinite(offset) && std::isfinite(accept) && std::isfinite(fwhm) && accept >= 0 && fwhm >= 0;
    const double theta = std::abs(angles_[a] + offset);
    ok = ok && theta + accept < 90.0;
    for (std::size_t j = 0; ok && j < layers_; ++j) ok = std::isfinite(d[j]) && d[j] >= 0;
    for (std::size_t q = 0; ok && q < M * E; ++q)
        ok = std::isfinite(n[q].real()) && std::isfinite(n[q].imag()) && n[q].real() > 0 && n[q].imag() >= 0;
    for (std::size_t q = 0; ok && q < E; ++q) ok = std::isfinite(wl[q]) && wl[q] > 0 && n[q].imag() == 0;
    if (!ok) {
        std::fill(out, out + wavelengths_, kNaN);
        return;
    }
    // Incidence cosines of the cone's nodes and their normalised weights (solid angle).
    const bool cone = accept > 0;
    const std::size_t nb = cone ? cone_u_.size() : 1, npsi = cone ? psi_cos_.size() : 1;
    const double ct = std::cos(theta * kDegToRad), st = std::sin(theta * kDegToRad);
    double cos_in[kMaxCone * kMaxCone], weight[kMaxCone * kMaxCone];
    std::size_t nodes = 0;
    double wsum = 0.0;
    for (std::size_t q = 0; q < nb; ++q) {
        const double b = cone ? accept * kDegToRad * cone_u_[q] : 0.0;
        const double wb = cone ? cone_w_[q] * std::sin(b) : 1.0;
        for (std::size_t m = 0; m < npsi; ++m) {
            cos_in[nodes] =
                std::clamp(ct * std::cos(b) + st * std::sin(b) * (cone ? psi_cos_[m] : 0.0), 0.0, 1.0);
            weight[nodes] = wb;
            wsum += wb;
            ++nodes;
        }
    }
    // Only the middle wavelength node without a bandwidth.
    const std::size_t k0 = fwhm > 0 ? 0 : B / 2, k1 = fwhm > 0 ? B : B / 2 + 1;
    cplx media_n[kMaxMedia];
    // Non-dispersive media (constants such as guanine, cytoplasm, a fitted n + ik): the
    // stack's interfaces depend on the angle only, and film_stack_spectrum reuses them over
    // all wavelengths (bit-identical to film_stack except for its lossless one-film closed form).
    bool constant = layers_ <= kFilmSpectrumMaxLayers;
    for (std::size_t m = 0; constant && m < M; ++m)
        for (std::size_t q = 1; constant && q < E; ++q) constant = n[m * E + q] == n[m * E];
    if (constant) {
        for (std::size_t m = 0; m < M; ++m) media_n[m] = n[m * E];
        const std::size_t used = k1 - k0;
        std::vector<double> wls(wavelengths_ * used), R(wls.size()), T(wls.size()), acc(wls.size(), 0.0);
        for (std::size_t j = 0; j < wavelengths_; ++j)
            for (std::size_t k = k0; k < k1; ++k) wls[j * used + (k - k0)] = wl[j * B + k];
        for (std::size_t q = 0; q < nodes; ++q) {
            film_stack_spectrum(media_n, d, layers_, cos_in[q], wls.data(), static_cast<int>(wls.size()),
                                R.data(), T.data());
            for (std::size_t c = 0; c < wls.size(); ++c) acc[c] += weight[q] * R[c];
        }
        for (std::size_t j = 0; j < wavelengths_; ++j) {
            double sum = 0.0;
            for (std::size_t k = k0; k < k1; ++k)
                sum += (fwhm > 0 ? band_w_[k] : 1.0) * acc[j * used + (k - k0)];
            out[j] = sum / wsum;
        }
        return;
    }
    for (std::size_t j = 0; j < wavelengths_; ++j) {
        double sum = 0.0;
        for (std::size_t k = k0; k < k1; ++k) {
            const std::size_t col = j * B + k;
            for (std::size_t m = 0; m < M; ++m) media_n[m] = n[m * E + col];
            double r = 0.0;
            for (std::size_t q = 0; q < nodes; ++q) {
                const FilmResponse f = film_stack(media_n, d, layers_, cos_in[q], wl[col]);
                r += weight[q] * 0.5 * (f.R_s + f.R_p);
            }
            sum += (fwhm > 0 ? band_w_[k] : 1.0) * r / wsum;
        }
        out[j] = sum;
    }
}

void smear_uniform(const double *r, std::size_t count, std::size_t angles, std::size_t grid,
                   const double *sigma_nm, double step_nm, std::size_t first, std::size_t stride,
                   std::size_t wavelengths, std::size_t reach, double *out) {
    if (wavelengths > 0 && (first < reach || first + (wavelengths - 1) * stride + reach >= grid))
        throw std::invalid_argument("smear_uniform: the kernel reaches past the grid");
    parallel_for(count, 64, [&](std::size_t s, std::size_t e) {
        std::vector<double> w(2 * reach + 1);
        for (std::size_t set = s; set < e; ++set) {
            const double sg = sigma_nm[set];
            double sum = 0.0;
            for (std::size_t i = 0; i <= 2 * reach; ++i) {
                const double x = (static_cast<double>(i) - static_cast<double>(reach)) * step_nm / sg;
                w[i] = sg > 0 ? std::exp(-0.5 * x * x) : (i == reach ? 1.0 : 0.0);
                sum += w[i];
            }
            for (double &v : w) v /= sum;
            for (std::size_t a = 0; a < angles; ++a) {
                const double *ra = r + (set * angles + a) * grid;
                double *oa = out + (set * angles + a) * wavelengths;
                for (std::size_t j = 0; j < wavelengths; ++j) {
                    const std::size_t c = first + j * stride - reach;
                    double v = 0.0;
                    for (std::size_t i = 0; i <= 2 * reach; ++i) v += w[i] * ra[c + i];
                    oa[j] = v;
                }
            }
        }
    });
}

} // namespace bsdflab::fit
