// The two sides of a stack, and the boundary / slab arithmetic that depends on one.
// Boundaries are numbered 0 (top) .. K (base), slabs 0 .. K-1; slab j lies between
// boundaries j and j + 1. A walk measures its depth from a reference side (the exit side
// for eval's walk, the top for sample()'s), so these helpers take that side.
#pragma once
#include "bsdflab/vector.h"

namespace bsdflab::layered {

enum class Side { Top, Bottom };

// The side a direction of travel heads to (z > 0: up, toward the top).
inline Side side_of(const Vec3 &w) { return w.z > 0 ? Side::Top : Side::Bottom; }
// Whether w travels toward side s.
inline bool heads_to(Side s, const Vec3 &w) { return s == Side::Top ? w.z > 0 : w.z < 0; }
// The outer boundary on side s of a stack of K slabs.
inline int outer_boundary(Side s, int K) { return s == Side::Top ? 0 : K; }
// The slab just inside side s.
inline int outer_slab(Side s, int K) { return s == Side::Top ? 0 : K - 1; }
// Slab j's boundary on side s, and on the other side.
inline int near_boundary(Side s, int j) { return s == Side::Top ? j : j + 1; }
inline int far_boundary(Side s, int j) { return s == Side::Top ? j + 1 : j; }
// The step in slab index that moves toward side s.
inline int step_toward(Side s) { return s == Side::Top ? -1 : 1; }
// Slab j of K, counted `step` slabs in from side s.
inline int slab_from(Side s, int step, int K) { return s == Side::Top ? step : K - 1 - step; }

} // namespace bsdflab::layered
