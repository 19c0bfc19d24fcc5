// The layered model: construction and checks, its lobes, its film lookups, the top's delta
// reflection, and the memory layout of one of eval's walks.
#include <algorithm>
#include <stdexcept>
#include "bsdflab/frame.h"
#include "walk.h"

namespace bsdflab {

using layered::kMaxSlabs;
using layered::kNonDeltaTransmission;
using layered::WalkMemory;

namespace {

// pfmc2 draws a slab's flights with its smallest extinction where scattering dominates the
// least absorbed channel (single-scattering albedo >= this): long walks, where per-flight
// spectral MIS weights multiply into heavy tails (docs/estimators.md).
constexpr double kMinExtinctionAlbedo = 0.95;
// ... and whose optical thickness (by that extinction) is at least this: a thinner slab sees
// few flights per walk, so no heavy tail, and the grey flights only cost variance there
// (0.88x on a tau 0.2 slab over rough gold, bench/bench_layered_compare.py).
constexpr double kMinExtinctionDepth = 1.0;

} // namespace

std::size_t LayeredBSDF::walk_doubles() const { return (6 * slabs_.size() + 8) * std::size_t(channels()); }

WalkMemory LayeredBSDF::bind_walk(EstimateWorkspace &ws, std::size_t offset) const {
    const std::size_t C = channels(), K = slabs_.size();
    double *p = ws.doubles(offset + walk_doubles()) + offset;
    WalkMemory wk;
    layered::Chain &ch = wk.chain;
    ch.a = p;
    ch.B = p + K * C;
    ch.up_extra = p + 2 * K * C;
    ch.down = p + 3 * K * C;
    ch.tau = p + 4 * K * C;
    ch.r_exit_side = p + 5 * K * C;
    p += 6 * K * C;
    double **bufs[] = {&ch.beyond, &ch.w, &wk.beta, &wk.tmp, &wk.tr, &wk.wgt, &wk.fly_tr, &wk.contrib};
    for (double **b : bufs) {
        *b = p;
        p += C;
    }
    return wk;
}

LayeredBSDF::LayeredBSDF(std::vector<double> wavelengths, std::vector<std::shared_ptr<const BSDF>> boundaries,
                         std::vector<Slab> slabs, LayeredOptions options)
    : BSDF(std::move(wavelengths)), boundaries_(std::move(boundaries)), slabs_(std::move(slabs)),
      options_(options), estimator_(static_cast<Estimator>(options.estimator)) {
    if (slabs_.empty() || slabs_.size() > static_cast<std::size_t>(kMaxSlabs))
        throw std::invalid_argument("a layered BSDF needs 1 to 16 slabs");
    if (boundaries_.size() != slabs_.size() + 1)
        throw std::invalid_argument("a layered BSDF needs one boundary more than slabs");
    for (const auto &b : boundaries_)
        if (!b || b->channels() != channels())
            throw std::invalid_argument("every boundary must have one channel per wavelength");
    for (const Slab &s : slabs_) {
        if (static_cast<int>(s.sigma_a.size()) != channels())
            throw std::invalid_argument("every slab needs sigma_a per wavelength");
    }
    if (options_.samples < 1 || options_.max_depth < 1)
        throw std::invalid_argument("samples and max_depth must be >= 1");
    if (options_.estimator != kEstimatorPfmc && options_.estimator != kEstimatorPfmc2)
        throw std::invalid_argument("estimator must be 0 (pfmc) or 1 (pfmc2)");
    for (const Slab &s : slabs_) {
        double m = s.sigma_a.empty() ? 0.0 : s.sigma_a[0];
        for (double a : s.sigma_a) m = std::min(m, a);
        min_sigma_a_.push_back(std::max(m, 0.0));
        const double sbar = s.sigma_s + min_sigma_a_.back();
        min_extinction_.push_back(s.sigma_s > 0 && s.sigma_s >= kMinExtinctionAlbedo * sbar &&
                                  sbar * s.thickness >= kMinExtinctionDepth);
    }
    // Walks share a chain only where it is deterministic: the chain from wo's side crosses
    // every boundary but the far outer one, and a non-delta transmission lobe on any of them
    // makes it random, its spread shared by the group (docs/estimators.md, "Version 6").
    const std::size_t K = slabs_.size();
    auto random = [&](std::size_t b) { return (boundaries_[b]->lobes() & kNonDeltaTransmission) != 0; };
    bool random_from_top = false, random_from_bottom = false;
    for (std::size_t b = 0; b < K; ++b) random_from_top = random_from_top || random(b);
    for (std::size_t b = 1; b <= K; ++b) random_from_bottom = random_from_bottom || random(b);
    const bool v2 = estimator_ == Estimator::Pfmc2;
    walks_per_chain_[0] = v2 && !random_from_top ? kWalksPerChain : 1;
    walks_per_chain_[1] = v2 && !random_from_bottom ? kWalksPerChain : 1;
}

uint32_t LayeredBSDF::lobes() const {
    uint32_t l = kGlossyReflection | (boundaries_.front()->lobes() & kDeltaReflection);
    if (boundaries_.back()->lobes() & kTransmission) l |= kGlossyTransmission;
    // Paths delta at every vertex (clear slabs between smooth boundaries) are delta lobes
    // of the stack: sample() labels them so (they are not part of eval).
    bool all_delta_t = true, any_delta_r = false;
    for (const auto &b : boundaries_) {
        all_delta_t = all_delta_t && (b->lobes() & kDeltaTransmission);
        any_delta_r = any_delta_r || (b->lobes() & kDeltaReflection);
    }
    if ((boundaries_.front()->lobes() & kDeltaTransmission) && any_delta_r) l |= kDeltaReflection;
    if (all_delta_t) l |= kDeltaTransmission;
    return l;
}

ScatteredPart::ScatteredPart(std::shared_ptr<const LayeredBSDF> model)
    : BSDF(model ? model->wavelengths() : std::vector<double>{}), model_(std::move(model)) {
    if (!model_) throw std::invalid_argument("ScatteredPart needs a layered model");
}

std::shared_ptr<const BSDF> LayeredBSDF::with_film_lookup(double thickness_nm, FilmLookupStats &stats) const {
    std::vector<std::shared_ptr<const BSDF>> boundaries = boundaries_;
    bool changed = false;
    for (std::size_t i = 0; i < boundaries.size(); ++i) // only the top takes the query's film
        if (auto fast = boundaries[i]->with_film_lookup(i == 0 ? thickness_nm : -1.0, stats)) {
            boundaries[i] = std::move(fast);
            changed = true;
        }
    if (!changed) return nullptr;
    return std::make_shared<LayeredBSDF>(wavelengths_, std::move(boundaries), slabs_, options_);
}

std::shared_ptr<const BSDF> ScatteredPart::with_film_lookup(double thickness_nm,
                                                            FilmLookupStats &stats) const {
    auto fast = std::dynamic_pointer_cast<const LayeredBSDF>(model_->with_film_lookup(thickness_nm, stats));
    return fast ? std::make_shared<ScatteredPart>(fast) : nullptr;
}

void LayeredBSDF::delta_reflectance(const Vec3 &wi, const Query &q, double *out) const {
    zero(out);
    if (!usable_direction(wi) || wi.z <= 0) return;
    // Only a delta reflection counts: a rough top has none (version 4 copied whatever the
    // masked sample returned, a leaked glossy transmission included).
    BSDFSample s = boundaries_.front()->sample(wi, 0.5, 0.5, 0.5, kDeltaReflection, q, out);
    if (!(s.lobe & kDeltaReflection)) zero(out);
}

} // namespace bsdflab
