// The renderer's scene: triangle meshes in an Embree BVH, their materials, emissive
// triangles (area lights, picked by power), an environment and a camera.
//
// Shading follows Mitsuba 3 so images compare pixel for pixel: BSDFs are evaluated in the
// shading frame (interpolated vertex normals, tangent from dp/du), normals are never
// flipped towards the ray (one-sided BSDFs are black from behind), and an emitter
// radiates from the side its shading normal points to.
#pragma once
#include <memory>
#include <string>
#include <vector>
#include "bsdflab/bsdf.h"
#include "bsdflab/render/camera.h"
#include "bsdflab/render/distribution.h"
#include "bsdflab/render/environment.h"
#include "bsdflab/render/lights.h"
#include "bsdflab/render/shading.h"
#include "bsdflab/scale_texture.h"

namespace bsdflab {

// Spectral mode carries this many bins per path: the default 380-780 nm grid at 5 nm.
constexpr int kSpectralBins = 81;

// A BSDF as the renderer sees it: its own channels projected to linear sRGB by P (3 x C,
// row-major; empty: the BSDF already answers in RGB, C == 3) and, for spectral mode, lifted
// to the spectral bins by U (kSpectralBins x C, row-major; empty: the BSDF's channels are
// those bins, C == kSpectralBins).
struct RenderBSDF {
    std::shared_ptr<const BSDF> bsdf;
    std::vector<double> P, U;
    uint32_t lobes = 0;
    void to_rgb(const double *channels, double rgb[3]) const;
    void to_spectrum(const double *channels, double out[kSpectralBins]) const;
};

struct Material {
    RenderBSDF surface;
    RenderBSDF gap;                             // used in scale gaps when has_gap
    bool has_gap = false;
    std::shared_ptr<const ScaleTexture> scales; // may be null
    double film_thickness_nm = -1;              // base thickness the scales modulate; < 0: none

    // The BSDF, shading frame and query at a hit (see shading.h).
    ShadingPoint shade(const SurfaceHit &hit) const;
};

struct MeshInput {
    std::vector<float> positions; // 3V
    std::vector<float> normals;   // 3V or empty
    std::vector<float> uvs;       // 2V or empty
    std::vector<uint32_t> indices; // 3F
    int material = -1;            // -1: black (emitters)
    double emission[3] = {0, 0, 0};
};

// A surface point found by a ray.
struct SurfaceHit {
    double t = 0;
    Vec3 p, ng, ns, dpdu, dpdv; // ng: unit geometric normal (counter-clockwise front); ns: shading
    double u = 0, v = 0;  // texture coordinates
    int mesh = -1;
    uint32_t prim = 0;
};

struct EmitterSample {
    Vec3 wo;           // unit direction from the reference point to the light
    double dist = 0;   // distance to the light point (inf for the environment)
    double pdf = 0;    // solid-angle density, light selection included; 0 = failed
    double radiance[3] = {0, 0, 0};
    // A delta light (point, spot, sharp directional): pdf is the selection probability
    // alone, radiance what replaces radiance in the estimator, and no MIS applies.
    bool delta = false;
    // A light with a spectral colour (kSpectralBins values): spectral mode uses
    // spectrum x factor instead of lifting `radiance` (its RGB x factor).
    const double *spectrum = nullptr;
    double factor = 0;
};

class RenderScene {
  public:
    RenderScene();
    ~RenderScene();
    RenderScene(const RenderScene &) = delete;
    RenderScene &operator=(const RenderScene &) = delete;

    int add_material(Material m);
    int add_mesh(MeshInput m);
    void set_camera(const Camera &c);
    void set_environment(Environment e);
    // A point, spot or directional light (render/lights.h); `spectrum` (kSpectralBins
    // values, or empty) is its colour for spectral mode, whose RGB the light carries.
    void add_light(const AnalyticLight &light, std::vector<double> spectrum = {});
    // Spectral mode's colour: U (kSpectralBins x 3) lifts RGB emission to the bins, W
    // (3 x kSpectralBins) takes a spectrum (illuminant folded in) to linear sRGB.
    void set_spectral(std::vector<double> U, std::vector<double> W);
    // Every material has a spectral form and the matrices are set.
    bool spectral_ready() const { return !W_.empty() && spectral_capable_; }
    void lift(const double rgb[3], double out[kSpectralBins]) const;
    const double *sensor() const { return W_.data(); }
    bool committed() const { return committed_; }
    // Embree's robust traversal (watertight on shared edges, ~1.8x slower traversal on the
    // project's scenes; see docs/rendering.md for the measured leak rate of the default).
    void set_robust(bool robust);
    bool robust() const { return robust_; }
    // Builds the BVH and the light distribution; the scene is read-only afterwards.
    void commit();

    const Camera &camera() const { return camera_; }
    const Environment &environment() const { return environment_; }
    const Material *material_of(int mesh) const;
    bool has_lights() const { return environment_.active() || !lights_.empty() || !analytic_.empty(); }
    // The most channels any material's BSDF produces (sizes per-thread buffers).
    int max_channels() const { return max_channels_; }

    bool intersect(const Vec3 &o, const Vec3 &d, double tmax, SurfaceHit &hit) const;
    bool occluded(const Vec3 &o, const Vec3 &d, double tmax) const;
    // Embree alone: traces recorded rays (8 floats each, see RenderJob::record_rays) on all
    // cores with rtcIntersect1 / rtcOccluded1 and nothing else; returns the wall seconds.
    // packet = 16: in 16-wide packets (rtcIntersect16 / rtcOccluded16, consecutive rays of
    // one kind), the traversal a wavefront renderer such as Mitsuba's llvm variant uses.
    double trace_recorded(const float *rays, std::size_t n, int packet = 1) const;
    // First hit of each ray (origin, direction: 6 floats each) on all cores: the mesh id, or
    // -1 for a miss (for watertightness tests).
    void first_hits(const float *rays, std::size_t n, int *mesh) const;

    // Radiance a surface emits at `hit` towards direction `w` (unit, away from the surface).
    void emitted(const SurfaceHit &hit, const Vec3 &w, double rgb[3]) const;
    // Light sampling from point `ref`: one emitter strategy chosen uniformly among the
    // environment, the area lights (then a triangle by power) and each analytic light.
    EmitterSample sample_emitter(const Vec3 &ref, double u0, double u1, double u2) const;
    // Density with which sample_emitter(ref) would have produced the emitter point `hit`.
    double emitter_pdf(const Vec3 &ref, const SurfaceHit &hit) const;
    // ... or the environment in direction d.
    double environment_pdf(const Vec3 &d) const;
    // The environment radiance arriving from direction d, and environment_pdf(d), in one lookup.
    void environment_radiance(const Vec3 &d, double rgb[3], double &pdf) const;
    // Soft suns (directional lights with an angular diameter) a ray leaving the scene can
    // find: soft_light(i, d, ...) gives the i-th one's radiance and sample_emitter's density
    // (selection included) in direction d; false outside its cone.
    std::size_t soft_lights() const { return soft_.size(); }
    // `spectrum`: the light's spectral colour (to scale by `factor`), or null.
    bool soft_light(std::size_t i, const Vec3 &d, double rgb[3], double &pdf, const double *&spectrum,
                    double &factor) const;

  private:
    struct Mesh;
    void fill_hit(int mesh, uint32_t prim, double b1, double b2, SurfaceHit &hit) const;
    double env_selection() const;
    double area_selection() const;
    // An area light chosen by power with u0, a point on it with (u1, u2); p_area: the
    // probability of the area-light strategy.
    EmitterSample sample_area(const Vec3 &ref, double u0, double u1, double u2, double p_area) const;

    struct Embree;
    std::unique_ptr<Embree> embree_;
    std::vector<Mesh> meshes_;
    std::vector<Material> materials_;
    Camera camera_;
    Environment environment_;
    // Emissive triangles: (mesh, prim) pairs picked by power = area x luminance.
    std::vector<std::pair<int, uint32_t>> lights_;
    Distribution1D light_choice_;
    std::vector<std::vector<double>> light_prob_; // per mesh, per triangle (empty if not emissive)
    std::vector<AnalyticLight> analytic_;
    std::vector<std::vector<double>> analytic_spectra_; // per analytic light: kSpectralBins or empty
    std::vector<std::size_t> soft_;   // indices into analytic_ of the soft suns
    std::size_t strategies_ = 0;      // environment + area lights + analytic lights
    int max_channels_ = 3;
    std::vector<double> U_, W_;
    bool spectral_capable_ = true;
    bool committed_ = false;
    bool robust_ = false;
};

} // namespace bsdflab
