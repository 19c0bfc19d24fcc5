#include "bsdflab/scale_texture.h"
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include "bsdflab/rng.h"
#include "bsdflab/sampling.h"

namespace bsdflab {

namespace {

constexpr double kRowHeight = 0.86602540378443864676; // sqrt(3)/2: rows of unit-spaced hexagons
constexpr uint64_t kSeedSalt = 0x5ca1e5eed0000001ULL;
constexpr uint64_t kJitterSalt = 0x5ca1e0000000a001ULL;
constexpr uint64_t kTiltSalt = 0x5ca1e0000000a002ULL;
constexpr uint64_t kThicknessSalt = 0x5ca1e0000000a003ULL;
constexpr std::size_t kMaxCandidates = 64;

// floor / ceil to an integer for |x| < 2^52, inline (std::floor is a libm call without SSE4.1).
int64_t floor_int(double x) {
    int64_t t = int64_t(x);
    return t - int64_t(x < double(t));
}
int64_t ceil_int(double x) {
    int64_t t = int64_t(x);
    return t + int64_t(x > double(t));
}

double hi_unit(uint64_t h) { return double(h >> 32) * 0x1p-32; }
double lo_unit(uint64_t h) { return double(h & 0xffffffffULL) * 0x1p-32; }

void require(bool ok, const std::string &message) {
    if (!ok) throw std::invalid_argument("ScaleParams: " + message);
}

// An upper bound on the lattice points within `radius` of any point: rows x columns.
std::size_t candidate_bound(double radius) {
    return std::size_t((std::floor(2 * radius / kRowHeight) + 1) * (std::floor(2 * radius) + 1));
}

struct Candidate {
    double x, y;
    uint64_t id;
};

} // namespace

ScaleTexture::ScaleTexture(const ScaleParams &p) : p_(p) {
    require(std::isfinite(p.scales_per_unit_u) && p.scales_per_unit_u > 0 && p.scales_per_unit_u <= 1e6,
            "scales_per_unit_u must be in (0, 1e6]");
    require(p.scales_around >= 3 && p.scales_around <= (1 << 20), "scales_around must be in [3, 2^20]");
    require(p.gap >= 0 && p.gap <= 0.5, "gap must be in [0, 0.5]");
    require(p.jitter >= 0 && p.jitter <= 0.3, "jitter must be in [0, 0.3]");
    require(p.dome >= 0 && p.dome <= 2, "dome must be in [0, 2]");
    require(p.tilt_deg >= 0 && p.tilt_deg <= 45, "tilt_deg must be in [0, 45]");
    require(p.thickness_jitter >= 0 && p.thickness_jitter <= 0.9, "thickness_jitter must be in [0, 0.9]");
    seed_key_ = mix64(p.seed ^ kSeedSalt);
    x_per_u_ = p.scales_per_unit_u * kRowHeight;
    tan_tilt_ = std::tan(p.tilt_deg * kPi / 180);
    // Nearest jittered centre of any point: within rho = 1/sqrt(3) + |offset|max. The
    // bisectors that matter (closest boundary, end of the rim ray) belong to centres within
    // 2 rho + gap of the point, i.e. lattice points within that + |offset|max. 1e-9: rounding.
    double max_offset = p.jitter * std::sqrt(2.0);
    search_radius_ = 2 / std::sqrt(3.0) + 3 * max_offset + p.gap + 1e-9;
    if (candidate_bound(search_radius_) > kMaxCandidates)
        throw std::logic_error("ScaleTexture: search neighbourhood exceeds its fixed capacity");
}

uint64_t ScaleTexture::wrapped_id(int64_t i, int64_t j) const {
    return mix64(mix64(seed_key_ ^ uint64_t(i)) ^ uint64_t(j));
}

uint64_t ScaleTexture::scale_id(int64_t i, int64_t j) const {
    if (p_.periodic_v) {
        j %= p_.scales_around;
        if (j < 0) j += p_.scales_around;
    }
    return wrapped_id(i, j);
}

void ScaleTexture::centre(int64_t i, int64_t j, double &u, double &v) const {
    uint64_t h = mix64(scale_id(i, j) ^ kJitterSalt);
    double x = double(i) * kRowHeight + p_.jitter * (2 * hi_unit(h) - 1);
    double y = double(j) + 0.5 * double(i & 1) + p_.jitter * (2 * lo_unit(h) - 1);
    u = x / x_per_u_;
    v = y / p_.scales_around;
}

ScaleSample ScaleTexture::lookup(double u, double v) const {
    ScaleSample s;
    s.gap = true;
    if (!std::isfinite(u) || !std::isfinite(v)) return s;
    double rows = u * p_.scales_per_unit_u;
    if (p_.periodic_v) {
        v -= std::floor(v);
        if (v >= 1) v = 0; // -tiny - floor(-tiny) rounds to 1
    }
    double x = u * x_per_u_, y = v * p_.scales_around;
    if (!(std::abs(rows) <= kScaleCoordinateLimit && std::abs(y) <= kScaleCoordinateLimit)) return s;

    // Visit every lattice point within search_radius_ of (x, y); keep them for the bisectors.
    const double r = search_radius_;
    const int64_t n_around = p_.scales_around;
    std::array<Candidate, kMaxCandidates> cand;
    std::size_t count = 0, nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    const int64_t row_lo = ceil_int((x - r) / kRowHeight), row_hi = floor_int((x + r) / kRowHeight);
    for (int64_t i = row_lo; i <= row_hi; ++i) {
        double dx_nominal = x - double(i) * kRowHeight;
        double half_width = std::sqrt(std::max(0.0, r * r - dx_nominal * dx_nominal));
        double shift = 0.5 * double(i & 1);
        int64_t j_lo = ceil_int(y - shift - half_width), j_hi = floor_int(y - shift + half_width);
        uint64_t row_key = mix64(seed_key_ ^ uint64_t(i));
        int64_t j_hash = j_lo;
        if (p_.periodic_v) { // y in [0, n_around), so j_lo in [-3, n_around): no division
            if (j_hash < 0) j_hash += n_around;
            else if (j_hash >= n_around) j_hash -= n_around;
        }
        for (int64_t j = j_lo; j <= j_hi && count < kMaxCandidates; ++j) {
            uint64_t id = mix64(row_key ^ uint64_t(j_hash));
            uint64_t h = mix64(id ^ kJitterSalt);
            double cx = double(i) * kRowHeight + p_.jitter * (2 * hi_unit(h) - 1);
            double cy = double(j) + shift + p_.jitter * (2 * lo_unit(h) - 1);
            double d2 = (cx - x) * (cx - x) + (cy - y) * (cy - y);
            if (d2 < best) {
                best = d2;
                nearest = count;
            }
            cand[count++] = {cx, cy, id};
            if (++j_hash == n_around && p_.periodic_v) j_hash = 0;
        }
    }
    if (count == 0) return s; // the radius always holds several points; keeps the compiler sure
    const Candidate &c1 = cand[nearest];
    s.id = c1.id;

    // Distance to the cell boundary, and how far along the ray centre -> point the rim is.
    const double px = x - c1.x, py = y - c1.y;
    double edge = std::numeric_limits<double>::infinity(), rim_fraction = 0;
    for (std::size_t k = 0; k < count; ++k) {
        if (k == nearest) continue;
        double dx = cand[k].x - c1.x, dy = cand[k].y - c1.y;
        double length = std::sqrt(dx * dx + dy * dy);
        if (length == 0) continue; // coincident centres (jitter 0.3 cannot reach; guard anyway)
        double toward = dx * px + dy * py; // (c_k - c_1) . (p - c_1)
        // (d_k^2 - d_1^2) / (2 L) = L/2 - (c_k - c_1).(p - c_1) / L
        edge = std::min(edge, 0.5 * length - toward / length);
        double inner = length * (length - p_.gap); // 2 x distance to the rim's line x L
        if (toward > 0 && inner > 0) rim_fraction = std::max(rim_fraction, 2 * toward / inner);
    }
    s.edge_distance = std::max(0.0, edge);
    if (s.edge_distance < 0.5 * p_.gap) return s;

    s.gap = false;
    double d1 = std::sqrt(best);
    if (d1 > 0) {
        double k = -p_.dome * std::min(rim_fraction, 1.0) / d1; // gradient points to the centre
        s.slope_u = k * px;
        s.slope_v = k * py;
    }
    uint64_t ht = mix64(c1.id ^ kTiltSalt);
    double tilt = tan_tilt_ * std::sqrt(hi_unit(ht)), azimuth = 2 * kPi * lo_unit(ht);
    s.slope_u += tilt * std::cos(azimuth);
    s.slope_v += tilt * std::sin(azimuth);
    s.thickness_factor = 1 + p_.thickness_jitter * (2 * hi_unit(mix64(c1.id ^ kThicknessSalt)) - 1);
    return s;
}

} // namespace bsdflab
