// Material::shade: the scale texture's gap BSDF, bump frame and film thickness.
#include "bsdflab/render/shading.h"
#include <cmath>
#include "bsdflab/frame.h"
#include "bsdflab/render/scene.h"

namespace bsdflab {

ShadingFrame frame_around(const Vec3 &n, const Vec3 &tangent) {
    Vec3 s = tangent - n * dot(n, tangent);
    double l = length(s);
    if (!(l > 1e-9 * (length(tangent) + 1e-300))) {
        Vec3 t; // no usable tangent: any perpendicular (frame.h's basis)
        orthonormal_basis(n, s, t);
    } else {
        s = s * (1 / l);
    }
    return {s, cross(n, s), n};
}

ShadingPoint Material::shade(const SurfaceHit &hit) const {
    ShadingPoint sp;
    sp.bsdf = &surface;
    sp.frame = frame_around(hit.ns, hit.dpdu);
    if (!scales) return sp;
    ScaleSample ss = scales->lookup(hit.u, hit.v);
    if (ss.gap) {
        if (has_gap) sp.bsdf = &gap;
        return sp;
    }
    // Slopes are along (T_u, T_v); t = n x s is T_v only for right-handed (u, v)
    // parameterisations (the snake's and the sphere's are left-handed).
    const ShadingFrame &f = sp.frame;
    const double handed = dot(cross(hit.dpdu, hit.dpdv), f.n) < 0 ? -1.0 : 1.0;
    Vec3 nb = normalized(f.n - f.s * ss.slope_u - f.t * (handed * ss.slope_v));
    if (length(nb) > 0) sp.frame = frame_around(nb, f.s);
    if (film_thickness_nm > 0) sp.query.film_thickness_nm = film_thickness_nm * ss.thickness_factor;
    return sp;
}

} // namespace bsdflab
