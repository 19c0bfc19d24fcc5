#include "bsdflab/projected_term.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/parallel.h"

namespace bsdflab {

ProjectedFresnelTerm::ProjectedFresnelTerm(std::shared_ptr<const FresnelTerm> exact, std::vector<double> P,
                                           int out_channels, double thickness_lo, double thickness_hi,
                                           double default_thickness, int n_cos, int n_thickness)
    : FresnelTerm(out_channels, exact ? exact->eta() : 1.0), exact_(std::move(exact)), P_(std::move(P)),
      lo_(thickness_lo), hi_(thickness_hi), default_(default_thickness), n_cos_(n_cos),
      n_thickness_(thickness_lo < 0 ? 1 : n_thickness) {
    if (!exact_) throw std::invalid_argument("projected term: no exact term");
    const int K = out_channels, C = exact_->channels();
    if (K < 1 || P_.size() != std::size_t(K) * C)
        throw std::invalid_argument("projected term: P must be (K x C)");
    if (n_cos_ < 2 || n_thickness_ < 1) throw std::invalid_argument("projected term: need >= 2 cosine nodes");
    if (lo_ >= 0 && !(hi_ >= lo_)) throw std::invalid_argument("projected term: thickness_hi < thickness_lo");
    if (lo_ >= 0 && hi_ > lo_ && n_thickness_ < 2)
        throw std::invalid_argument("projected term: need >= 2 thickness nodes");
    if (hi_ == lo_) n_thickness_ = 1;
    table_.resize(std::size_t(n_thickness_) * n_cos_ * 2 * K);
    // Nodes are independent (and the exact term is thread-safe): build them on all cores.
    parallel_for(std::size_t(n_thickness_), 1, [&](std::size_t t_begin, std::size_t t_end) {
        std::vector<double> R(C), T(C);
        for (int t = int(t_begin); t < int(t_end); ++t) {
            Query q;
            q.film_thickness_nm =
                lo_ < 0 ? -1.0 : (n_thickness_ > 1 ? lo_ + (hi_ - lo_) * t / (n_thickness_ - 1) : lo_);
            for (int c = 0; c < n_cos_; ++c) {
                // The grazing node (cos 0) is evaluated just inside: a term may be undefined at 0.
                double cos_i = std::max(double(c) / (n_cos_ - 1), 1e-9);
                exact_->eval(cos_i, q, R.data(), T.data());
                float *out = &table_[(std::size_t(t) * n_cos_ + c) * 2 * K];
                for (int k = 0; k < K; ++k) {
                    double r = 0, tr = 0;
                    for (int l = 0; l < C; ++l) {
                        r += P_[std::size_t(k) * C + l] * R[l];
                        tr += P_[std::size_t(k) * C + l] * T[l];
                    }
                    out[k] = float(r);
                    out[K + k] = float(tr);
                }
            }
        }
    });
}

void ProjectedFresnelTerm::project(const double *spectral, double *out) const {
    const int K = channels(), C = exact_->channels();
    for (int k = 0; k < K; ++k) {
        double s = 0;
        for (int l = 0; l < C; ++l) s += P_[std::size_t(k) * C + l] * spectral[l];
        out[k] = s;
    }
}

void ProjectedFresnelTerm::eval(double cos_i, const Query &q, double *R, double *T) const {
    const int K = channels();
    if (!(cos_i > 0)) {
        // From the interior: exact (a buffer of this function only: the exact term's own
        // evaluation does not come back here).
        thread_local std::vector<double> buffer;
        const int C = exact_->channels();
        if (int(buffer.size()) < 2 * C) buffer.resize(2 * C);
        Query e = q;
        if (lo_ >= 0) {
            double t = q.film_thickness_nm >= 0 ? q.film_thickness_nm : default_;
            e.film_thickness_nm = std::clamp(t, lo_, hi_);
        }
        exact_->eval(std::isnan(cos_i) ? 0.0 : cos_i, e, buffer.data(), buffer.data() + C);
        project(buffer.data(), R);
        project(buffer.data() + C, T);
        return;
    }
    double x = std::min(cos_i, 1.0) * (n_cos_ - 1);
    int c0 = std::min(int(x), n_cos_ - 2);
    double wc = x - c0;
    int t0 = 0;
    double wt = 0;
    if (n_thickness_ > 1) {
        double t = q.film_thickness_nm >= 0 ? q.film_thickness_nm : default_;
        double y = (std::clamp(t, lo_, hi_) - lo_) / (hi_ - lo_) * (n_thickness_ - 1);
        t0 = std::min(int(y), n_thickness_ - 2);
        wt = y - t0;
    }
    const int stride = 2 * K;
    const float *a = &table_[(std::size_t(t0) * n_cos_ + c0) * stride];
    const float *b = a + stride;
    const float *c = n_thickness_ > 1 ? a + std::size_t(n_cos_) * stride : a;
    const float *d = c + stride;
    const double w00 = (1 - wt) * (1 - wc), w01 = (1 - wt) * wc, w10 = wt * (1 - wc), w11 = wt * wc;
    for (int k = 0; k < K; ++k) {
        R[k] = w00 * a[k] + w01 * b[k] + w10 * c[k] + w11 * d[k];
        T[k] = w00 * a[K + k] + w01 * b[K + k] + w10 * c[K + k] + w11 * d[K + k];
    }
}

} // namespace bsdflab
