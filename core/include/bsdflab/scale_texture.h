// Procedural hexagonal snake scales driven by a surface's (u, v).
//
// Geometry. Scales sit on a hexagonal lattice of rows: row i is a ring around the body at
// u = i / scales_per_unit_u, holding `scales_around` scales evenly spaced in v; odd rows are
// shifted by half a spacing in v, so neighbouring rows fit into each other. All distances
// are measured in the texture metric
//     x = u * scales_per_unit_u * sqrt(3)/2,   y = v * scales_around,
// where the spacing between neighbouring centres is 1 and the rows are sqrt(3)/2 apart, so
// an unjittered scale is a regular hexagon (unit area; exactly scales_per_unit_u *
// scales_around scales per unit of u). Scales look regular on the surface when the surface
// maps this metric isotropically (rows sqrt(3)/2 times the spacing around apart).
//
// Centre of scale (i, j):  (i * sqrt(3)/2 + jitter * a,  j + (i odd ? 1/2 : 0) + jitter * b),
// a, b uniform in [-1, 1) from the scale's hash. A point belongs to the nearest centre (a
// Voronoi cell of the jittered lattice: a slightly irregular hexagon). edge_distance is the
// exact distance to that cell's boundary, min_k (d_k^2 - d_1^2) / (2 |c_k - c_1|) over the
// other centres k; the point is in a gap iff edge_distance < gap / 2.
//
// Periodic v: v is wrapped into [0, 1) and the column index j is taken modulo scales_around
// for the hash (positions stay unwrapped), so the texture is seamless for any count, odd
// or even (the half-spacing row shift is along v). Ids at v and v + 1 agree except where
// rounding of the wrapped v moves a point across a boundary.
//
// Hashes (mix64 = splitmix64 finaliser from rng.h, all arithmetic mod 2^64; j is the
// wrapped column when periodic_v):
//     seed_key = mix64(seed ^ kSeedSalt)
//     id       = mix64(mix64(seed_key ^ uint64(i)) ^ uint64(j))
//     jitter   : h = mix64(id ^ kJitterSalt); a = 2 (h >> 32) / 2^32 - 1, b = 2 (h & 0xffffffff) / 2^32 - 1
//     tilt     : h = mix64(id ^ kTiltSalt);   magnitude tan(tilt) * sqrt(hi32 / 2^32),
//                                             direction 2 pi lo32 / 2^32
//     thickness: h = mix64(id ^ kThicknessSalt); factor 1 + thickness_jitter * (2 hi32 / 2^32 - 1)
// with kSeedSalt = 0x5ca1e5eed0000001, kJitterSalt = 0x5ca1e0000000a001, kTiltSalt =
// 0x5ca1e0000000a002, kThicknessSalt = 0x5ca1e0000000a003 (hi32 / lo32: the high / low
// 32 bits of h). tests/test_scales.py rebuilds the lattice from these lines alone.
//
// Shading. Slopes are gradients of the scale's height field in the texture metric (the
// normal is normalize(-slope_u, -slope_v, 1)). A scale is a dome: along the ray from its
// centre through the point, the slope grows linearly from 0 at the centre to `dome` where
// the ray meets the gap (the rim), and the gradient points to the centre, so the normal
// leans outward as on a convex scale. On top comes a per-scale constant tilt. So
// |slope| <= dome + tan(tilt_deg). No roof-tile skew: the contract does not say which way
// along u the tail lies, and the random tilts already make neighbours flash differently.
//
// Cost: one pass over the lattice points whose unjittered position is within
// 2/sqrt(3) + 3 * jitter * sqrt(2) + gap of the point (about 12 with the defaults, at most
// about 31), which provably contains the nearest centre, every centre whose bisector bounds
// the cell near the point and the one that ends the ray from the centre at the rim.
#pragma once
#include <cstdint>

namespace bsdflab {

struct ScaleParams {
    double scales_per_unit_u = 8;   // scale rows per unit of u (along the body), (0, 1e6]
    int scales_around = 16;         // scales per unit of v (v in [0,1) around the body), [3, 2^20]
    double gap = 0.06;              // gap width as a fraction of the spacing, [0, 0.5]
    double jitter = 0.15;           // centre jitter per axis as a fraction of the spacing, [0, 0.3]
    double dome = 0.25;             // slope of the scale's surface at its rim, [0, 2]
    double tilt_deg = 6;            // max per-scale tilt of the normal, degrees, [0, 45]
    double thickness_jitter = 0.15; // film thickness factor = 1 + thickness_jitter * U[-1, 1], [0, 0.9]
    uint64_t seed = 0;
    bool periodic_v = true;         // v wraps with period 1 (a body of revolution): seamless
};

struct ScaleSample {
    bool gap = false;                // the point lies in a gap between scales
    uint64_t id = 0;                 // stable id of the nearest scale (also given for gap points)
    double slope_u = 0, slope_v = 0; // tangent-space slopes: normal = normalize(-slope_u, -slope_v, 1)
                                     // in the frame (T_u, T_v, n); 0 in gaps
    double thickness_factor = 1;     // multiplies the film thickness (1 in gaps)
    double edge_distance = 0;        // distance to the nearest scale boundary, in spacings
};

// Beyond this |u * scales_per_unit_u| (or |v * scales_around| when v does not wrap) the
// lattice index no longer fits comfortably in double precision: such points are gaps.
constexpr double kScaleCoordinateLimit = 1099511627776.0; // 2^40

class ScaleTexture {
  public:
    explicit ScaleTexture(const ScaleParams &p); // throws std::invalid_argument on bad params
    // Thread-safe, no allocation. NaN / infinite / out-of-range (u, v) give a gap sample
    // with id 0.
    ScaleSample lookup(double u, double v) const;
    // Jittered centre of scale (row i, column j) in (u, v); j is wrapped for the hash only.
    void centre(int64_t i, int64_t j, double &u, double &v) const;
    // Id of scale (row i, column j) (j wrapped modulo scales_around when periodic_v).
    uint64_t scale_id(int64_t i, int64_t j) const;
    const ScaleParams &params() const { return p_; }

  private:
    uint64_t wrapped_id(int64_t i, int64_t j) const;
    ScaleParams p_;
    uint64_t seed_key_;
    double x_per_u_;        // texture metric x per unit u
    double tan_tilt_;
    double search_radius_;  // lattice points within this (unjittered) distance are visited
};

} // namespace bsdflab
