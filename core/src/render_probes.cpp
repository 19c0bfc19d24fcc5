// Embree-only probes, outside the renderer's hot path: tracing recorded rays (the
// benchmark of bench/bench_render.py) and first hits of given rays (tests).
#include <embree3/rtcore.h>
#include <atomic>
#include <chrono>
#include <limits>
#include <stdexcept>
#include "bsdflab/parallel.h"
#include "bsdflab/render/scene.h"
#include "render_scene_impl.h"

namespace bsdflab {

namespace {
// Packs up to 16 recorded rays of one kind into Embree's SoA packet; returns the count.
template <typename Ray16>
int pack16(const float *rays, std::size_t begin, std::size_t end, bool shadow, Ray16 &p, int valid[16]) {
    int k = 0;
    for (std::size_t i = begin; i < end && k < 16; ++i) {
        const float *r = &rays[8 * i];
        if ((r[7] != 0) != shadow) continue;
        p.org_x[k] = r[0], p.org_y[k] = r[1], p.org_z[k] = r[2];
        p.dir_x[k] = r[3], p.dir_y[k] = r[4], p.dir_z[k] = r[5];
        p.tnear[k] = 0.0f, p.tfar[k] = r[6], p.time[k] = 0.0f;
        p.mask[k] = 0xffffffffu, p.id[k] = 0, p.flags[k] = 0;
        valid[k++] = -1;
    }
    for (int j = k; j < 16; ++j) valid[j] = 0;
    return k;
}
} // namespace

double RenderScene::trace_recorded(const float *rays, std::size_t n, int packet) const {
    if (packet != 1 && packet != 16) throw std::invalid_argument("packet width must be 1 or 16");
    std::atomic<std::size_t> hits{0}; // consumed, so the work cannot be optimised away
    const auto start = std::chrono::steady_clock::now();
    if (packet == 16) {
        // Each block is scanned twice, once per kind, so packets hold rays of one kind.
        parallel_for(n, 4096, [&](std::size_t begin, std::size_t end) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            std::size_t local = 0;
            alignas(64) int valid[16];
            for (bool shadow : {false, true}) {
                std::size_t i = begin;
                while (i < end) {
                    // Find the window of `end` that holds the next 16 rays of this kind.
                    std::size_t j = i, taken = 0;
                    while (j < end && taken < 16) taken += ((rays[8 * j++ + 7] != 0) == shadow);
                    if (shadow) {
                        alignas(64) RTCRay16 r;
                        if (pack16(rays, i, j, true, r, valid)) {
                            rtcOccluded16(valid, embree_->scene, &ctx, &r);
                            for (int k = 0; k < 16; ++k) local += valid[k] && r.tfar[k] < 0.0f;
                        }
                    } else {
                        alignas(64) RTCRayHit16 rh;
                        if (pack16(rays, i, j, false, rh.ray, valid)) {
                            for (int k = 0; k < 16; ++k)
                                rh.hit.geomID[k] = rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
                            rtcIntersect16(valid, embree_->scene, &ctx, &rh);
                            for (int k = 0; k < 16; ++k)
                                local += valid[k] && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
                        }
                    }
                    i = j;
                }
            }
            hits += local;
        });
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return hits.load() > n ? -1.0 : seconds;
    }
    parallel_for(n, 4096, [&](std::size_t begin, std::size_t end) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        std::size_t local = 0;
        for (std::size_t i = begin; i < end; ++i) {
            const float *r = &rays[8 * i];
            RTCRayHit rh;
            rh.ray.org_x = r[0];
            rh.ray.org_y = r[1];
            rh.ray.org_z = r[2];
            rh.ray.dir_x = r[3];
            rh.ray.dir_y = r[4];
            rh.ray.dir_z = r[5];
            rh.ray.tnear = 0.0f;
            rh.ray.tfar = r[6];
            rh.ray.time = 0.0f;
            rh.ray.mask = 0xffffffffu;
            rh.ray.id = 0;
            rh.ray.flags = 0;
            if (r[7] != 0) {
                rtcOccluded1(embree_->scene, &ctx, &rh.ray);
                local += rh.ray.tfar < 0.0f;
            } else {
                rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(embree_->scene, &ctx, &rh);
                local += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            }
        }
        hits += local;
    });
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return hits.load() > n ? -1.0 : seconds; // never true; keeps the hit count live
}

void RenderScene::first_hits(const float *rays, std::size_t n, int *mesh) const {
    parallel_for(n, 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const float *r = &rays[6 * i];
            SurfaceHit hit;
            mesh[i] = intersect({r[0], r[1], r[2]}, {r[3], r[4], r[5]},
                                std::numeric_limits<double>::infinity(), hit)
                          ? hit.mesh
                          : -1;
        }
    });
}

} // namespace bsdflab
