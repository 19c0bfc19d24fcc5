// Kulla-Conty energy compensation of rough interfaces (rough_multiscatter.h).
#include "bsdflab/rough_multiscatter.h"
#include <algorithm>
#include <cmath>
#include "bsdflab/complex_fresnel.h"
#include "bsdflab/quadrature.h"
#include "bsdflab/sampling.h"

namespace bsdflab {

namespace {
// Per-thread buffers of this file (distinct from scratch(): the interface's own single-
// scattering evaluation holds scratch slots 0-1 while this runs).
double *ms_buffer(int slot, int n) {
    thread_local std::vector<double> buffers[2];
    std::vector<double> &b = buffers[slot];
    if (static_cast<int>(b.size()) < n) b.resize(n);
    return b.data();
}

// Gauss-Legendre nodes / weights on [0, 1] (3 points: exact for degree 5; 24 points for
// the smooth Fresnel averages, whose film interference varies slowly with angle).
struct Rule {
    std::vector<double> x, w;
};
Rule gauss_legendre(int n) {
    std::vector<double> x, w;
    bsdflab::gauss_legendre(n, x, w); // on [-1, 1], ascending
    Rule r{std::vector<double>(n), std::vector<double>(n)};
    for (int i = 0; i < n; ++i) {
        r.x[i] = 0.5 * (1.0 - x[n - 1 - i]);
        r.w[i] = 0.5 * w[n - 1 - i];
    }
    return r;
}

// Midpoints of u = (1 - cos(pi x)) / 2, x uniform: nodes crowd both ends of each uniform,
// where the visible-normal warp sends its tails (steep facets: total internal reflection,
// grazing exits). Weights (pi / 2) sin(pi x) / n; about 1e-3 absolute error at n = 64
// where the uniform midpoint rule had 3e-3 at n = 48 (Beckmann, alpha 0.3, from inside).
Rule cosine_spaced(int n) {
    Rule r{std::vector<double>(n), std::vector<double>(n)};
    for (int i = 0; i < n; ++i) {
        double x = (i + 0.5) / n;
        r.x[i] = 0.5 * (1.0 - std::cos(kPi * x));
        r.w[i] = 0.5 * kPi * std::sin(kPi * x) / n;
    }
    return r;
}

double node_mu(int k) {
    double t = static_cast<double>(k) / (MultiScatter::kNodes - 1);
    return std::max(t * t, 1e-6);
}
} // namespace

MultiScatter::MultiScatter(const Microfacet &mf, std::shared_ptr<const FresnelTerm> term)
    : term_(std::move(term)), channels_(term_->channels()), transmits_(term_->transmissive()),
      eta_(term_->eta()), film_(dynamic_cast<const FilmTerm *>(term_.get()) != nullptr) {
    const int C = channels_, N = kNodes, M = kGrid, sides = transmits_ ? 2 : 1;
    std::vector<double> R(C), T(C), acc(C);
    Query nominal;
    const Rule grid = cosine_spaced(M);
    for (int side = 0; side < sides; ++side) {
        table_[side].assign(static_cast<std::size_t>(N) * C, 0.0);
        for (int k = 0; k < N; ++k) {
            double mu = node_mu(k);
            Vec3 wi{std::sqrt(std::max(0.0, 1.0 - mu * mu)), 0.0, side == 0 ? mu : -mu};
            Vec3 wi_up = side == 0 ? wi : -wi;
            std::fill(acc.begin(), acc.end(), 0.0);
            for (int a = 0; a < M; ++a)
                for (int b = 0; b < M; ++b) {
                    Vec3 m = mf.sample_visible(wi_up, grid.x[a], grid.x[b]);
                    const double w = grid.w[a] * grid.w[b];
                    double dim = dot(wi, m);
                    if (transmits_) {
                        term_->eval(dim, nominal, R.data(), T.data());
                    } else {
                        std::fill(R.begin(), R.end(), 1.0); // white: the F = 1 albedo
                        std::fill(T.begin(), T.end(), 0.0);
                    }
                    Vec3 wr = m * (2.0 * dim) - wi;
                    double gr = wr.z * wi.z > 0 ? mf.G1(wr, m) : 0.0, gt = 0.0;
                    if (transmits_) {
                        DielectricFresnel f = fresnel_dielectric(dim, eta_);
                        if (f.cos_theta_t != 0.0) {
                            Vec3 wt = m * (dim * f.eta_ti + f.cos_theta_t) - wi * f.eta_ti;
                            if (wt.z * wi.z < 0) gt = mf.G1(wt, m);
                        }
                    }
                    for (int c = 0; c < C; ++c) acc[c] += w * (R[c] * gr + T[c] * gt);
                }
            for (int c = 0; c < C; ++c) table_[side][k * C + c] = std::min(1.0, acc[c]);
        }
        // E_avg = 2 int E mu dmu = int E(t) 4 t^3 dt, E linear in t on each segment.
        Rule g = gauss_legendre(3);
        avg_[side].assign(C, 0.0);
        double h = 1.0 / (N - 1);
        for (int k = 0; k + 1 < N; ++k)
            for (int j = 0; j < 3; ++j) {
                double t = (k + g.x[j]) * h;
                for (int c = 0; c < C; ++c) {
                    double e =
                        (1 - g.x[j]) * table_[side][k * C + c] + g.x[j] * table_[side][(k + 1) * C + c];
                    avg_[side][c] += g.w[j] * h * e * 4.0 * t * t * t;
                }
            }
    }
    if (transmits_) {
        // Average Fresnel transmittance of the less dense side; the dense side's share
        // from reciprocity (header comment).
        Rule g = gauss_legendre(24);
        const int light = eta_ >= 1.0 ? 0 : 1, dense = 1 - light;
        const double eta2 = eta_ >= 1.0 ? eta_ * eta_ : 1.0 / (eta_ * eta_); // (n_dense / n_light)^2
        std::vector<double> t_avg(C, 0.0);
        for (int j = 0; j < 24; ++j) {
            double mu = g.x[j];
            term_->eval(light == 0 ? mu : -mu, nominal, R.data(), T.data());
            for (int c = 0; c < C; ++c) t_avg[c] += g.w[j] * 2.0 * mu * T[c];
        }
        for (int s = 0; s < 2; ++s) transmit_share_[s].assign(C, 0.0);
        for (int c = 0; c < C; ++c) {
            double loss_l = 1.0 - avg_[light][c], loss_d = 1.0 - avg_[dense][c];
            double tl = std::clamp(t_avg[c], 0.0, 1.0), td = 0.0;
            if (loss_d > 1e-12 && loss_l > 1e-12) {
                td = tl * loss_l / (eta2 * loss_d);
                if (td > 1.0) {
                    td = 1.0;
                    tl = eta2 * loss_d / loss_l;
                }
            } else {
                tl = 0.0; // no loss on one side: no lobe through the interface
            }
            transmit_share_[light][c] = tl;
            transmit_share_[dense][c] = td;
        }
    } else {
        tint_.assign(C, 0.0);
        conductor_tint(nominal, tint_.data());
    }
}

void MultiScatter::conductor_tint(const Query &q, double *tint) const {
    static const Rule g = gauss_legendre(24);
    const int C = channels_;
    double *R = ms_buffer(0, C), *T = ms_buffer(1, C);
    for (int c = 0; c < C; ++c) tint[c] = 0.0;
    for (int j = 0; j < 24; ++j) {
        term_->eval(g.x[j], q, R, T);
        for (int c = 0; c < C; ++c) tint[c] += g.w[j] * 2.0 * g.x[j] * R[c];
    }
    const double e = avg_[0][0];
    for (int c = 0; c < C; ++c) {
        double f = std::clamp(tint[c], 0.0, 1.0), denom = 1.0 - f * (1.0 - e);
        tint[c] = denom > 0 ? f * f * e / denom : 0.0;
    }
}

double MultiScatter::interpolate(const std::vector<double> &table, double mu, int c) const {
    double t = std::sqrt(std::clamp(mu, 0.0, 1.0)) * (kNodes - 1);
    int k = std::min(static_cast<int>(t), kNodes - 2);
    double f = t - k;
    return (1 - f) * table[k * channels_ + c] + f * table[(k + 1) * channels_ + c];
}

double MultiScatter::albedo(int side, double mu, int c) const {
    int s = transmits_ ? std::clamp(side, 0, 1) : 0;
    return interpolate(table_[s], mu, std::clamp(c, 0, channels_ - 1));
}

void MultiScatter::eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const {
    const int C = channels_;
    for (int c = 0; c < C; ++c) out[c] = 0.0;
    const bool reflect = wi.z * wo.z > 0;
    if (!(lobes & (reflect ? kGlossyReflection : kGlossyTransmission))) return;
    const double mi = std::abs(wi.z), mo = std::abs(wo.z);
    if (!transmits_) {
        if (!(wi.z > 0 && wo.z > 0)) return;
        const double *tint = tint_.data();
        if (film_ && q.film_thickness_nm >= 0) { // the tint at this thickness
            thread_local std::vector<double> local;
            local.resize(C);
            conductor_tint(q, local.data());
            tint = local.data();
        }
        const double loss = 1.0 - avg_[0][0];
        if (!(loss > 1e-12)) return;
        double k =
            (1.0 - interpolate(table_[0], mi, 0)) * (1.0 - interpolate(table_[0], mo, 0)) * mo / (kPi * loss);
        for (int c = 0; c < C; ++c) out[c] = tint[c] * k;
        return;
    }
    const int si = wi.z > 0 ? 0 : 1, so = wo.z > 0 ? 0 : 1;
    // Radiance scaling (n_i / n_t)^2 of transmission, as the single-scattering lobe.
    const double scale = reflect ? 1.0 : (si == 0 ? 1.0 / (eta_ * eta_) : eta_ * eta_);
    for (int c = 0; c < C; ++c) {
        double loss_o = 1.0 - avg_[so][c];
        if (!(loss_o > 1e-12)) continue;
        double share = reflect ? 1.0 - transmit_share_[si][c] : transmit_share_[si][c];
        double v = scale * share * (1.0 - interpolate(table_[si], mi, c)) *
                   (1.0 - interpolate(table_[so], mo, c)) * mo / (kPi * loss_o);
        out[c] = std::isfinite(v) ? v : 0.0;
    }
}

void MultiScatter::probabilities(const Vec3 &wi, uint32_t lobes, double &p_lobe, double &p_reflect) const {
    p_lobe = 0.0;
    p_reflect = 0.0;
    const bool want_r = lobes & kGlossyReflection, want_t = transmits_ && (lobes & kGlossyTransmission);
    const double mu = std::abs(wi.z);
    const int C = channels_, si = (transmits_ && wi.z < 0) ? 1 : 0;
    double ms_r = 0, ms_t = 0, ss = 0;
    for (int c = 0; c < C; ++c) {
        double e = interpolate(table_[si], mu, c);
        if (transmits_) {
            double share = transmit_share_[si][c];
            ms_r += (1.0 - share) * (1.0 - e);
            ms_t += share * (1.0 - e);
            ss += e;
        } else {
            ms_r += tint_[c] * (1.0 - e);
            ss += e; // a white conductor's; only the split's efficiency depends on it
        }
    }
    if (!want_r) ms_r = 0;
    if (!want_t) ms_t = 0;
    double ms = ms_r + ms_t;
    if (!(ms > 0)) return;
    p_lobe = ms / (ms + ss);
    p_reflect = ms_r / ms;
}

double MultiScatter::pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes) const {
    double p_lobe, p_reflect;
    probabilities(wi, lobes, p_lobe, p_reflect);
    const bool reflect = wi.z * wo.z > 0;
    if (!transmits_ && !(wi.z > 0 && wo.z > 0)) return 0.0;
    return p_lobe * (reflect ? p_reflect : 1.0 - p_reflect) * std::abs(wo.z) * kInvPi;
}

} // namespace bsdflab
