// First-hit auxiliary images for a denoiser (albedo, shading normal, mesh id): separate
// rays after the render, never part of the image.
#include "bsdflab/render/path_tracer.h"
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include "bsdflab/frame.h"
#include "bsdflab/parallel.h"
#include "bsdflab/rng.h"
#include "bsdflab/sampling.h"

namespace bsdflab {

void RenderJob::aovs(int samples, double *albedo, double *normal, int *mesh_id) const {
    const int W = width(), H = height();
    const RenderScene &scene = *scene_;
    parallel_for(std::size_t(W) * H, 256, [&](std::size_t begin, std::size_t end) {
        std::vector<double> buf(std::max(max_channels_, 3));
        for (std::size_t pixel = begin; pixel < end; ++pixel) {
            double *a = &albedo[3 * pixel], *n = &normal[3 * pixel];
            a[0] = a[1] = a[2] = n[0] = n[1] = n[2] = 0;
            mesh_id[pixel] = -1;
            const int x = int(pixel % W), y = int(pixel / W);
            SurfaceHit hit;
            const Vec3 d = scene.camera().direction(x + 0.5, y + 0.5);
            if (!scene.intersect(scene.camera().origin(), d, kInf, hit)) continue;
            mesh_id[pixel] = hit.mesh;
            const Material *mat = scene.material_of(hit.mesh);
            if (!mat) {
                a[0] = a[1] = a[2] = 1;
                continue;
            } // emitters: white albedo
            const ShadingPoint sp = mat->shade(hit);
            n[0] = sp.frame.n.x;
            n[1] = sp.frame.n.y;
            n[2] = sp.frame.n.z;
            const Vec3 wi = sp.frame.to_local(-d);
            PCG32 rng(mix64(pixel) ^ 0xa0a5ULL);
            for (int k = 0; k < samples; ++k) {
                const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                BSDFSample bs = sp.bsdf->bsdf->sample(wi, u0, u1, u2, kAll, sp.query, buf.data());
                if (!bs.lobe) continue;
                double rgb[3];
                sp.bsdf->to_rgb(buf.data(), rgb);
                for (int c = 0; c < 3; ++c) a[c] += std::clamp(rgb[c], 0.0, 1.0) / samples;
            }
        }
    });
}

} // namespace bsdflab
