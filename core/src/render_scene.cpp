// The scene's geometry: meshes into Embree, intersection and occlusion, surface hits.
// Material colour is in render_colour.cpp, emitters and the environment in
// render_lights.cpp, Embree-only probes (benchmarks, tests) in render_probes.cpp.
#include "bsdflab/render/scene.h"
#include <embree3/rtcore.h>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include "bsdflab/frame.h"
#include "bsdflab/scratch.h" // kLuminanceRGB
#include "render_scene_impl.h"

namespace bsdflab {

namespace {
// Embree reports errors through a callback; keep the last one for the exception text.
void on_embree_error(void *user, RTCError code, const char *message) {
    auto *last = static_cast<std::string *>(user);
    *last = "Embree error " + std::to_string(int(code)) + ": " + (message ? message : "");
}
} // namespace

RenderScene::Embree::Embree() {
    device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("could not create an Embree device");
    rtcSetDeviceErrorFunction(device, on_embree_error, &last_error);
    scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
}

RenderScene::Embree::~Embree() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
}

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
    if (!m.normals.empty() && m.normals.size() != 3 * V)
        throw std::invalid_argument("mesh: normals must be (V, 3)");
    if (!m.uvs.empty() && m.uvs.size() != 2 * V) throw std::invalid_argument("mesh: uvs must be (V, 2)");
    for (uint32_t i : m.indices)
        if (i >= V) throw std::invalid_argument("mesh: index out of range");
    for (float x : m.positions)
        if (!std::isfinite(x)) throw std::invalid_argument("mesh: non-finite vertex position");
    if (m.material < -1 || m.material >= int(materials_.size()))
        throw std::invalid_argument("mesh: unknown material");
    for (double e : m.emission)
        if (!(std::isfinite(e) && e >= 0))
            throw std::invalid_argument("mesh: emission must be finite and >= 0");

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
    auto *vb = static_cast<float *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), V));
    auto *ib = static_cast<uint32_t *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), F));
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
    if (committed_)
        throw std::logic_error("scene already committed: choose robust traversal before commit()");
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
    strategies_ = (environment_.active() ? 1 : 0) + (lights_.empty() ? 0 : 1) + analytic_.size();
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
    Vec3 p0 = vertex(m.positions, 3, t[0]), p1 = vertex(m.positions, 3, t[1]),
         p2 = vertex(m.positions, 3, t[2]);
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
    rh.ray.tfar =
        tmax < std::numeric_limits<float>::max() ? float(tmax) : std::numeric_limits<float>::infinity();
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

} // namespace bsdflab
