// Discretisation of the adding-doubling solver: nodes, the Fourier kernels of the core's
// BSDFs, delta weights, and Henyey-Greenstein coefficients (adding_doubling_ops.h).
#include <algorithm>
#include <cmath>
#include "bsdflab/adding_doubling_ops.h"
#include "bsdflab/constants.h"
#include "bsdflab/parallel.h"
#include "bsdflab/quadrature.h"

namespace bsdflab::ad {

namespace {

// cos(m k pi / H) for k = 0..H, m < M, and the trapezoid weights of the half period.
struct CosineTable {
    int H, M;
    std::vector<double> c, wk;
    CosineTable(int H_, int M_) : H(H_), M(M_), c((H_ + 1) * M_), wk(H_ + 1, 1.0 / H_) {
        for (int k = 0; k <= H; ++k)
            for (int m = 0; m < M; ++m) c[k * M + m] = std::cos(kPi * double(k) * m / H);
        wk[0] = wk[H] = 0.5 / H;
    }
};

} // namespace

static std::vector<double> panel_cuts(std::vector<double> breaks) {
    breaks.push_back(0.0);
    breaks.push_back(1.0);
    std::sort(breaks.begin(), breaks.end());
    std::vector<double> cuts;
    for (double b : breaks)
        if (b >= 0.0 && b <= 1.0 && (cuts.empty() || b - cuts.back() > 1e-9)) cuts.push_back(b);
    return cuts;
}

// The panel variable u in [0, 1] of mu on panel [a, b] (see panel_nodes).
static double panel_u(double a, double b, double mu) {
    if (a == 0.0) return mu / b;
    return std::sqrt(std::max(0.0, (mu - a) * (mu + a) / ((b - a) * (b + a))));
}

void panel_nodes(int per_panel, std::vector<double> breaks, std::vector<double> &mu, std::vector<double> &w) {
    std::vector<double> cuts = panel_cuts(std::move(breaks));
    std::vector<double> x, wx;
    gauss_legendre(per_panel, x, wx);
    mu.clear();
    w.clear();
    for (std::size_t p = 0; p + 1 < cuts.size(); ++p) {
        double a = cuts[p], b = cuts[p + 1];
        for (int i = 0; i < per_panel; ++i) {
            double u = 0.5 * (x[i] + 1.0), wu = 0.5 * wx[i];
            if (a == 0.0) {
                mu.push_back(b * u);
                w.push_back(b * wu);
            } else {
                double span = (b - a) * (b + a), m = std::sqrt(a * a + span * u * u);
                mu.push_back(m);
                w.push_back(wu * span * u / m);
            }
        }
    }
}

void product_nodes(int per_panel, std::vector<double> breaks, double h, std::vector<double> &mu_f,
                   std::vector<double> &w_f, std::vector<double> &B) {
    std::vector<double> cuts = panel_cuts(std::move(breaks));
    std::vector<double> x, wx, g4, w4;
    gauss_legendre(per_panel, x, wx);
    gauss_legendre(4, g4, w4);
    const int P = static_cast<int>(cuts.size()) - 1, n = P * per_panel;
    std::vector<double> u(per_panel), bary(per_panel);
    for (int i = 0; i < per_panel; ++i) u[i] = 0.5 * (x[i] + 1.0);
    for (int i = 0; i < per_panel; ++i) {  // barycentric weights of the panel's nodes
        double prod = 1.0;
        for (int j = 0; j < per_panel; ++j)
            if (j != i) prod *= u[i] - u[j];
        bary[i] = 1.0 / prod;
    }
    mu_f.clear();
    w_f.clear();
    B.clear();
    for (int p = 0; p < P; ++p) {
        double a = cuts[p], b = cuts[p + 1];
        double t_lo = std::acos(b), t_hi = std::acos(a);
        int S = std::max(1, static_cast<int>(std::ceil((t_hi - t_lo) / h)));
        for (int s = 0; s < S; ++s)
            for (int q = 0; q < 4; ++q) {
                double lo = t_lo + (t_hi - t_lo) * s / S, hi = t_lo + (t_hi - t_lo) * (s + 1) / S;
                double t = 0.5 * (lo + hi) + 0.5 * (hi - lo) * g4[q];
                double m = std::cos(t);
                mu_f.push_back(m);
                w_f.push_back(0.5 * (hi - lo) * w4[q] * std::sin(t));
                std::vector<double> row(n, 0.0);
                double v = panel_u(a, b, m), den = 0.0;
                int exact = -1;
                for (int i = 0; i < per_panel; ++i) {
                    if (v == u[i]) exact = i;
                    den += bary[i] / (v - u[i]);
                }
                for (int i = 0; i < per_panel; ++i)
                    row[p * per_panel + i] =
                        exact >= 0 ? (i == exact ? 1.0 : 0.0) : bary[i] / (v - u[i]) / den;
                B.insert(B.end(), row.begin(), row.end());
            }
    }
}

// a[c][m] += sum_k S[k][c] T[k][m] (S: K x C samples, T: K x M cosines, a: C x M), in
// 4 x 4 register tiles: the transform costs C M per sample, more than the BSDF's eval.
static void cosine_transform(const double *S, const double *T, int K, int C, int M, double *a) {
    int c0 = 0;
    for (; c0 + 4 <= C; c0 += 4) {
        int m0 = 0;
        for (; m0 + 4 <= M; m0 += 4) {
            double acc[4][4] = {};
            for (int k = 0; k < K; ++k) {
                const double *s = S + k * C + c0, *t = T + k * M + m0;
                for (int i = 0; i < 4; ++i)
                    for (int j = 0; j < 4; ++j) acc[i][j] += s[i] * t[j];
            }
            for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j) a[(c0 + i) * M + m0 + j] += acc[i][j];
        }
        for (; m0 < M; ++m0)
            for (int k = 0; k < K; ++k)
                for (int i = 0; i < 4; ++i) a[(c0 + i) * M + m0] += S[k * C + c0 + i] * T[k * M + m0];
    }
    for (; c0 < C; ++c0)
        for (int k = 0; k < K; ++k) {
            double s = S[k * C + c0];
            for (int m = 0; m < M; ++m) a[c0 * M + m] += s * T[k * M + m];
        }
}

// The cosine coefficients a[c][m] of f = eval(wi, wo) / |zi| over the azimuth difference
// for one pair of cosines (wi.z = zo, wo.z = zi); S holds (H + 1) x C samples.
static void pair_coefficients(const BSDF &b, double zo, double zi, const CosineTable &table,
                              std::vector<double> &S, Query &q, double *a) {
    const int C = b.channels(), M = table.M, H = table.H;
    double so = std::sqrt(std::max(0.0, 1.0 - zo * zo));
    double si = std::sqrt(std::max(0.0, 1.0 - zi * zi));
    Vec3 wo{si, 0.0, zi};
    for (int k = 0; k <= H; ++k) {
        double d = kPi * k / H;
        Vec3 wi{-so * std::cos(d), -so * std::sin(d), zo};
        double *f = &S[k * C];
        b.eval(wi, wo, kAll, q, f);
        for (int c = 0; c < C; ++c) {
            double v = f[c] / std::abs(zi) * table.wk[k];
            f[c] = std::isfinite(v) ? v : 0.0;
        }
    }
    std::fill(a, a + C * M, 0.0);
    cosine_transform(S.data(), table.c.data(), H + 1, C, M, a);
    for (int c = 0; c < C; ++c)
        for (int m = 1; m < M; ++m) a[c * M + m] *= 2.0;
}

std::vector<double> fourier_kernel(const BSDF &b, const std::vector<double> &out_z,
                                   const std::vector<double> &in_z, int M, int H) {
    const int C = b.channels();
    const std::size_t rows = out_z.size(), cols = in_z.size();
    std::vector<double> out(rows * cols * C * M, 0.0);
    CosineTable table(H, M);
    parallel_for(rows * cols, 16, [&](std::size_t begin, std::size_t end) {
        std::vector<double> S((H + 1) * C);
        Query q;
        for (std::size_t p = begin; p < end; ++p)
            pair_coefficients(b, out_z[p / cols], in_z[p % cols], table, S, q, &out[p * C * M]);
    });
    return out;
}

std::vector<double> projected_kernel(const BSDF &b, const std::vector<double> &fine_z,
                                     const std::vector<double> &other_z, bool fine_rows,
                                     const std::vector<double> &B, const std::vector<double> &scale, int n,
                                     int M, int H) {
    const std::size_t C = b.channels(), cm = C * M, nf = fine_z.size(), other = other_z.size();
    std::vector<double> out(static_cast<std::size_t>(n) * other * cm, 0.0);
    CosineTable table(H, M);
    // One column (or row) of the coarse result per task: the fine kernel is never stored.
    parallel_for(other, 1, [&](std::size_t begin, std::size_t end) {
        std::vector<double> S((H + 1) * C), a(cm);
        Query q;
        for (std::size_t o = begin; o < end; ++o)
            for (std::size_t f = 0; f < nf; ++f) {
                bool any = false;
                for (int k = 0; k < n && !any; ++k) any = B[f * n + k] != 0.0;
                if (!any) continue;
                if (fine_rows) pair_coefficients(b, fine_z[f], other_z[o], table, S, q, a.data());
                else pair_coefficients(b, other_z[o], fine_z[f], table, S, q, a.data());
                for (int k = 0; k < n; ++k) {
                    double w = B[f * n + k] * scale[f * n + k];
                    if (w == 0.0) continue;
                    double *dst = fine_rows ? &out[(k * other + o) * cm] : &out[(o * n + k) * cm];
                    for (std::size_t x = 0; x < cm; ++x) dst[x] += w * a[x];
                }
            }
    });
    return out;
}

void delta_weight(const BSDF &b, double z, uint32_t lobe, double *out, double *cos_out) {
    Vec3 wi{std::sqrt(std::max(0.0, 1.0 - z * z)), 0.0, z};
    Query q;
    BSDFSample s = b.sample(wi, 0.5, 0.5, 0.5, lobe, q, out);
    if (!s.lobe) {
        for (int c = 0; c < b.channels(); ++c) out[c] = 0.0;
        if (cos_out) *cos_out = 0.0;
        return;
    }
    if (cos_out) *cos_out = std::abs(s.wo.z);
}

std::vector<double> hg_coefficients(double g, const std::vector<double> &mu, int M, bool same) {
    const std::size_t N = mu.size();
    std::vector<double> out(M * N * N, 0.0);
    if (g == 0.0) {
        for (std::size_t i = 0; i < N * N; ++i) out[i] = 1.0 / (4.0 * kPi);
        return out;
    }
    int H = 64;
    while (H < 2 * M) H *= 2;
    CosineTable table(H, M);
    const double sign = same ? 1.0 : -1.0, norm = (1.0 - g * g) / (4.0 * kPi);
    for (std::size_t i = 0; i < N; ++i)
        for (std::size_t j = 0; j < N; ++j) {
            double a = sign * mu[i] * mu[j];
            double b = std::sqrt(std::max(0.0, 1.0 - mu[i] * mu[i]) * std::max(0.0, 1.0 - mu[j] * mu[j]));
            for (int k = 0; k <= H; ++k) {
                double ct = std::clamp(a + b * std::cos(kPi * k / H), -1.0, 1.0);
                double d = 1.0 + g * g - 2.0 * g * ct;
                double v = norm / (d * std::sqrt(d)) * table.wk[k];
                for (int m = 0; m < M; ++m)
                    out[(m * N + i) * N + j] += v * table.c[k * M + m] * (m ? 2.0 : 1.0);
            }
        }
    return out;
}

} // namespace bsdflab::ad
