// A layered BSDF evaluated by Position-Free Monte Carlo (Guo, Hasan, Zhao 2018; pbrt-v4's
// LayeredBxDF is the two-interface special case). The stack, top to bottom:
//     boundary 0 (top interface), slab 0, boundary 1, slab 1, ..., slab K-1, boundary K (base)
// Boundaries are BSDFs whose exterior (+z) is the slab above and interior (-z) the slab
// below; the base is any BSDF (diffuse, conductor, or an interface to a medium below).
// Slabs have a thickness (um), a spectral absorption sigma_a (1/um), a grey scattering
// coefficient sigma_s (1/um) and a phase function. Lateral displacement is ignored, so a
// path vertex is just (slab, depth, direction).
//
// eval(wi, wo): random walks start at wi (the camera side, radiance transport) and carry
// a spectral throughput. A "light chain" is sampled once per walk from wo through the
// boundaries on the exit side (transmission only), giving per slab the direction u_j that
// leads straight out to wo and the factor of that unscattered path. Every non-delta vertex
// (medium scattering, reflection at the non-exit side of a slab) connects to the chain
// (next-event estimation, strategy A). After a vertex samples a direction toward a rough
// exit-side boundary, that boundary's BTDF toward the chain is evaluated (strategy B); A
// and B are combined with the power heuristic. The walk itself never leaves through the
// exit side, so no path is counted twice. Russian roulette after a few bounces and a depth
// cap end every walk. The top boundary's own reflection is added exactly (non-delta part);
// its delta part is not estimated: see delta_reflectance / sample.
//
// Paths whose every vertex is a delta event (e.g. a smooth coat over a smooth mirror) form
// a delta lobe of the stack and are not part of eval.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>
#include "bsdf.h"
#include "phase.h"
#include "rng.h"

namespace bsdflab {

struct Slab {
    double thickness = 0.0;       // um
    std::vector<double> sigma_a;  // 1/um, per channel
    double sigma_s = 0.0;         // 1/um, grey
    PhaseFunction phase;
};

struct LayeredOptions {
    int samples = 256;    // walks per eval()
    uint64_t seed = 0;
    int max_depth = 256;  // scattering events per walk
    bool nee = true;      // false: strategy B only (the naive walk, for benchmarks)
};

class LayeredBSDF final : public BSDF {
public:
    LayeredBSDF(std::vector<double> wavelengths, std::vector<std::shared_ptr<const BSDF>> boundaries,
                std::vector<Slab> slabs, LayeredOptions options);
    uint32_t lobes() const override;
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
              double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const override;
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                      const Query &q, double *weight) const override;

    // eval() with an explicit effort and seed, also writing the standard error per channel.
    void eval_with_error(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                         int samples, uint64_t seed, double *out, double *stderr_out) const;
    // The same estimate projected by P (rows x channels, row-major) before the statistics,
    // so errors of derived quantities (RGB, luminance) are exact; `include_direct` false
    // leaves out the top boundary's own (deterministic) reflection.
    void eval_projected(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, int samples,
                        uint64_t seed, const double *P, int rows, bool include_direct, double *out,
                        double *stderr_out) const;
    // Reflectance of the top boundary's delta lobe toward the mirror direction.
    void delta_reflectance(const Vec3 &wi, const Query &q, double *out) const;
    const LayeredOptions &options() const { return options_; }

private:
    struct Chain;
    struct Walk;
    bool build_chain(const Vec3 &wo, int exit, const Query &q, PCG32 &rng, Chain &chain) const;
    void one_walk(const Vec3 &wi, const Vec3 &wo, int entry, int exit, const Query &q,
                  PCG32 &rng, double *contrib) const;
    void transmittance(int slab, double distance, double *tr) const;
    // Advances a flight of at most `room` depth in slab j along a direction of |z| = cz,
    // sampled by spectral MIS over the channels' extinctions (so absorbing slabs scatter
    // where light actually reaches, with weights bounded by the channel count):
    // returns the travelled distance along the ray if it ends in a scattering event
    // (throughput updated), or a negative number if it reaches the boundary.
    double fly(const Slab &S, double room, double cz, PCG32 &rng, double *beta) const;

    std::vector<std::shared_ptr<const BSDF>> boundaries_;
    std::vector<Slab> slabs_;
    LayeredOptions options_;
};

} // namespace bsdflab
