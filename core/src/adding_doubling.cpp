// The adding-doubling solver (adding_doubling.h): setup, the per-(wavelength, order)
// solve from the base up, and the evaluation of direction pairs.
#include "bsdflab/adding_doubling.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/adding_doubling_ops.h"
#include "bsdflab/constants.h"
#include "bsdflab/frame.h"
#include "bsdflab/interfaces.h"
#include "bsdflab/parallel.h"

namespace bsdflab {

using ad::Grid;
using ad::Layer;
using ad::Op;

namespace {

constexpr double kIndexTolerance = 1e-9;

bool is_delta(const BSDF &b) { return (b.lobes() & ~kDelta) == 0; }

double rough_alpha(const BSDF &b) {
    auto *r = dynamic_cast<const RoughInterface *>(&b);
    return r && !r->pass_through() ? r->microfacet().alpha() : 0.0;
}

// Distinct values of v (sorted) and, per entry of v, its index among them.
std::vector<double> distinct(const std::vector<double> &v, std::vector<int> &index) {
    std::vector<double> d(v);
    std::sort(d.begin(), d.end());
    d.erase(std::unique(d.begin(), d.end()), d.end());
    index.resize(v.size());
    for (std::size_t i = 0; i < v.size(); ++i)
        index[i] = static_cast<int>(std::lower_bound(d.begin(), d.end(), v[i]) - d.begin());
    return d;
}

std::vector<double> signed_cos(const std::vector<double> &mu, double sign) {
    std::vector<double> z(mu);
    for (double &x : z) x *= sign;
    return z;
}

// An operator's kernel at (channel c, order m) from fourier_kernel's layout.
std::vector<double> kernel_at(const std::vector<double> &coef, std::size_t rows, std::size_t cols, int C,
                              int M, int c, int m) {
    std::vector<double> K(rows * cols);
    for (std::size_t p = 0; p < rows * cols; ++p) K[p] = coef[(p * C + c) * M + m];
    return K;
}

// The channels whose inner reflection is solved: every stride-th and the last (all when
// fewer than 4 would remain; the rest are interpolated in wavelength).
std::vector<int> solved_channels(int C, int stride) {
    std::vector<int> out;
    for (int c = 0; c < C; c += std::max(1, stride)) out.push_back(c);
    if (out.back() != C - 1) out.push_back(C - 1);
    if (stride <= 1 || out.size() < 4) {
        out.resize(C);
        for (int c = 0; c < C; ++c) out[c] = c;
    }
    return out;
}

// sum_i w_i a_i over operators of one grid (an empty part counts as zero).
Op combine(const std::vector<const Op *> &ops, const std::vector<double> &w) {
    Op r;
    for (std::size_t i = 0; i < ops.size(); ++i) {
        auto acc = [&](std::vector<double> &dst, const std::vector<double> &src) {
            if (src.empty()) return;
            if (dst.empty()) dst.assign(src.size(), 0.0);
            for (std::size_t p = 0; p < src.size(); ++p) dst[p] += w[i] * src[p];
        };
        acc(r.D, ops[i]->D);
        acc(r.K, ops[i]->K);
    }
    return r;
}

} // namespace

int hg_orders_needed(double g, double tolerance) {
    if (g == 0.0) return 1;
    double y = std::acosh(1.0 + (1.0 - std::abs(g)) * (1.0 - std::abs(g)) / (2.0 * std::abs(g)));
    return static_cast<int>(std::ceil(-std::log(tolerance) / y)) + 2;
}

// What the solve needs of boundary j >= 1 at one grid: kernels (non-delta) or delta parts.
struct AddingDoubling::Boundary {
    bool delta = false, interior = false;
    std::vector<double> Rt, Td, Rb, Tu;  // fourier_kernel layout, or D as [c][i] when delta

    Op op(const std::vector<double> &a, std::size_t N, int C, int M, int c, int m) const {
        Op o;
        if (a.empty()) return o;
        if (delta) {
            o.D.assign(a.begin() + c * N, a.begin() + (c + 1) * N);
        } else {
            o.K = kernel_at(a, N, N, C, M, c, m);
        }
        return o;
    }
};

struct AddingDoubling::Inner {
    std::mutex mutex;
    bool ready = false;
    std::vector<Op> R;  // [channel * orders + order], on the nodes
};

std::shared_ptr<AddingDoubling> AddingDoubling::with_top(std::shared_ptr<const BSDF> top) const {
    if (!top || top->channels() != channels()) throw std::invalid_argument("top channel count mismatch");
    if (smooth_top_ || is_delta(*top)) throw std::invalid_argument("with_top needs rough tops");
    if (settings_.film_lookup) {
        FilmLookupStats stats;
        if (auto fast = top->with_film_lookup(-1.0, stats)) top = fast;
    }
    auto copy = std::make_shared<AddingDoubling>(*this);
    copy->boundaries_[0] = std::move(top);
    return copy;
}

AddingDoubling::AddingDoubling(std::vector<double> wavelengths,
                               std::vector<std::shared_ptr<const BSDF>> boundaries, std::vector<double> media,
                               std::vector<ADSlab> slabs, ADSettings settings)
    : wavelengths_(std::move(wavelengths)), boundaries_(std::move(boundaries)), media_(std::move(media)),
      slabs_(std::move(slabs)), settings_(settings) {
    const std::size_t K = slabs_.size();
    if (boundaries_.size() != K + 1) throw std::invalid_argument("need one boundary more than slabs");
    if (media_.size() != K + 2) throw std::invalid_argument("need K + 2 media indices");
    for (auto &b : boundaries_)
        if (!b || b->channels() != channels()) throw std::invalid_argument("boundary channel count mismatch");
    for (auto &s : slabs_)
        if (static_cast<int>(s.sigma_a.size()) != channels())
            throw std::invalid_argument("sigma_a needs one value per channel");
    if (settings_.nodes < 2) throw std::invalid_argument("nodes must be >= 2");
    if (!(settings_.thin_depth > 0)) throw std::invalid_argument("thin_depth must be > 0");
    if (settings_.spectral_stride < 1) throw std::invalid_argument("spectral_stride must be >= 1");
    if (!(settings_.fine_step > 0)) throw std::invalid_argument("fine_step must be > 0");
    if (settings_.film_lookup) {
        FilmLookupStats stats;
        for (auto &b : boundaries_)
            if (auto fast = b->with_film_lookup(-1.0, stats)) b = fast;
        film_lookup_error_ = stats.max_error;
    }
    smooth_top_ = is_delta(*boundaries_[0]);
    two_sided_ = smooth_top_ && K >= 1 && is_delta(*boundaries_[K]) && media_[K + 1] > 0;
    inner_ = std::make_shared<Inner>();
    for (std::size_t j = 0; j + 1 < media_.size(); ++j) {  // critical cosines of every index step
        double a = media_[j], b = media_[j + 1];
        if (a > 0 && b > 0 && std::abs(a - b) > kIndexTolerance * std::max(a, b)) {
            double r = std::min(a, b) / std::max(a, b);
            breaks_.push_back(std::sqrt((1.0 - r) * (1.0 + r)));
        }
    }
    ad::panel_nodes(settings_.nodes, breaks_, mu_, w_);
    // Fourier orders: what the slabs' phase functions and the boundaries below the top
    // carry (the top's own reflection is evaluated directly; below it, only orders the
    // stack under it scatters into survive the adding).
    double alpha_min = 1.0;
    int M = 1;
    for (auto &s : slabs_)
        if (s.sigma_s > 0 && s.thickness > 0)
            M = std::max(M, hg_orders_needed(s.g, settings_.order_tolerance));
    for (std::size_t j = 0; j < boundaries_.size(); ++j) {
        double a = rough_alpha(*boundaries_[j]);
        if (a > 0) alpha_min = std::min(alpha_min, a);
        if (j == 0 || is_delta(*boundaries_[j])) continue;
        if (a > 0) M = std::max(M, static_cast<int>(std::ceil(6.0 / a)) + 2);
        else if (boundaries_[j]->lobes() & (kGlossyReflection | kGlossyTransmission)) M = std::max(M, 64);
    }
    orders_ = settings_.orders > 0 ? settings_.orders : M;
    int H = 32;
    double need = std::max(4.0 * orders_, orders_ + 10.0 / alpha_min);
    while (2 * H < need && H < (1 << 14)) H *= 2;
    half_samples_ = settings_.azimuth_samples > 0 ? settings_.azimuth_samples : H;
}

void AddingDoubling::solve(const std::vector<double> &out_cos, const std::vector<double> &in_cos,
                           std::vector<double> &values, const Queries *two_sided) const {
    const int C = channels(), M = orders_, H = half_samples_;
    const int n = static_cast<int>(mu_.size());
    const std::size_t Qo = out_cos.size(), Qi = in_cos.size(), K = slabs_.size();
    // The grid: nodes, then (smooth top) the query cosines inside the first slab.
    std::vector<double> grid(mu_), extras;
    std::vector<int> xo(Qo), xi(Qi);
    if (two_sided) {
        grid.insert(grid.end(), two_sided->cosines.begin(), two_sided->cosines.end());
    } else if (smooth_top_) {
        std::vector<double> all(out_cos);
        all.insert(all.end(), in_cos.begin(), in_cos.end());
        std::vector<int> index;
        extras = distinct(all, index);
        for (std::size_t q = 0; q < Qo; ++q) xo[q] = n + index[q];
        for (std::size_t q = 0; q < Qi; ++q) xi[q] = n + index[Qo + q];
        grid.insert(grid.end(), extras.begin(), extras.end());
    }
    const std::size_t N = grid.size();
    const std::vector<double> up = grid, down = signed_cos(grid, -1.0);
    // A rough top's queries never enter below it: what lies there is solved once per
    // solver (and shared with with_top copies).
    std::unique_lock<std::mutex> lock(inner_->mutex, std::defer_lock);
    if (!smooth_top_) lock.lock();
    const bool cached = !smooth_top_ && inner_->ready;

    // Boundaries below the top.
    std::vector<Boundary> below(K + 1);
    for (std::size_t j = 1; j <= K && !cached; ++j) {
        const BSDF &b = *boundaries_[j];
        Boundary &B = below[j];
        B.interior = j < K;
        B.delta = is_delta(b);
        if (!B.delta) {
            B.Rt = ad::fourier_kernel(b, up, up, M, H);
            if (B.interior) {
                B.Td = ad::fourier_kernel(b, down, up, M, H);
                B.Rb = ad::fourier_kernel(b, down, down, M, H);
                B.Tu = ad::fourier_kernel(b, up, down, M, H);
            }
            continue;
        }
        if (B.interior && std::abs(media_[j] - media_[j + 1]) > kIndexTolerance * media_[j])
            throw std::invalid_argument("adding-doubling: a smooth interior interface must be index-matched");
        auto table = [&](double sign, uint32_t lobe) {
            std::vector<double> d(C * N), v(C);
            for (std::size_t i = 0; i < N; ++i) {
                ad::delta_weight(b, sign * grid[i], lobe, v.data(), nullptr);
                for (int c = 0; c < C; ++c) d[c * N + i] = v[c];
            }
            return d;
        };
        B.Rt = table(1.0, kDeltaReflection);
        if (B.interior) {
            B.Td = table(1.0, kDeltaTransmission);
            B.Rb = table(-1.0, kDeltaReflection);
            B.Tu = table(-1.0, kDeltaTransmission);
        }
    }
    // The top, seen from the first slab.
    const BSDF &top = *boundaries_[0];
    std::vector<double> topRb, topTd, topTu;
    if (smooth_top_) {
        topRb.assign(C * N, 0.0);
        std::vector<double> v(C);
        for (std::size_t i = 0; i < N; ++i) {
            ad::delta_weight(top, -grid[i], kDeltaReflection, v.data(), nullptr);
            for (int c = 0; c < C; ++c) topRb[c * N + i] = v[c];
        }
    } else {
        // The top's lobes are narrower than the nodes resolve: integrate them on fine
        // nodes against the (smooth) interpolant of what lies below.
        std::vector<double> mu_f, w_f, B;
        double h = std::clamp(rough_alpha(top) * settings_.fine_step, 0.004, 0.05);
        ad::product_nodes(settings_.nodes, breaks_, h, mu_f, w_f, B);
        const std::size_t nf = mu_f.size();
        std::vector<double> scale(nf * n);  // (mu_f w_f) / (mu_k w_k)
        for (std::size_t f = 0; f < nf; ++f)
            for (int k = 0; k < n; ++k) scale[f * n + k] = mu_f[f] * w_f[f] / (mu_[k] * w_[k]);
        const std::vector<double> fine_down = signed_cos(mu_f, -1.0);
        topRb = ad::projected_kernel(top, fine_down, down, true, B, scale, n, M, H);
        topTd = ad::projected_kernel(top, fine_down, in_cos, true, B, scale, n, M, H);
        topTu = ad::projected_kernel(top, fine_down, out_cos, false, B, scale, n, M, H);
    }
    // Phase-function coefficients per slab (orders beyond its own are unscattered).
    std::vector<int> slab_orders(K, 0);
    std::vector<std::vector<double>> pr(K), pt(K);
    for (std::size_t j = 0; j < K && !cached; ++j) {
        const ADSlab &s = slabs_[j];
        if (!(s.sigma_s > 0 && s.thickness > 0)) continue;
        slab_orders[j] =
            settings_.orders > 0 ? M : std::min(M, hg_orders_needed(s.g, settings_.order_tolerance));
        pr[j] = ad::hg_coefficients(s.g, grid, slab_orders[j], false);
        pt[j] = ad::hg_coefficients(s.g, grid, slab_orders[j], true);
    }

    auto make_grid = [&](int m) {
        Grid g;
        g.n = n;
        g.N = static_cast<int>(N);
        g.W.assign(N, 0.0);
        for (int i = 0; i < n; ++i) g.W[i] = (m == 0 ? 2.0 : 1.0) * kPi * mu_[i] * w_[i];
        return g;
    };
    auto identity = [&]() {
        Op o;
        o.D.assign(N, 1.0);
        return o;
    };
    auto exp_tau = [&](double tau) {
        Op o;
        o.D.resize(N);
        for (std::size_t i = 0; i < N; ++i) o.D[i] = std::exp(-tau / grid[i]);
        return o;
    };
    // Single-scattering layer of depth delta and albedo omega at order m.
    auto thin = [&](std::size_t j, int m, double delta, double omega, Op &R, Op &T) {
        const double *Pr = &pr[j][static_cast<std::size_t>(m) * N * N];
        const double *Pt = &pt[j][static_cast<std::size_t>(m) * N * N];
        R.K.assign(N * N, 0.0);
        T.K.assign(N * N, 0.0);
        for (std::size_t i = 0; i < N; ++i)
            for (std::size_t k = 0; k < N; ++k) {
                double mo = grid[i], mi = grid[k];
                R.K[i * N + k] =
                    omega * Pr[i * N + k] * -std::expm1(-delta * (1.0 / mo + 1.0 / mi)) / (mo + mi);
                double x = 1.0 / mi - 1.0 / mo;
                double h = std::abs(delta * x) < 1e-8 ? delta * (1.0 - 0.5 * delta * x)
                                                      : -std::expm1(-delta * x) / x;
                T.K[i * N + k] = omega * Pt[i * N + k] * std::exp(-delta / mo) * h / (mo * mi);
            }
        T.D = exp_tau(delta).D;
        R.D.clear();
    };
    // Slab j as a layer (all four operators; it is up-down symmetric).
    auto slab_layer = [&](std::size_t j, int c, int m, const Grid &g) -> Layer {
        const ADSlab &s = slabs_[j];
        double sigma_t = s.sigma_a[c] + s.sigma_s, tau = sigma_t * s.thickness;
        if (!(tau > 0)) return Layer{Op(), identity(), Op(), identity()};
        double omega = sigma_t > 0 ? s.sigma_s / sigma_t : 0.0;
        if (!(omega > 0) || m >= slab_orders[j]) return Layer{Op(), exp_tau(tau), Op(), exp_tau(tau)};
        int k = std::max(0, static_cast<int>(std::ceil(std::log2(tau / settings_.thin_depth))));
        double delta = tau / std::ldexp(1.0, k);
        // Richardson start: 2 (doubled half layer) - (single layer) cancels the O(delta^2)
        // multiple scattering the single-scattering layer misses.
        Op R1, T1, Rs, Ts;
        thin(j, m, delta, omega, R1, T1);
        thin(j, m, 0.5 * delta, omega, Rs, Ts);
        ad::double_symmetric(Rs, Ts, g);
        for (std::size_t p = 0; p < N * N; ++p) {
            Rs.K[p] = 2.0 * Rs.K[p] - R1.K[p];
            Ts.K[p] = 2.0 * Ts.K[p] - T1.K[p];
        }
        Rs.D.clear();
        Ts.D = T1.D;
        for (int d = 1; d <= k; ++d) {
            ad::double_symmetric(Rs, Ts, g);
            Ts.D = exp_tau(delta * std::ldexp(1.0, d)).D;  // the unscattered beam exactly
        }
        return Layer{Rs, Ts, Rs, Ts};
    };
    auto slab = [&](std::size_t j, int c, int m, const Grid &g, const Op &R) -> Op {
        const ADSlab &s = slabs_[j];
        double tau = (s.sigma_a[c] + s.sigma_s) * s.thickness;
        if (!(tau > 0)) return R;
        Layer L = slab_layer(j, c, m, g);
        if (L.Rt.K.empty()) return ad::mul(L.Td, ad::mul(R, L.Td, g), g);  // no scattering
        return ad::reflect_over(L, R, g);
    };
    // Reflection of everything below the top (seen from the first slab), from the base up.
    auto inner = [&](int c, int m, const Grid &g) -> Op {
        Op R = below[K].op(below[K].Rt, N, C, M, c, m);
        for (std::size_t j = K; j-- > 0;) {
            R = slab(j, c, m, g, R);
            if (j >= 1) {
                const Boundary &B = below[j];
                Layer L{B.op(B.Rt, N, C, M, c, m), B.op(B.Td, N, C, M, c, m), B.op(B.Rb, N, C, M, c, m),
                        B.op(B.Tu, N, C, M, c, m)};
                R = ad::reflect_over(L, R, g);
            }
        }
        return R;
    };
    if (!smooth_top_ && !cached) {
        // Solved at every spectral_stride-th channel, the rest interpolated in wavelength
        // (cubic Lagrange on the 4 nearest solved channels).
        const std::vector<int> solved = solved_channels(C, settings_.spectral_stride);
        const std::size_t S = solved.size();
        inner_->R.assign(static_cast<std::size_t>(C) * M, Op());
        parallel_for_each(S * M, [&](std::size_t t) {
            int c = solved[t / M], m = static_cast<int>(t % M);
            inner_->R[static_cast<std::size_t>(c) * M + m] = inner(c, m, make_grid(m));
        });
        std::vector<char> is_solved(C, 0);
        for (int c : solved) is_solved[c] = 1;
        parallel_for_each(static_cast<std::size_t>(C) * M, [&](std::size_t task) {
            const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
            if (is_solved[c]) return;
            std::size_t hi = std::upper_bound(solved.begin(), solved.end(), c) - solved.begin();
            std::size_t j0 = std::min(S - 4, hi < 2 ? 0 : hi - 2);
            std::vector<const Op *> ops;
            std::vector<double> w;
            for (std::size_t i = j0; i < j0 + 4; ++i) {
                double l = 1.0, x = wavelengths_[c];
                for (std::size_t j = j0; j < j0 + 4; ++j)
                    if (j != i)
                        l *= (x - wavelengths_[solved[j]]) /
                             (wavelengths_[solved[i]] - wavelengths_[solved[j]]);
                ops.push_back(&inner_->R[static_cast<std::size_t>(solved[i]) * M + m]);
                w.push_back(l);
            }
            inner_->R[task] = combine(ops, w);
        });
        inner_->ready = true;
    }

    if (two_sided) {
        // The whole stack as one layer, top down: the top's internal reflection, then slab,
        // boundary, ..., slab, and the base's internal reflection (their transmissions to the
        // outside are applied by the caller).
        const std::size_t P = two_sided->op.size();
        values.assign(static_cast<std::size_t>(C) * M * P, 0.0);
        parallel_for_each(static_cast<std::size_t>(C) * M, [&](std::size_t task) {
            const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
            const Grid g = make_grid(m);
            Layer S{Op(), identity(), Op(), identity()};
            S.Rb.D.assign(topRb.begin() + c * N, topRb.begin() + (c + 1) * N);
            for (std::size_t j = 0; j < K; ++j) {
                S = ad::add_layers(S, slab_layer(j, c, m, g), g);
                const Boundary &B = below[j + 1];
                Op rt = B.op(B.Rt, N, C, M, c, m);
                Layer L = j + 1 < K ? Layer{rt, B.op(B.Td, N, C, M, c, m), B.op(B.Rb, N, C, M, c, m),
                                            B.op(B.Tu, N, C, M, c, m)}
                                    : Layer{rt, identity(), Op(), identity()};
                S = ad::add_layers(S, L, g);
            }
            const Op *ops[4] = {&S.Rt, &S.Td, &S.Rb, &S.Tu};
            double *V = &values[task * P];
            for (std::size_t p = 0; p < P; ++p) {
                const Op &o = *ops[two_sided->op[p]];
                if (!o.K.empty()) V[p] = o.K[(n + two_sided->row[p]) * N + n + two_sided->col[p]];
            }
        });
        return;
    }
    values.assign(static_cast<std::size_t>(C) * M * Qo * Qi, 0.0);
    parallel_for_each(static_cast<std::size_t>(C) * M, [&](std::size_t task) {
        const int c = static_cast<int>(task / M), m = static_cast<int>(task % M);
        const Grid g = make_grid(m);
        const Op R = smooth_top_ ? inner(c, m, g) : inner_->R[task];
        if (R.D.empty() && R.K.empty()) return;
        Op Rb;
        if (smooth_top_) Rb.D.assign(topRb.begin() + c * N, topRb.begin() + (c + 1) * N);
        else Rb.K = kernel_at(topRb, N, N, C, M, c, m);
        Op Y = ad::mul(ad::inverse_one_minus(ad::mul(R, Rb, g), g), R, g);
        double *V = &values[task * Qo * Qi];
        if (smooth_top_) {
            if (Y.K.empty()) return;
            for (std::size_t a = 0; a < Qo; ++a)
                for (std::size_t b = 0; b < Qi; ++b) V[a * Qi + b] = Y.K[xo[a] * N + xi[b]];
            return;
        }
        // Tu W (Y_D + Y_K W) Td at the query cosines.
        std::vector<double> Td = kernel_at(topTd, N, Qi, C, M, c, m);
        std::vector<double> Tu = kernel_at(topTu, Qo, N, C, M, c, m);
        std::vector<double> Z(N * Qi, 0.0);  // (Y_D + Y_K W) Td
        for (std::size_t i = 0; i < N; ++i) {
            double *z = &Z[i * Qi];
            if (!Y.D.empty())
                for (std::size_t b = 0; b < Qi; ++b) z[b] = Y.D[i] * Td[i * Qi + b];
            if (!Y.K.empty())
                for (int k = 0; k < n; ++k) {
                    double s = Y.K[i * N + k] * g.W[k];
                    if (s == 0.0) continue;
                    for (std::size_t b = 0; b < Qi; ++b) z[b] += s * Td[k * Qi + b];
                }
        }
        for (std::size_t a = 0; a < Qo; ++a)
            for (int k = 0; k < n; ++k) {
                double s = Tu[a * N + k] * g.W[k];
                if (s == 0.0) continue;
                for (std::size_t b = 0; b < Qi; ++b) V[a * Qi + b] += s * Z[k * Qi + b];
            }
    });
}

void AddingDoubling::eval_two_sided(const double *wi_, const double *wo_, std::size_t count,
                                    double *out) const {
    const int C = channels(), M = orders_;
    const std::size_t K = slabs_.size();
    const BSDF &top = *boundaries_[0], &base = *boundaries_[K];
    std::vector<std::size_t> active;
    std::vector<double> cosines, scale;  // per active pair: (viewer, light) inside cosines
    std::vector<int> op;
    std::vector<double> tv(C), tl(C);
    for (std::size_t p = 0; p < count; ++p) {
        Vec3 wi{wi_[3 * p], wi_[3 * p + 1], wi_[3 * p + 2]}, wo{wo_[3 * p], wo_[3 * p + 1], wo_[3 * p + 2]};
        if (!usable_direction(wi) || !usable_direction(wo) || wi.z == 0 || wo.z == 0) continue;
        const bool view_up = wi.z > 0, light_up = wo.z > 0;
        double mu_v = 0, mu_l = 0;
        ad::delta_weight(view_up ? top : base, wi.z, kDeltaTransmission, tv.data(), &mu_v);
        ad::delta_weight(light_up ? top : base, wo.z, kDeltaTransmission, tl.data(), &mu_l);
        if (!(mu_v > 0) || !(mu_l > 0)) continue;
        // The delta weights carry the radiance scaling of both crossings; the light's
        // solid angle inside is (n_out / n_in)^2 times its own outside.
        double r = light_up ? media_[1] / media_[0] : media_[K] / media_[K + 1];
        for (int c = 0; c < C; ++c) scale.push_back(tv[c] * tl[c] * r * r * std::abs(wo.z));
        op.push_back(view_up ? (light_up ? 0 : 3) : (light_up ? 1 : 2));
        cosines.push_back(mu_v);
        cosines.push_back(mu_l);
        active.push_back(p);
    }
    if (active.empty()) return;
    Queries q;
    std::vector<int> index;
    q.cosines = distinct(cosines, index);
    q.op = op;
    for (std::size_t a = 0; a < active.size(); ++a) {
        q.row.push_back(index[2 * a]);
        q.col.push_back(index[2 * a + 1]);
    }
    std::vector<double> V;
    solve({}, {}, V, &q);
    const std::size_t P = active.size();
    parallel_for(P, 256, [&](std::size_t begin, std::size_t end) {
        std::vector<double> cm(M);
        for (std::size_t a = begin; a < end; ++a) {
            std::size_t p = active[a];
            double dphi =
                std::atan2(wi_[3 * p + 1], wi_[3 * p]) - std::atan2(wo_[3 * p + 1], wo_[3 * p]) - kPi;
            for (int m = 0; m < M; ++m) cm[m] = std::cos(m * dphi);
            for (int c = 0; c < C; ++c) {
                double s = 0.0;
                for (int m = 0; m < M; ++m) s += V[(static_cast<std::size_t>(c) * M + m) * P + a] * cm[m];
                double v = s * scale[a * C + c];
                out[p * C + c] = std::isfinite(v) ? v : 0.0;
            }
        }
    });
}

void AddingDoubling::eval(const double *wi_, const double *wo_, std::size_t count, double *out,
                          bool scattered_only) const {
    const int C = channels(), M = orders_;
    std::fill(out, out + count * C, 0.0);
    if (two_sided_) return eval_two_sided(wi_, wo_, count, out);
    std::vector<std::size_t> active;
    std::vector<double> cos_out, cos_in, scale;  // scale: per active pair and channel
    const BSDF &top = *boundaries_[0];
    std::vector<double> tv(C), tl(C);
    for (std::size_t p = 0; p < count; ++p) {
        Vec3 wi{wi_[3 * p], wi_[3 * p + 1], wi_[3 * p + 2]}, wo{wo_[3 * p], wo_[3 * p + 1], wo_[3 * p + 2]};
        if (!usable_direction(wi) || !usable_direction(wo) || !(wi.z > 0) || !(wo.z > 0)) continue;
        double mu_v = wi.z, mu_l = wo.z;
        if (smooth_top_) {
            ad::delta_weight(top, wi.z, kDeltaTransmission, tv.data(), &mu_v);
            ad::delta_weight(top, wo.z, kDeltaTransmission, tl.data(), &mu_l);
            if (!(mu_v > 0) || !(mu_l > 0)) continue;
            double r = media_[1] / media_[0];
            for (int c = 0; c < C; ++c) scale.push_back(tv[c] * tl[c] * r * r * wo.z);
        } else {
            for (int c = 0; c < C; ++c) scale.push_back(wo.z);
        }
        active.push_back(p);
        cos_out.push_back(mu_v);
        cos_in.push_back(mu_l);
    }
    if (active.empty()) return;
    std::vector<int> io, ii;
    std::vector<double> qo = distinct(cos_out, io), qi = distinct(cos_in, ii);
    std::vector<double> V;
    solve(qo, qi, V);
    const std::size_t Qo = qo.size(), Qi = qi.size();
    parallel_for(active.size(), 256, [&](std::size_t begin, std::size_t end) {
        std::vector<double> direct(C), cm(M);
        Query q;
        for (std::size_t a = begin; a < end; ++a) {
            std::size_t p = active[a];
            Vec3 wi{wi_[3 * p], wi_[3 * p + 1], wi_[3 * p + 2]},
                wo{wo_[3 * p], wo_[3 * p + 1], wo_[3 * p + 2]};
            double dphi = std::atan2(wi.y, wi.x) - std::atan2(wo.y, wo.x) - kPi;
            for (int m = 0; m < M; ++m) cm[m] = std::cos(m * dphi);
            if (!smooth_top_ && !scattered_only) top.eval(wi, wo, kAll, q, direct.data());
            std::size_t cell = io[a] * Qi + ii[a];
            for (int c = 0; c < C; ++c) {
                double s = 0.0;
                for (int m = 0; m < M; ++m)
                    s += V[(static_cast<std::size_t>(c) * M + m) * Qo * Qi + cell] * cm[m];
                double v = s * scale[a * C + c] + (smooth_top_ || scattered_only ? 0.0 : direct[c]);
                out[p * C + c] = std::isfinite(v) ? v : 0.0;
            }
        }
    });
}

} // namespace bsdflab
