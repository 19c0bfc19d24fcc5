// Material colour: a render BSDF's channels to RGB (its projection P) or to the spectral
// bins (its lift U), and the scene's lift of RGB emission to the bins.
#include <stdexcept>
#include "bsdflab/render/scene.h"

namespace bsdflab {

void RenderBSDF::to_rgb(const double *channels, double rgb[3]) const {
    if (P.empty()) {
        for (int c = 0; c < 3; ++c) rgb[c] = channels[c];
        return;
    }
    const int C = bsdf->channels();
    for (int r = 0; r < 3; ++r) {
        double s = 0;
        const double *row = &P[std::size_t(r) * C];
        for (int c = 0; c < C; ++c) s += row[c] * channels[c];
        rgb[r] = s;
    }
}

void RenderBSDF::to_spectrum(const double *channels, double out[kSpectralBins]) const {
    if (U.empty()) {
        for (int l = 0; l < kSpectralBins; ++l) out[l] = channels[l];
        return;
    }
    const int C = bsdf->channels();
    for (int l = 0; l < kSpectralBins; ++l) {
        const double *row = &U[std::size_t(l) * C];
        double s = 0;
        for (int c = 0; c < C; ++c) s += row[c] * channels[c];
        out[l] = s;
    }
}

void RenderScene::set_spectral(std::vector<double> U, std::vector<double> W) {
    if (committed_)
        throw std::logic_error("scene already committed: set the spectral matrices before commit()");
    if (U.size() != 3u * kSpectralBins || W.size() != 3u * kSpectralBins)
        throw std::invalid_argument("spectral matrices must be (81 x 3) and (3 x 81)");
    U_ = std::move(U);
    W_ = std::move(W);
}

void RenderScene::lift(const double rgb[3], double out[kSpectralBins]) const {
    for (int l = 0; l < kSpectralBins; ++l)
        out[l] = U_[3 * l] * rgb[0] + U_[3 * l + 1] * rgb[1] + U_[3 * l + 2] * rgb[2];
}

} // namespace bsdflab
