#include "bsdflab/film_lookup.h"
#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include "bsdflab/parallel.h"

namespace bsdflab {

namespace {

// The critical cosine of light arriving from `side` (0: above), 0 when there is none.
double critical_cosine(const FresnelTerm &t, int side) {
    if (!t.transmissive()) return 0.0;
    const double eta = t.eta(); // n_int / n_ext
    const double ratio = side == 0 ? eta : 1.0 / eta; // n of the far side / n of the near side
    return ratio < 1 ? std::sqrt(1.0 - ratio * ratio) : 0.0;
}

// Lagrange weights of the cubic through nodes 0, 1, 2, 3 at s in [0, 3].
void cubic_weights(double s, double w[4]) {
    const double a = s, b = s - 1, c = s - 2, d = s - 3;
    w[0] = -b * c * d / 6.0;
    w[1] = a * c * d / 2.0;
    w[2] = -a * b * d / 2.0;
    w[3] = a * b * c / 6.0;
}

// The exact term clamps R to [0, 1] and T to [0, 1 - R]; so does the lookup.
void clamp_power(double &r, double &t) {
    r = std::min(std::max(r, 0.0), 1.0);
    t = std::min(std::max(t, 0.0), 1.0 - r);
}

} // namespace

FilmLookupTerm::FilmLookupTerm(std::shared_ptr<const FresnelTerm> exact, double thickness_nm, int intervals)
    : FresnelTerm(exact ? exact->channels() : 0, exact ? exact->eta() : 0.0), exact_(std::move(exact)),
      thickness_(thickness_nm < 0 ? -1.0 : thickness_nm), intervals_(intervals) {
    if (!exact_) throw std::invalid_argument("film lookup: no exact term");
    if (intervals_ < 6) throw std::invalid_argument("film lookup: need >= 6 intervals");
    sides_[1] = exact_->transmissive();
    for (int side = 0; side < 2; ++side) {
        if (!sides_[side]) continue;
        const double k = critical_cosine(*exact_, side);
        segments_[side][0].kink = k;
        segments_[side][0].end = 1.0;
        segments_[side][1].kink = k;
        segments_[side][1].end = 0.0;
        for (int part = 0; part < 2; ++part) {
            Segment &s = segments_[side][part];
            if (part == 1 && !(k > 0)) continue; // no total internal reflection on this side
            fill(s, side);
            measured_error_ = std::max(measured_error_, check(s, side));
        }
    }
}

std::shared_ptr<const FilmLookupTerm> FilmLookupTerm::build(std::shared_ptr<const FresnelTerm> exact,
                                                            double thickness_nm, double max_error) {
    if (!exact || !(max_error > 0)) return nullptr;
    for (int n = kStartIntervals; n <= kMaxIntervals; n *= 2) {
        auto lookup = std::make_shared<const FilmLookupTerm>(exact, thickness_nm, n);
        // Half the bound at the check points: margin for the error between them.
        if (lookup->measured_error() <= 0.5 * max_error) return lookup;
    }
    return nullptr;
}

std::size_t FilmLookupTerm::bytes() const {
    std::size_t n = 0;
    for (const auto &side : segments_)
        for (const Segment &s : side) n += s.nodes.size() * sizeof(double);
    return n;
}

void FilmLookupTerm::exact_at(int side, double cos, double *R, double *T) const {
    Query q;
    q.film_thickness_nm = thickness_;
    // From below, the grazing node is taken just inside (-0.0 would count as from above).
    exact_->eval(side == 0 ? cos : -std::max(cos, 1e-300), q, R, T);
}

void FilmLookupTerm::fill(Segment &s, int side) const {
    const int C = channels_, N = intervals_;
    s.nodes.assign(std::size_t(N + 1) * 2 * C, 0.0);
    // Nodes are independent and the exact term is thread-safe: all cores, same bits.
    parallel_for(std::size_t(N + 1), 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const double v = double(i) / N;
            double *row = &s.nodes[i * 2 * C];
            exact_at(side, s.kink + (s.end - s.kink) * v * v, row, row + C);
        }
    });
    // At the kink itself the exact term is ill-conditioned: ~sqrt(cos - k) with cos - k at
    // rounding level is off by up to ~1e-7 (measured: T = 8.7e-8 at cos = k where the limit
    // is 0). The node takes the limit instead, extrapolated from its smooth neighbours by
    // the quintic through v = 1..6: extrapolation error h^6 f^(6), measured ~1e-11 for the
    // snake's film (the cubic through 1..4 left 4e-8: R and T vary fast near the kink).
    if (s.kink > 0) {
        static constexpr double kTo0[6] = {6, -15, 20, -15, 6, -1}; // Lagrange weights at v = 0
        double *row = s.nodes.data();
        const std::size_t n = 2 * C;
        for (std::size_t k = 0; k < n; ++k) {
            double v = 0;
            for (int j = 0; j < 6; ++j) v += kTo0[j] * row[(j + 1) * n + k];
            row[k] = v;
        }
        for (int c = 0; c < C; ++c) clamp_power(row[c], row[C + c]);
    }
}

double FilmLookupTerm::check(const Segment &s, int side) const {
    const int C = channels_, N = intervals_;
    // Midpoints of every interval, and the quarter points of the two end intervals, where
    // the one-sided stencils are used.
    std::vector<double> points;
    for (int i = 0; i < N; ++i) points.push_back((i + 0.5) / N);
    for (double f : {0.25, 0.75, N - 0.75, N - 0.25}) points.push_back(f / N);
    std::vector<double> worst(points.size(), 0.0);
    parallel_for(points.size(), 16, [&](std::size_t begin, std::size_t end) {
        std::vector<double> r(C), t(C), re(C), te(C);
        for (std::size_t p = begin; p < end; ++p) {
            const double v = points[p];
            interpolate(s, v, r.data(), t.data());
            exact_at(side, s.kink + (s.end - s.kink) * v * v, re.data(), te.data());
            double e = 0;
            for (int c = 0; c < C; ++c) e = std::max({e, std::abs(r[c] - re[c]), std::abs(t[c] - te[c])});
            worst[p] = std::isfinite(e) ? e : HUGE_VAL;
        }
    });
    return *std::max_element(worst.begin(), worst.end());
}

void FilmLookupTerm::interpolate(const Segment &s, double v, double *R, double *T) const {
    const int C = channels_, N = intervals_;
    const double x = std::min(std::max(v, 0.0), 1.0) * N;
    const int i = std::min(int(x), N - 1);
    const int base = std::min(std::max(i - 1, 0), N - 3); // nodes base .. base + 3
    double w[4];
    cubic_weights(x - base, w);
    const double *a = &s.nodes[std::size_t(base) * 2 * C];
    const double *b = a + 2 * C, *c = b + 2 * C, *d = c + 2 * C;
    for (int k = 0; k < 2 * C; ++k) {
        const double value = w[0] * a[k] + w[1] * b[k] + w[2] * c[k] + w[3] * d[k];
        if (k < C) R[k] = value;
        else T[k - C] = value;
    }
    for (int k = 0; k < C; ++k) clamp_power(R[k], T[k]);
}

void FilmLookupTerm::eval(double cos_i, const Query &q, double *R, double *T) const {
    const double qt = q.film_thickness_nm < 0 ? -1.0 : q.film_thickness_nm;
    const int side = cos_i >= 0 ? 0 : 1; // as the exact term: -0.0 counts as from above
    const double c = std::abs(cos_i);
    if (qt != thickness_ || !(c <= 1.0) || !sides_[side]) { // another film, NaN, or opaque from below
        exact_->eval(cos_i, q, R, T);
        return;
    }
    const Segment &tir = segments_[side][1];
    const double k = segments_[side][0].kink;
    if (c >= k || tir.nodes.empty()) {
        const Segment &s = segments_[side][0];
        interpolate(s, k < 1 ? std::sqrt(std::max(c - k, 0.0) / (1.0 - k)) : 0.0, R, T);
    } else {
        interpolate(tir, std::sqrt((k - c) / k), R, T);
    }
}

std::shared_ptr<const FresnelTerm> film_lookup_for(const std::shared_ptr<const FresnelTerm> &term,
                                                   double thickness_nm, FilmLookupStats &stats) {
    if (!std::dynamic_pointer_cast<const FilmTerm>(term)) return nullptr;
    auto lookup = FilmLookupTerm::build(term, thickness_nm);
    if (lookup) {
        stats.max_error = std::max(stats.max_error, lookup->measured_error());
        stats.bytes += lookup->bytes();
    }
    return lookup;
}

} // namespace bsdflab
