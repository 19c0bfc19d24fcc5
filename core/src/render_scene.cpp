#include "bsdflab/render/scene.h"
#include <embree3/rtcore.h>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include "bsdflab/frame.h"
#include "bsdflab/parallel.h"
#include "bsdflab/sampling.h"
#include "bsdflab/scratch.h"

namespace bsdflab {

namespace {
// Embree reports errors through a callback; keep the last one for the exception text.
void on_embree_error(void *user, RTCError code, const char *message) {
    auto *last = static_cast<std::string *>(user);
    *last = "Embree error " + std::to_string(int(code)) + ": " + (message ? message : "");
}
} // namespace

void RenderBSDF::to_rgb(const double *channels, double rgb[3]) const {
    if (P.empty()) {
        for (int c = 0; c < 3; ++c) rgb[c] = channels[c];
        return;
    }
    const int C = bsdf->channels();
    for (int r = 0; r < 3; ++r) {
        double s = 0;
        const double *row = &P[std::size_t(r) * C];
        for (int c = 0; c < C; ++c) s += row[c] * channels[c];
        rgb[r] = s;
    }
}

void RenderBSDF::to_spectrum(const double *channels, double out[kSpectralBins]) const {
    if (U.empty()) {
        for (int l = 0; l < kSpectralBins; ++l) out[l] = channels[l];
        return;
    }
    const int C = bsdf->channels();
    for (int l = 0; l < kSpectralBins; ++l) {
        const double *row = &U[std::size_t(l) * C];
        double s = 0;
        for (int c = 0; c < C; ++c) s += row[c] * channels[c];
        out[l] = s;
    }
}

void RenderScene::set_spectral(std::vector<double> U, std::vector<double> W) {
    if (committed_) throw std::logic_error("scene already committed: set the spectral matrices before commit()");
    if (U.size() != 3u * kSpectralBins || W.size() != 3u * kSpectralBins)
        throw std::invalid_argument("spectral matrices must be (81 x 3) and (3 x 81)");
    U_ = std::move(U);
    W_ = std::move(W);
}

void RenderScene::lift(const double rgb[3], double out[kSpectralBins]) const {
    for (int l = 0; l < kSpectralBins; ++l)
        out[l] = U_[3 * l] * rgb[0] + U_[3 * l + 1] * rgb[1] + U_[3 * l + 2] * rgb[2];
}

struct RenderScene::Mesh {
    MeshInput in;
    std::vector<double> area; // per triangle
};

struct RenderScene::Embree {
    std::string last_error;
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    Embree() {
        device = rtcNewDevice(nullptr);
        if (!device) throw std::runtime_error("could not create an Embree device");
        rtcSetDeviceErrorFunction(device, on_embree_error, &last_error);
        scene = rtcNewScene(device);
        rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    }
    ~Embree() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

RenderScene::RenderScene() : embree_(std::make_unique<Embree>()) {}
RenderScene::~RenderScene() = default;

int RenderScene::add_material(Material m) {
    if (committed_) throw std::logic_error("scene already committed");
    for (RenderBSDF *b : {&m.surface, &m.gap}) {
        if (!b->bsdf) continue;
        const std::size_t C = b->bsdf->channels();
        if (b->P.empty() ? C != 3 : b->P.size() != 3 * C)
            throw std::invalid_argument("material: the RGB projection does not match the BSDF's channels");
        if (!b->U.empty() && b->U.size() != std::size_t(kSpectralBins) * C)
            throw std::invalid_argument("material: the spectral lift does not match the BSDF's channels");
        if (b->U.empty() && C != std::size_t(kSpectralBins)) spectral_capable_ = false;
        b->lobes = b->bsdf->lobes();
        max_channels_ = std::max(max_channels_, int(C));
    }
    if (!m.surface.bsdf) throw std::invalid_argument("material: a BSDF is required");
    if (m.has_gap && !m.gap.bsdf) throw std::invalid_argument("material: has_gap without a gap BSDF");
    materials_.push_back(std::move(m));
    return int(materials_.size()) - 1;
}

int RenderScene::add_mesh(MeshInput m) {
    if (committed_) throw std::logic_error("scene already committed");
    const std::size_t V = m.positions.size() / 3, F = m.indices.size() / 3;
    if (m.positions.size() != 3 * V || m.indices.size() != 3 * F || V == 0 || F == 0)
        throw std::invalid_argument("mesh: positions must be (V, 3) and indices (F, 3), both non-empty");
    if (!m.normals.empty() && m.normals.size() != 3 * V) throw std::invalid_argument("mesh: normals must be (V, 3)");
    if (!m.uvs.empty() && m.uvs.size() != 2 * V) throw std::invalid_argument("mesh: uvs must be (V, 2)");
    for (uint32_t i : m.indices)
        if (i >= V) throw std::invalid_argument("mesh: index out of range");
    for (float x : m.positions)
        if (!std::isfinite(x)) throw std::invalid_argument("mesh: non-finite vertex position");
    if (m.material < -1 || m.material >= int(materials_.size())) throw std::invalid_argument("mesh: unknown material");
    for (double e : m.emission)
        if (!(std::isfinite(e) && e >= 0)) throw std::invalid_argument("mesh: emission must be finite and >= 0");

    Mesh mesh;
    mesh.in = std::move(m);
    mesh.area.resize(F);
    const float *P = mesh.in.positions.data();
    for (std::size_t f = 0; f < F; ++f) {
        const uint32_t *t = &mesh.in.indices[3 * f];
        Vec3 a{P[3 * t[0]], P[3 * t[0] + 1], P[3 * t[0] + 2]};
        Vec3 b{P[3 * t[1]], P[3 * t[1] + 1], P[3 * t[1] + 2]};
        Vec3 c{P[3 * t[2]], P[3 * t[2] + 1], P[3 * t[2] + 2]};
        mesh.area[f] = 0.5 * length(cross(b - a, c - a));
    }

    RTCGeometry g = rtcNewGeometry(embree_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto *vb = static_cast<float *>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                            3 * sizeof(float), V));
    auto *ib = static_cast<uint32_t *>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               3 * sizeof(uint32_t), F));
    if (!vb || !ib) {
        rtcReleaseGeometry(g);
        throw std::runtime_error("Embree could not allocate a mesh: " + embree_->last_error);
    }
    std::copy(mesh.in.positions.begin(), mesh.in.positions.end(), vb);
    std::copy(mesh.in.indices.begin(), mesh.in.indices.end(), ib);
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(embree_->scene, g);
    rtcReleaseGeometry(g);
    if (id != meshes_.size()) throw std::logic_error("Embree geometry ids out of step");
    meshes_.push_back(std::move(mesh));
    return int(id);
}

// A committed scene may be in use by a running RenderJob: it is read-only from then on.
void RenderScene::set_camera(const Camera &c) {
    if (committed_) throw std::logic_error("scene already committed: set the camera before commit()");
    camera_ = c;
}

void RenderScene::set_environment(Environment e) {
    if (committed_) throw std::logic_error("scene already committed: set the environment before commit()");
    environment_ = std::move(e);
}

void RenderScene::set_robust(bool robust) {
    if (committed_) throw std::logic_error("scene already committed: choose robust traversal before commit()");
    robust_ = robust;
}

void RenderScene::commit() {
    if (committed_) return;
    // Default traversal as Mitsuba 3 uses it; robust mode only on request (its cost and the
    // default's measured leak rate: docs/rendering.md).
    rtcSetSceneFlags(embree_->scene, robust_ ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcCommitScene(embree_->scene);
    if (!embree_->last_error.empty()) throw std::runtime_error(embree_->last_error);
    std::vector<double> power;
    light_prob_.assign(meshes_.size(), {});
    for (std::size_t m = 0; m < meshes_.size(); ++m) {
        const double *e = meshes_[m].in.emission;
        double lum = kLuminanceRGB[0] * e[0] + kLuminanceRGB[1] * e[1] + kLuminanceRGB[2] * e[2];
        if (!(lum > 0)) continue;
        for (uint32_t f = 0; f < meshes_[m].area.size(); ++f) {
            if (!(meshes_[m].area[f] > 0)) continue;
            lights_.emplace_back(int(m), f);
            power.push_back(meshes_[m].area[f] * lum);
        }
    }
    light_choice_ = Distribution1D(power);
    for (std::size_t k = 0; k < lights_.size(); ++k) {
        auto [m, f] = lights_[k];
        if (light_prob_[m].empty()) light_prob_[m].assign(meshes_[m].area.size(), 0.0);
        light_prob_[m][f] = light_choice_.prob(k);
    }
    committed_ = true;
}

const Material *RenderScene::material_of(int mesh) const {
    int id = meshes_[mesh].in.material;
    return id >= 0 ? &materials_[id] : nullptr;
}

void RenderScene::fill_hit(int mesh, uint32_t prim, double b1, double b2, SurfaceHit &hit) const {
    const MeshInput &m = meshes_[mesh].in;
    const uint32_t *t = &m.indices[3 * prim];
    const double b0 = 1 - b1 - b2;
    auto vertex = [&](const std::vector<float> &a, int k, uint32_t i) {
        return Vec3{a[k * i], a[k * i + 1], k == 3 ? double(a[k * i + 2]) : 0.0};
    };
    Vec3 p0 = vertex(m.positions, 3, t[0]), p1 = vertex(m.positions, 3, t[1]), p2 = vertex(m.positions, 3, t[2]);
    hit.mesh = mesh;
    hit.prim = prim;
    hit.p = p0 * b0 + p1 * b1 + p2 * b2;
    hit.ng = normalized(cross(p1 - p0, p2 - p0));
    hit.ns = hit.ng;
    if (!m.normals.empty()) {
        Vec3 n = normalized(vertex(m.normals, 3, t[0]) * b0 + vertex(m.normals, 3, t[1]) * b1 +
                            vertex(m.normals, 3, t[2]) * b2);
        if (length(n) > 0) hit.ns = n;
    }
    // dp/du from the triangle's uv parameterisation (a fallback tangent when degenerate).
    hit.dpdu = p1 - p0;
    hit.dpdv = p2 - p0;
    if (!m.uvs.empty()) {
        Vec3 t0 = vertex(m.uvs, 2, t[0]), t1 = vertex(m.uvs, 2, t[1]), t2 = vertex(m.uvs, 2, t[2]);
        hit.u = t0.x * b0 + t1.x * b1 + t2.x * b2;
        hit.v = t0.y * b0 + t1.y * b1 + t2.y * b2;
        double du1 = t1.x - t0.x, dv1 = t1.y - t0.y, du2 = t2.x - t0.x, dv2 = t2.y - t0.y;
        double det = du1 * dv2 - dv1 * du2;
        if (std::abs(det) > 1e-20) {
            hit.dpdu = ((p1 - p0) * dv2 - (p2 - p0) * dv1) * (1 / det);
            hit.dpdv = ((p2 - p0) * du1 - (p1 - p0) * du2) * (1 / det);
        }
    } else {
        hit.u = b1;
        hit.v = b2;
    }
}

bool RenderScene::intersect(const Vec3 &o, const Vec3 &d, double tmax, SurfaceHit &hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = float(o.x);
    rh.ray.org_y = float(o.y);
    rh.ray.org_z = float(o.z);
    rh.ray.dir_x = float(d.x);
    rh.ray.dir_y = float(d.y);
    rh.ray.dir_z = float(d.z);
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = tmax < std::numeric_limits<float>::max() ? float(tmax) : std::numeric_limits<float>::infinity();
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xffffffffu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(embree_->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    fill_hit(int(rh.hit.geomID), rh.hit.primID, rh.hit.u, rh.hit.v, hit);
    hit.t = rh.ray.tfar;
    return true;
}

bool RenderScene::occluded(const Vec3 &o, const Vec3 &d, double tmax) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    r.org_x = float(o.x);
    r.org_y = float(o.y);
    r.org_z = float(o.z);
    r.dir_x = float(d.x);
    r.dir_y = float(d.y);
    r.dir_z = float(d.z);
    r.tnear = 0.0f;
    r.tfar = tmax < std::numeric_limits<float>::max() ? float(tmax) : std::numeric_limits<float>::infinity();
    r.time = 0.0f;
    r.mask = 0xffffffffu;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(embree_->scene, &ctx, &r);
    return r.tfar < 0.0f;
}

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
                            for (int k = 0; k < 16; ++k) rh.hit.geomID[k] = rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
                            rtcIntersect16(valid, embree_->scene, &ctx, &rh);
                            for (int k = 0; k < 16; ++k) local += valid[k] && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
                        }
                    }
                    i = j;
                }
            }
            hits += local;
        });
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
            mesh[i] = intersect({r[0], r[1], r[2]}, {r[3], r[4], r[5]}, std::numeric_limits<double>::infinity(), hit)
                          ? hit.mesh
                          : -1;
        }
    });
}

void RenderScene::emitted(const SurfaceHit &hit, const Vec3 &w, double rgb[3]) const {
    const double *e = meshes_[hit.mesh].in.emission;
    bool front = dot(hit.ns, w) > 0;
    for (int c = 0; c < 3; ++c) rgb[c] = front ? e[c] : 0.0;
}

double RenderScene::env_selection() const {
    if (!environment_.active()) return 0.0;
    return lights_.empty() ? 1.0 : 0.5;
}

EmitterSample RenderScene::sample_emitter(const Vec3 &ref, double u0, double u1, double u2) const {
    EmitterSample s;
    const double p_env = env_selection();
    if (p_env == 0 && lights_.empty()) return s;
    if (u0 < p_env) {
        double pdf;
        Vec3 d = environment_.sample(u1, u2, pdf, s.radiance);
        if (!(pdf > 0)) {
            s.radiance[0] = s.radiance[1] = s.radiance[2] = 0.0;
            return s;
        }
        s.wo = d;
        s.dist = std::numeric_limits<double>::infinity();
        s.pdf = pdf * p_env;
        return s;
    }
    double u_rest;
    std::size_t k = light_choice_.sample(p_env > 0 ? (u0 - p_env) / (1 - p_env) : u0, u_rest);
    auto [m, f] = lights_[k];
    // Uniform point on the triangle (square-root parameterisation).
    double su = std::sqrt(u1), b1 = 1 - su, b2 = u2 * su;
    (void)u_rest;
    SurfaceHit h;
    fill_hit(m, f, b1, b2, h);
    Vec3 to = h.p - ref;
    double d2 = dot(to, to);
    if (!(d2 > 0)) return s;
    double dist = std::sqrt(d2);
    Vec3 wo = to * (1 / dist);
    double cos_l = std::abs(dot(h.ng, wo));
    if (!(cos_l > 1e-12)) return s;
    emitted(h, -wo, s.radiance);
    s.wo = wo;
    s.dist = dist;
    s.pdf = (1 - p_env) * light_choice_.prob(k) / meshes_[m].area[f] * d2 / cos_l;
    return s;
}

double RenderScene::emitter_pdf(const Vec3 &ref, const SurfaceHit &hit) const {
    const auto &probs = light_prob_[hit.mesh];
    if (probs.empty()) return 0.0;
    Vec3 to = hit.p - ref;
    double d2 = dot(to, to);
    double cos_l = std::abs(dot(hit.ng, to)) / std::sqrt(d2);
    if (!(cos_l > 1e-12)) return 0.0;
    return (1 - env_selection()) * probs[hit.prim] / meshes_[hit.mesh].area[hit.prim] * d2 / cos_l;
}

double RenderScene::environment_pdf(const Vec3 &d) const {
    double p = env_selection();
    return p > 0 ? p * environment_.pdf(d) : 0.0;
}

void RenderScene::environment_radiance(const Vec3 &d, double rgb[3], double &pdf) const {
    environment_.eval_pdf(d, rgb, pdf);
    pdf *= env_selection();
}

} // namespace bsdflab
