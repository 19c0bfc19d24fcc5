// The BSDF interface of the core (Mitsuba's convention):
//   eval(wi, wo)      -> f(wi, wo) * |cos theta_o|, one value per channel
//   pdf(wi, wo)       -> solid-angle density of sample() producing wo
//   sample(wi, u1,u2) -> wo, weight = f |cos theta_o| / pdf, pdf, the sampled lobe
// Delta lobes evaluate to 0 in eval/pdf and are reached only through sample().
//
// A BSDF object is built for a fixed list of channels (wavelengths, in nm): spectral
// parameters are resolved per channel by the Python layer before construction, so the
// core never interpolates spectra in a hot loop. Implementations are immutable after
// construction and therefore safe to share between threads.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>
#include "vector.h"

namespace bsdflab {

class StochasticEstimator; // estimate.h

// Lobe flags: one bit per (diffuse | glossy | delta) x (reflection | transmission).
enum Lobe : uint32_t {
    kNone = 0,
    kDiffuseReflection = 1u << 0,
    kGlossyReflection = 1u << 1,
    kDeltaReflection = 1u << 2,
    kDiffuseTransmission = 1u << 3,
    kGlossyTransmission = 1u << 4,
    kDeltaTransmission = 1u << 5,
    kReflection = kDiffuseReflection | kGlossyReflection | kDeltaReflection,
    kTransmission = kDiffuseTransmission | kGlossyTransmission | kDeltaTransmission,
    kDelta = kDeltaReflection | kDeltaTransmission,
    kAll = kReflection | kTransmission,
};

// Per-query surface parameters that may vary across a surface (textures in a renderer).
// A negative value means "use the model's own default".
struct Query {
    double film_thickness_nm = -1.0;
};

// A stack's per-query film thickness is its top film's: the query boundary b (0 the top)
// of a layered stack sees. Every other boundary keeps its own film (estimator version 8).
inline constexpr Query kOwnFilm{};
inline const Query &boundary_query(const Query &q, int b) { return b == 0 ? q : kOwnFilm; }

struct BSDFSample {
    Vec3 wo;
    double pdf = 0;     // solid-angle density; for a delta lobe, the probability of picking it
    uint32_t lobe = 0;  // the single lobe that produced wo; 0 = no sample
    double eta = 1;     // relative index crossed (n_t / n_i), 1 for reflection
};

// What BSDF::with_film_lookup made: the largest measured error of its lookups (-1: none)
// and their memory.
struct FilmLookupStats {
    double max_error = -1;
    std::size_t bytes = 0;
};

class BSDF {
  public:
    explicit BSDF(std::vector<double> wavelengths) : wavelengths_(std::move(wavelengths)) {}
    virtual ~BSDF() = default;

    int channels() const { return static_cast<int>(wavelengths_.size()); }
    const std::vector<double> &wavelengths() const { return wavelengths_; }
    virtual uint32_t lobes() const = 0;

    // Writes channels() values to `out`; zeros when nothing is reachable.
    virtual void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const = 0;
    virtual double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const = 0;
    // Writes channels() weights to `weight`; returns lobe 0 and zero weights on failure.
    virtual BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                              const Query &q, double *weight) const = 0;
    // Monte Carlo models (eval is an estimate) expose their estimator; others return null.
    virtual const StochasticEstimator *stochastic() const { return nullptr; }
    // The same BSDF for queries at film thickness `thickness_nm` (< 0: the model's own)
    // with its thin-film terms tabulated over the cosine (film_lookup.h): a faster copy
    // for callers whose thickness is fixed for many queries (the tabulator's cells).
    // nullptr: no such copy (no film, or no lookup reached its measured error bound).
    // `stats` accumulates the lookups' measured error and memory.
    virtual std::shared_ptr<const BSDF> with_film_lookup(double /*thickness_nm*/,
                                                         FilmLookupStats & /*stats*/) const {
        return nullptr;
    }

  protected:
    void zero(double *out) const {
        for (int c = 0; c < channels(); ++c) out[c] = 0.0;
    }
    std::vector<double> wavelengths_;
};

} // namespace bsdflab
