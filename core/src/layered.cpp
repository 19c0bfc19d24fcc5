#include "bsdflab/layered.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/frame.h"
#include "bsdflab/sampling.h"
#include "bsdflab/scratch.h"
#include "bsdflab/vector_math.h"

namespace bsdflab {

namespace {

constexpr int kMaxSlabs = 16;
constexpr int kRouletteDepth = 4;
// pfmc2 draws a slab's flights with its smallest extinction where scattering dominates the
// least absorbed channel (single-scattering albedo >= this): long walks, where per-flight
// spectral MIS weights multiply into heavy tails (docs/estimators.md).
constexpr double kMinExtinctionAlbedo = 0.95;
// ... and whose optical thickness (by that extinction) is at least this: a thinner slab sees
// few flights per walk, so no heavy tail, and the grey flights only cost variance there
// (0.88x on a tau 0.2 slab over rough gold, bench/bench_layered_compare.py).
constexpr double kMinExtinctionDepth = 1.0;
// A boundary that transmits through a non-delta lobe: strategy B can evaluate it.
constexpr uint32_t kNonDeltaTransmission = kDiffuseTransmission | kGlossyTransmission;

bool any_positive(const double *v, int n) {
    for (int c = 0; c < n; ++c)
        if (v[c] > 0) return true;
    return false;
}

// One boundary sample with its three random numbers drawn in a fixed order.
BSDFSample sample_boundary(const BSDF &b, const Vec3 &wi, uint32_t mask, const Query &q, PCG32 &rng,
                           double *weight) {
    const double u1 = rng.uniform();
    const double u2 = rng.uniform();
    const double u3 = rng.uniform();
    return b.sample(wi, u1, u2, u3, mask, q, weight);
}

Vec3 sample_phase(const PhaseFunction &phase, const Vec3 &w, PCG32 &rng) {
    const double u1 = rng.uniform();
    const double u2 = rng.uniform();
    return phase.sample(w, u1, u2);
}

} // namespace

// The state of one random walk: the light chain from wo and the walk's per-channel
// buffers. Its memory is carved from the caller's EstimateWorkspace (bind_walk), so walks
// allocate nothing and nothing is shared between estimates behind their backs.
// Chain, per slab j: the direction u_j leading from the exit side into slab j, the light
// direction L_j just beyond slab j's exit-side boundary, the last-step factor
// a_j = f_adjoint / pdf and the factor B_j of everything beyond that boundary.
struct LayeredBSDF::Walk {
    bool reached[kMaxSlabs]; // L_j and B_j known (strategy B possible)
    bool ok[kMaxSlabs];      // u_j sampled too (strategy A possible)
    bool delta[kMaxSlabs];
    double pdf[kMaxSlabs];
    Vec3 u[kMaxSlabs], L[kMaxSlabs];
    double *a, *B;                        // [slab * C + c]
    // Delta-chain connections (all-delta exit side, see solve_delta_region): per slab, the
    // factor (over |u_j.z|) of leaving along -u_j and coming back by at least one delta
    // reflection (up_extra), and of leaving along the mirror of -u_j, away from the exit
    // (down). Zero outside the region.
    double *up_extra, *down;              // [slab * C + c]
    double *tau, *r_exit_side;            // region solve: slab transmittance, X_j's reflection
    bool region[kMaxSlabs];
    double *beyond, *chain_w;             // chain construction
    double *beta, *tmp, *tr, *wgt, *fly_tr;
    double *contrib;                      // this walk's contribution, per channel
};

std::size_t LayeredBSDF::walk_doubles() const { return (6 * slabs_.size() + 8) * std::size_t(channels()); }

LayeredBSDF::Walk LayeredBSDF::bind_walk(EstimateWorkspace &ws, std::size_t offset) const {
    const std::size_t C = channels(), K = slabs_.size();
    double *p = ws.doubles(offset + walk_doubles()) + offset;
    Walk wk;
    wk.a = p;
    wk.B = p + K * C;
    wk.up_extra = p + 2 * K * C;
    wk.down = p + 3 * K * C;
    wk.tau = p + 4 * K * C;
    wk.r_exit_side = p + 5 * K * C;
    p += 6 * K * C;
    double **bufs[] = {&wk.beyond, &wk.chain_w, &wk.beta, &wk.tmp, &wk.tr, &wk.wgt, &wk.fly_tr, &wk.contrib};
    for (double **b : bufs) {
        *b = p;
        p += C;
    }
    return wk;
}

LayeredBSDF::LayeredBSDF(std::vector<double> wavelengths, std::vector<std::shared_ptr<const BSDF>> boundaries,
                         std::vector<Slab> slabs, LayeredOptions options)
    : BSDF(std::move(wavelengths)), boundaries_(std::move(boundaries)), slabs_(std::move(slabs)),
      options_(options) {
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
    const bool v2 = options_.estimator == kEstimatorPfmc2;
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

double LayeredBSDF::fly(const Slab &S, double room, double cz, PCG32 &rng, double *beta, double *tr) const {
    const int C = channels();
    const double length = room / cz;
    if (!(S.sigma_s > 0)) { // pure absorption: attenuate deterministically
        absorb(S, length, beta, tr);
        return -1.0;
    }
    // Spectral MIS (one-sample, balance heuristic over channels): draw the flight with a
    // randomly chosen channel's extinction; weight each channel by its true density over
    // the channel-average density. Weights stay below C whatever the spectral contrast.
    const double u_channel = rng.uniform();
    const double u_distance = rng.uniform();
    const int k = std::min(C - 1, static_cast<int>(u_channel * C));
    const double sk = S.sigma_a[k] + S.sigma_s;
    const double t = -std::log(1.0 - u_distance) / sk;
    const bool collide = t < length;
    const double d = collide ? t : length;
    for (int c = 0; c < C; ++c) tr[c] = -(S.sigma_a[c] + S.sigma_s) * d;
    exp_array(tr, tr, C);
    double avg = 0;
    for (int c = 0; c < C; ++c) avg += collide ? (S.sigma_a[c] + S.sigma_s) * tr[c] : tr[c];
    avg /= C;
    if (!(avg > 0)) { // every channel extinct: the walk carries nothing
        for (int c = 0; c < C; ++c) beta[c] = 0.0;
        return -1.0;
    }
    for (int c = 0; c < C; ++c) beta[c] *= (collide ? S.sigma_s : 1.0) * tr[c] / avg;
    return collide ? t : -1.0;
}

// Distances drawn with density sbar exp(-sbar t), sbar = sigma_s + min_c sigma_a[c], a grey
// extinction no channel's is below: a collision at t weighs channel c by
// sigma_s exp(-sigma_t[c] t) / (sbar exp(-sbar t)) = (sigma_s / sbar) exp(-(sigma_a[c] - min) t)
// and reaching the boundary (probability exp(-sbar L)) by exp(-(sigma_a[c] - min) L):
// both <= 1, so a walk's spectral weights never grow, however many flights it has.
double LayeredBSDF::fly_min_extinction(std::size_t j, double room, double cz, PCG32 &rng, double *beta,
                                       double *tmp) const {
    const Slab &S = slabs_[j];
    const int C = channels();
    const double length = room / cz, amin = min_sigma_a_[j];
    const double sbar = S.sigma_s + amin;
    if (!(S.sigma_s > 0)) { // pure absorption: attenuate deterministically
        absorb(S, length, beta, tmp);
        return -1.0;
    }
    const double u_distance = rng.uniform();
    const double t = -std::log(1.0 - u_distance) / sbar;
    const bool collide = t < length;
    const double d = collide ? t : length;
    const double scale = collide ? S.sigma_s / sbar : 1.0;
    for (int c = 0; c < C; ++c) {
        const double extra = S.sigma_a[c] - amin;
        tmp[c] = extra > 0 ? -extra * d : 0.0; // exp(0) = 1 exactly: the least absorbed channel
    }
    exp_array(tmp, tmp, C);
    for (int c = 0; c < C; ++c) beta[c] *= scale * tmp[c];
    return collide ? t : -1.0;
}

void LayeredBSDF::absorb(const Slab &S, double length, double *beta, double *tmp) const {
    const int C = channels();
    for (int c = 0; c < C; ++c) tmp[c] = -S.sigma_a[c] * length;
    exp_array(tmp, tmp, C);
    for (int c = 0; c < C; ++c) beta[c] *= tmp[c];
}

void LayeredBSDF::transmittance(int j, double distance, double *tr) const {
    const Slab &s = slabs_[j];
    const int C = channels();
    for (int c = 0; c < C; ++c) tr[c] = -(s.sigma_a[c] + s.sigma_s) * distance;
    exp_array(tr, tr, C);
}

void LayeredBSDF::build_chain(const Vec3 &wo, int exit, const Query &q, PCG32 &rng, Walk &ch) const {
    const int K = static_cast<int>(slabs_.size()), C = channels();
    for (int j = 0; j < K; ++j) ch.ok[j] = ch.reached[j] = ch.delta[j] = false;
    std::fill(ch.a, ch.a + K * C, 0.0);
    std::fill(ch.B, ch.B + K * C, 0.0);
    double *beyond = ch.beyond, *w = ch.chain_w, *tr = ch.tr;
    std::fill(beyond, beyond + C, 1.0);
    Vec3 L = wo;
    for (int step = 0; step < K; ++step) {
        int j = exit == 0 ? step : K - 1 - step;
        int xb = exit == 0 ? j : j + 1;
        ch.reached[j] = true;
        ch.L[j] = L;
        for (int c = 0; c < C; ++c) ch.B[j * C + c] = beyond[c];
        BSDFSample s = sample_boundary(*boundaries_[xb], L, kTransmission, q, rng, w);
        if (!s.lobe || !any_positive(w, C)) break;
        double cu = std::abs(s.wo.z);
        if (!(cu > 1e-12)) break;
        ch.ok[j] = true;
        ch.delta[j] = s.lobe & kDelta;
        ch.pdf[j] = s.pdf;
        ch.u[j] = s.wo;
        // Radiance-mode weight -> adjoint value f(u, L) / pdf by generalised reciprocity.
        transmittance(j, slabs_[j].thickness / cu, tr);
        for (int c = 0; c < C; ++c) {
            ch.a[j * C + c] = w[c] * s.eta * s.eta / cu;
            beyond[c] *= tr[c] * ch.a[j * C + c] * cu;
        }
        L = -s.wo;
    }
    solve_delta_region(exit, q, ch);
}

// The delta region: the slabs (in exit order from the exit) whose whole straight chain to
// wo is delta, so that every direction in them is fixed by wo. A vertex there can leave
// through delta events only, bouncing between the region's delta boundaries any number of
// times; no other strategy counts those paths (strategy B needs a rough exit-side boundary,
// and the walk never leaves through the exit side). Their total is a deterministic
// 1-D transport problem in the chain's adjoint convention (each event the factor w eta^2
// of a boundary sample in the chain's direction of travel, as build_chain), solved exactly:
//   D_j: a beam entering slab j at its exit-side boundary X_j, travelling along u_j;
//   U_j: a beam leaving slab j's other boundary N_j, travelling back toward X_j;
//   D_j = [j exit slab ? t(X_j) : t(X_j) tau_j' D_j'] + r_in(X_j) tau_j U_j,
//   U_j = rho_j tau_j D_j,  rho_j = r(N_j) + t_dn t_up tau_j''^2 rho_j'' / (1 - r_in(X_j'') tau_j''^2 rho_j''),
// (j' the slab toward the exit, j'' the one away, tau the slab's transmittance along u).
// The straight part of D_j (the chain's a_j |u_j.z| B_j) is strategy A's; the rest
// (up_extra) and U_j (down) are new connections with MIS weight 1. Reflections keep
// |u_j.z|, so the solid-angle Jacobian 1/|u_j.z| of A applies unchanged; every crossing
// of an interior boundary carries its own eta^2 in the w eta^2 factor.
void LayeredBSDF::solve_delta_region(int exit, const Query &q, Walk &ch) const {
    const int K = static_cast<int>(slabs_.size()), C = channels();
    int order[kMaxSlabs];
    int m = 0;
    for (int step = 0; step < K; ++step) {
        const int j = exit == 0 ? step : K - 1 - step;
        ch.region[j] = false;
        if (m == step && ch.ok[j] && ch.delta[j]) order[m++] = j;
    }
    if (m == 0) return;
    auto mirror = [](const Vec3 &u) { return Vec3{u.x, u.y, -u.z}; };
    auto nb = [&](int j) { return exit == 0 ? j + 1 : j; };  // N_j
    auto xb = [&](int j) { return exit == 0 ? j : j + 1; };  // X_j
    double *w = ch.chain_w, *t_up = ch.beyond;
    for (int k = 0; k < m; ++k) {
        const int j = order[k];
        ch.region[j] = true;
        const double cu = std::abs(ch.u[j].z);
        transmittance(j, slabs_[j].thickness / cu, ch.tau + j * C);
        // X_j seen from inside: a beam travelling toward the exit along mirror(u_j).
        double *rx = ch.r_exit_side + j * C;
        BSDFSample r = boundaries_[xb(j)]->sample(-mirror(ch.u[j]), 0.5, 0.5, 0.5, kDeltaReflection, q, w);
        for (int c = 0; c < C; ++c) rx[c] = (r.lobe & kDeltaReflection) ? w[c] : 0.0;
    }
    // Inward to outward: rho_j (stored in `down`).
    for (int k = m - 1; k >= 0; --k) {
        const int j = order[k];
        double *rho = ch.down + j * C;
        BSDFSample r = boundaries_[nb(j)]->sample(-ch.u[j], 0.5, 0.5, 0.5, kDeltaReflection, q, w);
        for (int c = 0; c < C; ++c) rho[c] = (r.lobe & kDeltaReflection) ? w[c] : 0.0;
        if (k + 1 == m) continue;
        const int j2 = order[k + 1];
        // Back across N_j from slab j2, toward the exit.
        BSDFSample t =
            boundaries_[nb(j)]->sample(-mirror(ch.u[j2]), 0.5, 0.5, 0.5, kDeltaTransmission, q, t_up);
        if (!(t.lobe & kDeltaTransmission)) continue;
        const double cu2 = std::abs(ch.u[j2].z);
        for (int c = 0; c < C; ++c) {
            const double t_dn = ch.a[j2 * C + c] * cu2;
            const double g = ch.tau[j2 * C + c] * ch.tau[j2 * C + c] * ch.down[j2 * C + c];
            const double denom = 1.0 - ch.r_exit_side[j2 * C + c] * g;
            if (denom > 1e-12) rho[c] += t_dn * t_up[c] * t.eta * t.eta * g / denom;
        }
    }
    // Outward to inward: D_j (stored in `up_extra` for now), then the connection factors.
    for (int k = 0; k < m; ++k) {
        const int j = order[k];
        const double cu = std::abs(ch.u[j].z);
        for (int c = 0; c < C; ++c) {
            const int i = j * C + c;
            const double tau = ch.tau[i];
            double d_in; // the beam arriving through X_j
            if (k == 0) {
                d_in = ch.a[i] * cu;
            } else {
                const int jp = order[k - 1], ip = jp * C + c;
                d_in = ch.a[i] * cu * ch.tau[ip] * ch.up_extra[ip];
            }
            const double denom = 1.0 - ch.r_exit_side[i] * tau * tau * ch.down[i];
            const double D = denom > 1e-12 ? d_in / denom : 0.0;
            ch.up_extra[i] = D;
            ch.down[i] *= tau * D; // U_j
        }
    }
    for (int k = 0; k < m; ++k) {
        const int j = order[k];
        const double cu = std::abs(ch.u[j].z);
        for (int c = 0; c < C; ++c) {
            const int i = j * C + c;
            const double straight = ch.a[i] * cu * ch.B[i];
            ch.up_extra[i] = std::max(0.0, ch.up_extra[i] - straight) / cu;
            ch.down[i] /= cu;
        }
    }
}

bool LayeredBSDF::one_walk(const Vec3 &wi, int entry, int exit, const Query &q, PCG32 &rng, Walk &wk,
                           double entry_scale) const {
    const int K = static_cast<int>(slabs_.size()), C = channels();
    double *beta = wk.beta, *tmp = wk.tmp, *tr = wk.tr, *wgt = wk.wgt, *contrib = wk.contrib;
    std::fill(beta, beta + C, 1.0); // the entry vertex connects before its own sample
    const bool nee = options_.nee;
    const bool v2 = options_.estimator == kEstimatorPfmc2;

    auto xb = [&](int j) { return exit == 0 ? j : j + 1; };
    auto toward_exit = [&](const Vec3 &w) { return exit == 0 ? w.z > 0 : w.z < 0; };
    auto rough_exit = [&](int j) { return (boundaries_[xb(j)]->lobes() & kNonDeltaTransmission) != 0; };

    // Strategy A: connect a vertex to the chain. `value` holds the vertex term per channel
    // (BSDF eval with its cosine, or the phase function), `depth` the distance to the exit
    // side, `p_vertex` the density with which the vertex would have sampled -u_j.
    auto connect = [&](int j, const double *value, double depth, double p_vertex) {
        // Without nee, A is kept only through a delta chain (B cannot count those paths).
        if (!wk.ok[j] || (!nee && !wk.delta[j])) return;
        double wA = wk.delta[j] ? 1.0 : power_heuristic(wk.pdf[j], p_vertex);
        if (!(wA > 0)) return;
        transmittance(j, depth / std::abs(wk.u[j].z), tr);
        for (int c = 0; c < C; ++c)
            contrib[c] += beta[c] * value[c] * tr[c] * wk.a[j * C + c] * wk.B[j * C + c] * wA;
        // In the delta region (wA is 1 there): the same departure, back by delta
        // reflections before it leaves.
        if (wk.region[j])
            for (int c = 0; c < C; ++c) contrib[c] += beta[c] * value[c] * tr[c] * wk.up_extra[j * C + c];
    };
    // Delta-chain connection away from the exit (a scattering vertex at `depth` below the
    // exit side of region slab j): along mirror(-u_j) to N_j, then delta events only.
    auto connect_away = [&](int j, const Vec3 &w_in, double depth) {
        if (!wk.region[j]) return;
        const Vec3 &u = wk.u[j];
        const double p = slabs_[j].phase.eval(w_in, Vec3{-u.x, -u.y, u.z});
        if (!(p > 0)) return;
        transmittance(j, (slabs_[j].thickness - depth) / std::abs(u.z), tr);
        for (int c = 0; c < C; ++c) contrib[c] += beta[c] * p * tr[c] * wk.down[j * C + c];
    };
    // Strategy B: the walk heads along w toward slab j's rough exit-side boundary, `depth`
    // below it. `p_sampled` is the density of w at its vertex; `mis` false when no strategy
    // A competes (the vertex was a delta event, or w arrived through delta transmissions).
    auto exit_through = [&](int j, const Vec3 &w, double depth, double p_sampled, bool mis) {
        if (!wk.reached[j] || !rough_exit(j)) return;
        const BSDF &X = *boundaries_[xb(j)];
        const Vec3 &L = wk.L[j];
        X.eval(-w, L, kTransmission, q, tmp);
        if (!any_positive(tmp, C)) return;
        double wB = 1.0;
        if (nee && mis) wB = power_heuristic(p_sampled, X.pdf(L, -w, kTransmission, q));
        transmittance(j, depth / std::abs(w.z), tr);
        double inv_cos = 1.0 / std::abs(L.z);
        for (int c = 0; c < C; ++c) contrib[c] += beta[c] * tr[c] * tmp[c] * inv_cos * wk.B[j * C + c] * wB;
    };
    // `covered`: while the walk heads toward the exit, whether the straight continuation
    // from its last non-delta vertex (through delta exit-side boundaries) is counted by
    // that vertex's connections. False after a delta vertex: then strategy B is tried at
    // every exit-side boundary the walk reaches through delta transmissions, the paths'
    // only strategy (Guo et al.'s estimator needs a non-delta vertex to connect from).
    bool covered = true;

    // Entering the stack.
    int j = entry == 0 ? 0 : K - 1;
    const BSDF &E = *boundaries_[entry];
    if (entry != exit && !(E.lobes() & kDeltaTransmission) && wk.ok[j]) {
        if (entry_scale > 0) {
            E.eval(wi, -wk.u[j], kTransmission, q, tmp);
            for (int c = 0; c < C; ++c) tmp[c] *= entry_scale;
            connect(j, tmp, slabs_[j].thickness, E.pdf(wi, -wk.u[j], kTransmission, q));
        }
    }
    BSDFSample s = sample_boundary(E, wi, kTransmission, q, rng, wgt);
    if (!s.lobe) return false;
    for (int c = 0; c < C; ++c) beta[c] = wgt[c];
    // Roulette compares the throughput with its value after entering, so a small entry
    // factor (grazing Fresnel transmission) does not make every walk die early.
    double beta_entry = 0;
    for (int c = 0; c < C; ++c) beta_entry = std::max(beta_entry, beta[c]);
    if (!(beta_entry > 0)) return false;
    Vec3 w = s.wo;
    double zx = entry == exit ? 0.0 : slabs_[j].thickness; // depth below the exit side
    if (entry != exit) {
        covered = !(s.lobe & kDelta);
        exit_through(j, w, zx, s.pdf, covered);
    }

    for (int depth = 0; depth < options_.max_depth; ++depth) {
        const Slab &S = slabs_[j];
        const bool up = toward_exit(w);
        const double cz = std::abs(w.z);
        if (!(cz > 1e-9)) return false;
        const double room = up ? zx : S.thickness - zx;

        const double t = (v2 && min_extinction_[j])
                             ? fly_min_extinction(std::size_t(j), room, cz, rng, beta, wk.fly_tr)
                             : fly(S, room, cz, rng, beta, wk.fly_tr);
        if (t >= 0) { // scattering event at depth zx (measured from the exit side)
            zx += up ? -t * cz : t * cz;
            double to_exit_pdf = wk.ok[j] ? S.phase.eval(w, -wk.u[j]) : 0.0;
            for (int c = 0; c < C; ++c) tmp[c] = to_exit_pdf;
            connect(j, tmp, zx, to_exit_pdf);
            connect_away(j, w, zx);
            Vec3 w2 = sample_phase(S.phase, w, rng);
            covered = true;
            if (toward_exit(w2)) exit_through(j, w2, zx, S.phase.eval(w, w2), true);
            w = w2;
            goto roulette;
        }
        {
            const int b = up ? xb(j) : (exit == 0 ? j + 1 : j);
            const BSDF &V = *boundaries_[b];
            const bool outer = b == 0 || b == K;
            if (up) {
                // Exit-side boundary: at the stack's exit only reflect (leaving is counted
                // by the connections); an interior one may also pass on toward the exit.
                uint32_t mask = b == exit ? uint32_t(kReflection) : uint32_t(kAll);
                s = sample_boundary(V, -w, mask, q, rng, wgt);
                if (!s.lobe) return false;
                for (int c = 0; c < C; ++c) beta[c] *= wgt[c];
                w = s.wo;
                if (s.lobe & kTransmission) {
                    j += exit == 0 ? -1 : 1;
                    zx = slabs_[j].thickness;
                    if (!(s.lobe & kDelta)) {
                        covered = true; // strategy B at this boundary counted the crossing
                    } else if (!covered) {
                        exit_through(j, w, zx, 0.0, false);
                    }
                } else {
                    zx = 0.0;
                }
            } else {
                // Non-exit side: a vertex that may be the last one before leaving.
                uint32_t mask = outer ? uint32_t(kReflection) : uint32_t(kAll);
                zx = S.thickness;
                if (wk.ok[j] && (V.lobes() & (kDiffuseReflection | kGlossyReflection))) {
                    V.eval(-w, -wk.u[j], kReflection, q, tmp);
                    if (any_positive(tmp, C)) connect(j, tmp, zx, V.pdf(-w, -wk.u[j], mask, q));
                }
                s = sample_boundary(V, -w, mask, q, rng, wgt);
                if (!s.lobe) return false;
                for (int c = 0; c < C; ++c) beta[c] *= wgt[c];
                w = s.wo;
                if (s.lobe & kReflection) {
                    covered = !(s.lobe & kDelta);
                    exit_through(j, w, zx, s.pdf, covered);
                } else {
                    j += exit == 0 ? 1 : -1;
                    zx = 0.0;
                }
            }
        }
    roulette:
        if (depth >= kRouletteDepth) {
            double m = 0;
            for (int c = 0; c < C; ++c) m = std::max(m, beta[c] / beta_entry);
            if (!(m > 0)) return false;
            if (m < 1) {
                const double u_survive = rng.uniform();
                if (u_survive >= m) return false;
                for (int c = 0; c < C; ++c) beta[c] /= m;
            }
        }
    }
    return true; // cut by the depth cap
}

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
    const int entry = wi.z > 0 ? 0 : K, exit = wo.z > 0 ? 0 : K;

    // Workspace layout: the walk, then x, mean, m2 (R each) and direct (C).
    const std::size_t wn = walk_doubles();
    double *extra = ws.doubles(wn + 3 * R + C) + wn;
    Walk wk = bind_walk(ws, 0);
    double *x = extra, *mean = extra + R, *m2 = extra + 2 * R, *direct = extra + 3 * R;
    std::fill(mean, mean + 2 * R, 0.0);

    PCG32 rng(hash_directions(req.seed, wi, wo));
    std::uint64_t nonfinite = 0, capped = 0;
    const double cos_o = std::abs(wo.z);
    // pfmc: one walk per chain, each walk one sample of the mean. pfmc2: groups of up to
    // kWalksPerChain walks (1 where the chain is random: a non-delta boundary on its way)
    // share a chain (and its entry connection, added once at the group's weight); a group's
    // mean is one sample (its walks are correlated).
    // At least two groups whenever samples >= 2, so that the standard error is estimated.
    const int per_chain = std::max(1, std::min(walks_per_chain_[exit == 0 ? 0 : 1], samples / 2));
    const int groups = (samples + per_chain - 1) / per_chain;
    for (int n = 1; n <= groups; ++n) {
        std::fill(wk.contrib, wk.contrib + C, 0.0);
        build_chain(wo, exit, q, rng, wk);
        const int walks = std::min(per_chain, samples - (n - 1) * per_chain);
        for (int k = 0; k < walks; ++k)
            if (one_walk(wi, entry, exit, q, rng, wk, k == 0 ? double(walks) : 0.0)) ++capped;
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
    if (include_direct && entry == exit) boundaries_[entry]->eval(wi, wo, kReflection, q, direct);
    project_rows(req.P, R, C, direct, x);
    for (int r = 0; r < R; ++r) {
        out[r] = mean[r] + x[r];
        err[r] = groups > 1 ? std::sqrt(m2[r] / (double(groups) * (groups - 1))) : 0.0;
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

ScatteredPart::ScatteredPart(std::shared_ptr<const LayeredBSDF> model)
    : BSDF(model ? model->wavelengths() : std::vector<double>{}), model_(std::move(model)) {
    if (!model_) throw std::invalid_argument("ScatteredPart needs a layered model");
}

void ScatteredPart::eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const {
    ThreadWorkspace walks, errors;
    EstimateRequest req{model_->options().samples, model_->options().seed};
    estimate(wi, wo, lobes, q, req, walks.get(), out, errors.get().doubles(channels()));
}

std::shared_ptr<const BSDF> LayeredBSDF::with_film_lookup(double thickness_nm, FilmLookupStats &stats) const {
    std::vector<std::shared_ptr<const BSDF>> boundaries = boundaries_;
    bool changed = false;
    for (auto &b : boundaries)
        if (auto fast = b->with_film_lookup(thickness_nm, stats)) {
            b = std::move(fast);
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

// The density with which sample() returns wo, per draw (it integrates to the share of
// draws that return a direction; the rest end inside the stack). Two parts:
//  - the entry boundary's own reflection, drawn by sample()'s first event: exact;
//  - the walk's exits through the outer boundary X on wo's side, if X transmits through a
//    non-delta lobe: a last-event estimate. The walk is sample()'s own (same events, same
//    roulette); every time it arrives at X heading out it adds X's density of
//    transmitting toward wo, then continues as sample() does (the arrival ends the walk if
//    X transmits). The expected sum over arrivals is the exit density at wo, so the
//    estimate is unbiased but for one defensive pseudo-walk (below: O(1/n) of the mass)
//    that keeps it positive; it is seeded from (seed, wi, wo), so pdf() is a fixed function
//    of the pair, which multiple importance sampling needs for its weights to sum to 1.
//  - a delta X (smooth top): the exits' density is that of the last non-delta vertex's
//    sample refracted through X; not estimated here: the share of draws that leave
//    through X (estimated by the same walks, smoothed so it is never 0) spread as a
//    cosine lobe over the directions X can refract into (see the end of the function).
// pbrt-v4's LayeredBxDF::PDF instead estimates the two-interface TRT density without the
// medium, mixed with 10 % uniform; it does not integrate to the sampler's share.
double LayeredBSDF::pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const {
    if (!usable_direction(wi) || !usable_direction(wo)) return 0.0;
    const bool base_transmits = boundaries_.back()->lobes() & kTransmission;
    if ((wi.z < 0 || wo.z < 0) && !base_transmits) return 0.0;
    const bool reflect = wi.z * wo.z > 0;
    if (!(lobes & (reflect ? kGlossyReflection : kGlossyTransmission))) return 0.0;
    const int K = static_cast<int>(slabs_.size()), C = channels();
    const BSDF &E = *boundaries_[wi.z > 0 ? 0 : K];
    const int n = options_.pdf_samples;
    if (n < 1) return approximate_pdf(wi, wo, reflect, q);
    double p = reflect ? E.pdf(wi, wo, kAll, q) : 0.0;
    const int x = wo.z > 0 ? 0 : K;
    ThreadWorkspace lease;
    double *buf = lease.get().doubles(3 * C);
    PCG32 rng(hash_directions(options_.seed ^ 0x9df5a1e3c4b2d187ull, wi, wo));
    ExitDensity density{wo, x, (boundaries_[x]->lobes() & kNonDeltaTransmission) != 0, 0.0};
    int left_through_x = 0;
    for (int i = 0; i < n; ++i) {
        const double u1 = rng.uniform();
        const double u2x = rng.uniform();
        const double u2y = rng.uniform();
        BSDFSample s = E.sample(wi, u1, u2x, u2y, kAll, q, buf + C);
        if (!s.lobe || (s.lobe & kReflection)) continue;
        BSDFSample out = walk(wi, s, q, rng, buf, &density);
        if (out.lobe && !(out.lobe & kDelta) && (out.wo.z > 0) == (wo.z > 0)) ++left_through_x;
    }
    // Rough X: the arrivals' density, with one defensive pseudo-walk whose exit density is
    // a cosine lobe carrying the smoothed share of draws that left through X. Without it the
    // estimate was 0 wherever none of the n walks arrived (36 % of a rough transmissive
    // stack's own samples at n = 1), and MIS then gave the sample no weight. Its mass bias,
    // ((k + 1) / (n + 2) - k / n) / (n + 1) of the share, vanishes as 1 / n.
    const double share = (left_through_x + 1.0) / (n + 2.0);
    if (density.rough) return p + (density.sum + share * std::abs(wo.z) * kInvPi) / (n + 1.0);
    // Delta X: the share of draws leaving through X spread as a cosine lobe over the
    // directions X can refract into. The share is smoothed, (k + 1) / (n + 2), so that a
    // direction sample() returns never reads pdf 0 (with n = 1 the raw k / n was 0 for
    // ~64 % of a smooth top's own samples, and a renderer that drops pdf-0 samples, or an
    // emitter light sampling cannot reach, loses them). The lobe is 0 where X cannot
    // refract toward wo (an outside denser than the slab, beyond the critical angle:
    // sample() never goes there) and normalised over the rest.
    const BSDF &X = *boundaries_[x];
    double *t = buf + C;
    if (!(X.sample(wo, 0.5, 0.5, 0.5, kDeltaTransmission, q, t).lobe & kDeltaTransmission)) return p;
    const BSDFSample normal =
        X.sample(Vec3{0.0, 0.0, wo.z > 0 ? 1.0 : -1.0}, 0.5, 0.5, 0.5, kDeltaTransmission, q, t);
    // sin^2 of the critical angle on wo's side (1: no critical angle)
    const double cone = normal.lobe ? std::min(1.0, normal.eta * normal.eta) : 1.0;
    return p + share * std::abs(wo.z) * kInvPi / cone;
}

// Estimator version 4's pdf (pdf_samples = 0, kept for comparisons): the entry's glossy
// lobe weighted by its reflectance, the rest spread as a cosine lobe over the exit
// hemisphere(s). It integrates to 1, while the sampler returns a direction for only a
// share of its draws, and its shape differs from the walk's exits at grazing angles.
double LayeredBSDF::approximate_pdf(const Vec3 &wi, const Vec3 &wo, bool reflect, const Query &q) const {
    const bool base_transmits = boundaries_.back()->lobes() & kTransmission;
    const BSDF &E = *boundaries_[wi.z > 0 ? 0 : boundaries_.size() - 1];
    const int C = channels();
    ThreadWorkspace lease;
    double *w = lease.get().doubles(C);
    E.sample(wi, 0.5, 0.5, 0.5, kReflection, q, w);
    double r = std::clamp(channel_mean(w, C), 0.0, 1.0);
    double p = reflect ? r * E.pdf(wi, wo, kReflection, q) : 0.0;
    double spread = (1.0 - r) * std::abs(wo.z) * kInvPi;
    p += base_transmits ? 0.5 * spread : spread;
    return p;
}

BSDFSample LayeredBSDF::sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                               const Query &q, double *weight) const {
    zero(weight);
    const int C = channels(), K = static_cast<int>(slabs_.size());
    if (!usable_direction(wi)) return {};
    const bool base_transmits = boundaries_.back()->lobes() & kTransmission;
    if (wi.z < 0 && !base_transmits) return {};
    const int entry = wi.z > 0 ? 0 : K;
    PCG32 rng(hash_directions(options_.seed, wi, Vec3{u1, u2x, u2y}));
    ThreadWorkspace lease;
    double *buf = lease.get().doubles(3 * C);
    double *w = buf + C;

    BSDFSample s = boundaries_[entry]->sample(wi, u1, u2x, u2y, kAll, q, w);
    if (!s.lobe) return {};
    if (s.lobe & kReflection) { // the top's own reflection (delta or glossy)
        if (!(s.lobe & lobes)) return {};
        std::copy(w, w + C, weight);
        // A renderer weights this direction by MIS against light sampling with pdf():
        // report that same density (the weight does not depend on it).
        if (!(s.lobe & kDelta)) s.pdf = pdf(wi, s.wo, kAll, q);
        return s;
    }
    BSDFSample out = walk(wi, s, q, rng, buf, nullptr);
    if (!out.lobe || !(out.lobe & lobes)) return {};
    if (!(out.lobe & kDelta)) out.pdf = pdf(wi, out.wo, kAll, q);
    std::copy(buf, buf + C, weight);
    return out;
}

// sample()'s walk after the entry boundary transmitted (`s`: that sample, its weight in
// buf[C..2C)). Returns the exit (weight in buf[0..C)) or nothing when the walk ends
// inside. With `density`, every arrival at boundary density->boundary heading out adds
// that boundary's density of transmitting toward density->wo (pdf()).
BSDFSample LayeredBSDF::walk(const Vec3 &wi, BSDFSample s, const Query &q, PCG32 &rng, double *buf,
                             ExitDensity *density) const {
    const int C = channels(), K = static_cast<int>(slabs_.size());
    double *beta = buf, *w = buf + C, *fly_tr = buf + 2 * C;
    const int entry = wi.z > 0 ? 0 : K;
    std::copy(w, w + C, beta);
    double eta = s.eta; // product of the relative indices crossed so far
    // A path with no non-delta vertex is a delta lobe of the stack (eval has no density
    // for it): it is labelled delta, with the probability of its discrete choices as pdf.
    bool all_delta = (s.lobe & kDelta) != 0;
    double delta_prob = s.pdf;
    const double beta_entry = *std::max_element(beta, beta + C);
    if (!(beta_entry > 0)) return {};
    int j = entry == 0 ? 0 : K - 1;
    Vec3 dir = s.wo;
    double zd = entry == 0 ? 0.0 : slabs_[j].thickness; // depth below the top of slab j
    for (int depth = 0; depth < options_.max_depth; ++depth) {
        if (depth >= kRouletteDepth) { // every event, scattering ones included
            double m = *std::max_element(beta, beta + C) / beta_entry;
            if (!(m > 0)) return {};
            if (m < 1) {
                const double u_survive = rng.uniform();
                if (u_survive >= m) return {};
                for (int c = 0; c < C; ++c) beta[c] /= m;
            }
        }
        const Slab &S = slabs_[j];
        const bool down = dir.z < 0;
        const double cz = std::abs(dir.z);
        if (!(cz > 1e-9)) return {};
        const double room = down ? S.thickness - zd : zd;
        const double t = options_.estimator == kEstimatorPfmc2 && min_extinction_[j]
                             ? fly_min_extinction(std::size_t(j), room, cz, rng, beta, fly_tr)
                             : fly(S, room, cz, rng, beta, fly_tr);
        if (t >= 0) {
            zd += down ? t * cz : -t * cz;
            dir = sample_phase(S.phase, dir, rng);
            all_delta = false;
            continue;
        }
        const int b = down ? j + 1 : j;
        if (density && density->rough && b == density->boundary)
            density->sum += boundaries_[b]->pdf(-dir, density->wo, kAll, q);
        s = sample_boundary(*boundaries_[b], -dir, kAll, q, rng, w);
        if (!s.lobe) return {};
        for (int c = 0; c < C; ++c) beta[c] *= w[c];
        dir = s.wo;
        if (s.lobe & kDelta) delta_prob *= s.pdf;
        else all_delta = false;
        if (s.lobe & kTransmission) {
            eta *= s.eta;
            if (b == 0 || b == K) { // left the stack
                BSDFSample out;
                out.wo = dir;
                const bool reflected = wi.z * dir.z > 0;
                if (all_delta) out.lobe = reflected ? kDeltaReflection : kDeltaTransmission;
                else out.lobe = reflected ? kGlossyReflection : kGlossyTransmission;
                out.pdf = all_delta ? delta_prob : 0.0; // non-delta: the caller's pdf()
                out.eta = reflected ? 1.0 : eta;
                return out;
            }
            j += down ? 1 : -1;
            zd = down ? 0.0 : slabs_[j].thickness;
        } else {
            zd = down ? S.thickness : 0.0;
        }
    }
    capped_.fetch_add(1, std::memory_order_relaxed); // cut by the depth cap
    return {};
}

} // namespace bsdflab
