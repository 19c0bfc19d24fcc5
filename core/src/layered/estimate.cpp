// eval's estimate: groups of walks per light chain, their mean and standard error (Welford),
// plus the entry boundary's exact reflection. The loop's body is one function
// (estimate_impl), the walk itself is EvalWalk (eval_walk.h).
#include <algorithm>
#include <cmath>
#include "bsdflab/frame.h"
#include "bsdflab/scratch.h"
#include "eval_walk.h"

namespace bsdflab {

using layered::EvalWalk;
using layered::Side;
using layered::WalkMemory;

std::uint64_t LayeredBSDF::estimate_impl(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                                         const EstimateRequest &req, bool include_direct,
                                         EstimateWorkspace &ws, double *out, double *err) const {
    const int C = channels(), K = static_cast<int>(slabs_.size());
    const int R = req.out_rows(C);
    const int samples = req.samples;
    for (int r = 0; r < R; ++r) out[r] = err[r] = 0.0;
    if (!usable_direction(wi) || !usable_direction(wo) || samples < 1) return 0;
    const bool base_transmits = boundaries_.back()->lobes() & kTransmission;
    if (wi.z < 0 && !base_transmits) return 0;
    if (wo.z < 0 && !base_transmits) return 0;
    const bool reflect = wi.z * wo.z > 0;
    if (!(lobes & (reflect ? kGlossyReflection : kGlossyTransmission))) return 0; // lobes()
    const Side entry = layered::side_of(wi), exit = layered::side_of(wo);

    // Workspace layout: the walk, then x, mean, m2 (R each) and direct (C).
    const std::size_t wn = walk_doubles();
    double *extra = ws.doubles(wn + 3 * R + C) + wn;
    WalkMemory wk = bind_walk(ws, 0);
    double *x = extra, *mean = extra + R, *m2 = extra + 2 * R, *direct = extra + 3 * R;
    std::fill(mean, mean + 2 * R, 0.0);

    PCG32 rng(hash_directions(req.seed, wi, wo));
    EvalWalk walk(*this, q, rng, wk, entry, exit);
    std::uint64_t nonfinite = 0, capped = 0;
    const double cos_o = std::abs(wo.z);
    // pfmc: one walk per chain, each walk one sample of the mean. pfmc2: groups of up to
    // kWalksPerChain walks (1 where the chain is random: a non-delta boundary on its way)
    // share a chain (and its entry connection, added once at the group's weight); a group's
    // mean is one sample (its walks are correlated).
    // At least two groups whenever samples >= 2, so that the standard error is estimated.
    const int per_chain = std::max(1, std::min(walks_per_chain_[exit == Side::Top ? 0 : 1], samples / 2));
    const int groups = (samples + per_chain - 1) / per_chain;
    for (int n = 1; n <= groups; ++n) {
        std::fill(wk.contrib, wk.contrib + C, 0.0);
        build_chain(wo, exit, q, rng, wk.chain, wk.tr);
        const int walks = std::min(per_chain, samples - (n - 1) * per_chain);
        for (int k = 0; k < walks; ++k)
            if (walk.run(wi, k == 0 ? double(walks) : 0.0)) ++capped;
        bool finite = true;
        for (int c = 0; c < C; ++c) finite = finite && std::isfinite(wk.contrib[c]);
        if (!finite) { // counted and reported by the caller; never part of the mean
            nonfinite += walks;
            std::fill(wk.contrib, wk.contrib + C, 0.0);
        }
        for (int c = 0; c < C; ++c) wk.contrib[c] *= cos_o / walks;
        project_rows(req.P, R, C, wk.contrib, x);
        for (int r = 0; r < R; ++r) { // Welford: running mean and sum of squared deviations
            double d = x[r] - mean[r];
            mean[r] += d / n;
            m2[r] += d * (x[r] - mean[r]);
        }
    }
    // The entry boundary's own (non-delta) reflection is known exactly.
    std::fill(direct, direct + C, 0.0);
    if (include_direct && entry == exit)
        boundaries_[outer_boundary(entry, K)]->eval(wi, wo, kReflection,
                                                    boundary_query(q, outer_boundary(entry, K)), direct);
    project_rows(req.P, R, C, direct, x);
    for (int r = 0; r < R; ++r) {
        out[r] = mean[r] + x[r];
        err[r] = groups > 1 ? std::sqrt(m2[r] / (double(groups) * (groups - 1))) : 0.0;
    }
    if (req.grouping) { // full groups of per_chain walks, then one of `rest`
        const int full = samples / per_chain, rest = samples % per_chain;
        const double inverse_walks = double(full) / per_chain + (rest ? 1.0 / rest : 0.0);
        *req.grouping = {groups, double(groups) * groups / inverse_walks};
    }
    if (capped) {
        if (req.capped) *req.capped += capped;
        else capped_.fetch_add(capped, std::memory_order_relaxed);
    }
    return nonfinite;
}

std::uint64_t LayeredBSDF::estimate(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                                    const EstimateRequest &request, EstimateWorkspace &ws, double *mean,
                                    double *err) const {
    return estimate_impl(wi, wo, lobes, q, request, true, ws, mean, err);
}

std::uint64_t LayeredBSDF::estimate_scattered(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                                              const EstimateRequest &request, EstimateWorkspace &ws,
                                              double *mean, double *err) const {
    return estimate_impl(wi, wo, lobes, q, request, false, ws, mean, err);
}

// eval() at the model's own effort and seed, on leased workspaces: one for the walks, one
// for the standard errors nobody asked for.
void LayeredBSDF::eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const {
    ThreadWorkspace walks, errors;
    EstimateRequest req{options_.samples, options_.seed};
    estimate(wi, wo, lobes, q, req, walks.get(), out, errors.get().doubles(channels()));
}

void ScatteredPart::eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const {
    ThreadWorkspace walks, errors;
    EstimateRequest req{model_->options().samples, model_->options().seed};
    estimate(wi, wo, lobes, q, req, walks.get(), out, errors.get().doubles(channels()));
}

} // namespace bsdflab
