// What a material makes of a surface hit: the BSDF to use there, the shading frame it is
// evaluated in and the per-query parameters (pbrt-v4's MaterialEvalContext, Mitsuba's
// bump/normal adapters). Textures (the scale texture: gap BSDF, bump frame, per-scale film
// thickness) live here, so the integrator only transports light and a new texture needs
// no integrator change.
#pragma once
#include "bsdflab/bsdf.h"
#include "bsdflab/vector.h"

namespace bsdflab {

struct RenderBSDF;
struct SurfaceHit;

struct ShadingFrame {
    Vec3 s, t, n;
    Vec3 to_local(const Vec3 &v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3 to_world(const Vec3 &v) const { return s * v.x + t * v.y + n * v.z; }
};

// Orthonormal frame around the unit normal n with s as close to `tangent` as possible
// (any perpendicular when the tangent is unusable).
ShadingFrame frame_around(const Vec3 &n, const Vec3 &tangent);

struct ShadingPoint {
    const RenderBSDF *bsdf = nullptr;
    ShadingFrame frame;
    Query query;
};

} // namespace bsdflab
