#include "bsdflab/layered.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/frame.h"
#include "bsdflab/sampling.h"
#include "bsdflab/scratch.h"

namespace bsdflab {

namespace {

constexpr int kMaxSlabs = 16;
constexpr int kRouletteDepth = 4;
constexpr uint32_t kSmoothTransmission = kDiffuseTransmission | kGlossyTransmission;

double power_heuristic(double a, double b) {
    a *= a;
    b *= b;
    return a + b > 0 ? a / (a + b) : 0.0;
}

bool any_positive(const double *v, int n) {
    for (int c = 0; c < n; ++c)
        if (v[c] > 0) return true;
    return false;
}

} // namespace

// The light chain from wo: per slab j, the direction u_j leading from the exit side into
// slab j, the light direction L_j just beyond slab j's exit-side boundary, the last-step
// factor a_j = f_adjoint / pdf and the factor B_j of everything beyond that boundary.
struct LayeredBSDF::Chain {
    bool reached[kMaxSlabs] = {}; // L_j and B_j known (strategy B possible)
    bool ok[kMaxSlabs] = {};      // u_j sampled too (strategy A possible)
    bool delta[kMaxSlabs] = {};
    double pdf[kMaxSlabs] = {};
    Vec3 u[kMaxSlabs], L[kMaxSlabs];
    std::vector<double> a, B; // [slab * C + c]
};

// Per-walk buffers, allocated once per eval() call.
struct LayeredBSDF::Walk {
    std::vector<double> beta, tmp, tr, w;
};

LayeredBSDF::LayeredBSDF(std::vector<double> wavelengths,
                         std::vector<std::shared_ptr<const BSDF>> boundaries, std::vector<Slab> slabs,
                         LayeredOptions options)
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
}

uint32_t LayeredBSDF::lobes() const {
    uint32_t l = kGlossyReflection | (boundaries_.front()->lobes() & kDeltaReflection);
    if (boundaries_.back()->lobes() & kTransmission) l |= kGlossyTransmission;
    return l;
}

double LayeredBSDF::fly(const Slab &S, double room, double cz, PCG32 &rng, double *beta) const {
    const int C = channels();
    const double length = room / cz;
    if (!(S.sigma_s > 0)) { // pure absorption: attenuate deterministically
        for (int c = 0; c < C; ++c) beta[c] *= std::exp(-S.sigma_a[c] * length);
        return -1.0;
    }
    // Spectral MIS (one-sample, balance heuristic over channels): draw the flight with a
    // randomly chosen channel's extinction; weight each channel by its true density over
    // the channel-average density. Weights stay below C whatever the spectral contrast.
    double *tr = scratch(2, C);
    const int k = std::min(C - 1, static_cast<int>(rng.uniform() * C));
    const double sk = S.sigma_a[k] + S.sigma_s;
    const double t = -std::log(1.0 - rng.uniform()) / sk;
    const bool collide = t < length;
    const double d = collide ? t : length;
    double avg = 0;
    for (int c = 0; c < C; ++c) {
        const double st = S.sigma_a[c] + S.sigma_s;
        tr[c] = std::exp(-st * d);
        avg += collide ? st * tr[c] : tr[c];
    }
    avg /= C;
    if (!(avg > 0)) { // every channel extinct: the walk carries nothing
        for (int c = 0; c < C; ++c) beta[c] = 0.0;
        return -1.0;
    }
    for (int c = 0; c < C; ++c) beta[c] *= (collide ? S.sigma_s : 1.0) * tr[c] / avg;
    return collide ? t : -1.0;
}

void LayeredBSDF::transmittance(int j, double distance, double *tr) const {
    const Slab &s = slabs_[j];
    for (int c = 0; c < channels(); ++c) tr[c] = std::exp(-(s.sigma_a[c] + s.sigma_s) * distance);
}

bool LayeredBSDF::build_chain(const Vec3 &wo, int exit, const Query &q, PCG32 &rng, Chain &ch) const {
    const int K = static_cast<int>(slabs_.size()), C = channels();
    ch.a.assign(K * C, 0.0);
    ch.B.assign(K * C, 0.0);
    std::vector<double> beyond(C, 1.0), w(C), tr(C);
    Vec3 L = wo;
    for (int step = 0; step < K; ++step) {
        int j = exit == 0 ? step : K - 1 - step;
        int xb = exit == 0 ? j : j + 1;
        ch.reached[j] = true;
        ch.L[j] = L;
        for (int c = 0; c < C; ++c) ch.B[j * C + c] = beyond[c];
        double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
        BSDFSample s = boundaries_[xb]->sample(L, u1, u2, u3, kTransmission, q, w.data());
        if (!s.lobe || !any_positive(w.data(), C)) break;
        double cu = std::abs(s.wo.z);
        if (!(cu > 1e-12)) break;
        ch.ok[j] = true;
        ch.delta[j] = s.lobe & kDelta;
        ch.pdf[j] = s.pdf;
        ch.u[j] = s.wo;
        // Radiance-mode weight -> adjoint value f(u, L) / pdf by generalised reciprocity.
        transmittance(j, slabs_[j].thickness / cu, tr.data());
        for (int c = 0; c < C; ++c) {
            ch.a[j * C + c] = w[c] * s.eta * s.eta / cu;
            beyond[c] *= tr[c] * ch.a[j * C + c] * cu;
        }
        L = -s.wo;
    }
    return ch.ok[exit == 0 ? 0 : K - 1];
}

void LayeredBSDF::one_walk(const Vec3 &wi, const Vec3 &wo, int entry, int exit, const Query &q,
                           PCG32 &rng, double *contrib) const {
    (void)wo;
    thread_local Chain ch;
    thread_local Walk wk;
    const int K = static_cast<int>(slabs_.size()), C = channels();
    wk.beta.assign(C, 1.0);
    wk.tmp.resize(C);
    wk.tr.resize(C);
    wk.w.resize(C);
    double *beta = wk.beta.data(), *tmp = wk.tmp.data(), *tr = wk.tr.data(), *wgt = wk.w.data();
    for (int j = 0; j < kMaxSlabs; ++j) ch.ok[j] = ch.reached[j] = false;
    build_chain(wo, exit, q, rng, ch);
    const bool nee = options_.nee;

    auto xb = [&](int j) { return exit == 0 ? j : j + 1; };
    auto toward_exit = [&](const Vec3 &w) { return exit == 0 ? w.z > 0 : w.z < 0; };
    auto rough_exit = [&](int j) { return (boundaries_[xb(j)]->lobes() & kSmoothTransmission) != 0; };

    // Strategy A: connect a vertex to the chain. `value` holds the vertex term per channel
    // (BSDF eval with its cosine, or the phase function), `depth` the distance to the exit
    // side, `p_vertex` the density with which the vertex would have sampled -u_j.
    auto connect = [&](int j, const double *value, double depth, double p_vertex) {
        if (!nee || !ch.ok[j]) return;
        double wA = ch.delta[j] ? 1.0 : power_heuristic(ch.pdf[j], p_vertex);
        if (!(wA > 0)) return;
        transmittance(j, depth / std::abs(ch.u[j].z), tr);
        for (int c = 0; c < C; ++c)
            contrib[c] += beta[c] * value[c] * tr[c] * ch.a[j * C + c] * ch.B[j * C + c] * wA;
    };
    // Strategy B: the walk has just sampled w toward slab j's rough exit-side boundary.
    auto exit_through = [&](int j, const Vec3 &w, double depth, double p_sampled, bool sampled_delta) {
        if (!ch.reached[j] || !rough_exit(j)) return;
        const BSDF &X = *boundaries_[xb(j)];
        const Vec3 &L = ch.L[j];
        X.eval(-w, L, kTransmission, q, tmp);
        if (!any_positive(tmp, C)) return;
        double wB = 1.0;
        if (nee && !sampled_delta) wB = power_heuristic(p_sampled, X.pdf(L, -w, kTransmission, q));
        transmittance(j, depth / std::abs(w.z), tr);
        double inv_cos = 1.0 / std::abs(L.z);
        for (int c = 0; c < C; ++c)
            contrib[c] += beta[c] * tr[c] * tmp[c] * inv_cos * ch.B[j * C + c] * wB;
    };

    // Entering the stack.
    int j = entry == 0 ? 0 : K - 1;
    const BSDF &E = *boundaries_[entry];
    if (entry != exit && !(E.lobes() & kDeltaTransmission) && ch.ok[j]) {
        E.eval(wi, -ch.u[j], kTransmission, q, tmp);
        connect(j, tmp, slabs_[j].thickness, E.pdf(wi, -ch.u[j], kTransmission, q));
    }
    BSDFSample s = E.sample(wi, rng.uniform(), rng.uniform(), rng.uniform(), kTransmission, q, wgt);
    if (!s.lobe) return;
    for (int c = 0; c < C; ++c) beta[c] = wgt[c];
    // Roulette compares the throughput with its value after entering, so a small entry
    // factor (grazing Fresnel transmission) does not make every walk die early.
    double beta_entry = 0;
    for (int c = 0; c < C; ++c) beta_entry = std::max(beta_entry, beta[c]);
    if (!(beta_entry > 0)) return;
    Vec3 w = s.wo;
    double zx = entry == exit ? 0.0 : slabs_[j].thickness; // depth below the exit side
    if (entry != exit) exit_through(j, w, zx, s.pdf, s.lobe & kDelta);

    for (int depth = 0; depth < options_.max_depth; ++depth) {
        const Slab &S = slabs_[j];
        const bool up = toward_exit(w);
        const double cz = std::abs(w.z);
        if (!(cz > 1e-9)) return;
        const double room = up ? zx : S.thickness - zx;

        const double t = fly(S, room, cz, rng, beta);
        if (t >= 0) { // scattering event at depth zx (measured from the exit side)
            zx += up ? -t * cz : t * cz;
            double to_exit_pdf = ch.ok[j] ? S.phase.eval(w, -ch.u[j]) : 0.0;
            for (int c = 0; c < C; ++c) tmp[c] = to_exit_pdf;
            connect(j, tmp, zx, to_exit_pdf);
            Vec3 w2 = S.phase.sample(w, rng.uniform(), rng.uniform());
            if (toward_exit(w2)) exit_through(j, w2, zx, S.phase.eval(w, w2), false);
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
                s = V.sample(-w, rng.uniform(), rng.uniform(), rng.uniform(), mask, q, wgt);
                if (!s.lobe) return;
                for (int c = 0; c < C; ++c) beta[c] *= wgt[c];
                w = s.wo;
                if (s.lobe & kTransmission) {
                    j += exit == 0 ? -1 : 1;
                    zx = slabs_[j].thickness;
                } else {
                    zx = 0.0;
                }
            } else {
                // Non-exit side: a vertex that may be the last one before leaving.
                uint32_t mask = outer ? uint32_t(kReflection) : uint32_t(kAll);
                zx = S.thickness;
                if (ch.ok[j] && (V.lobes() & (kDiffuseReflection | kGlossyReflection))) {
                    V.eval(-w, -ch.u[j], kReflection, q, tmp);
                    if (any_positive(tmp, C)) connect(j, tmp, zx, V.pdf(-w, -ch.u[j], mask, q));
                }
                s = V.sample(-w, rng.uniform(), rng.uniform(), rng.uniform(), mask, q, wgt);
                if (!s.lobe) return;
                for (int c = 0; c < C; ++c) beta[c] *= wgt[c];
                w = s.wo;
                if (s.lobe & kReflection) {
                    exit_through(j, w, zx, s.pdf, s.lobe & kDelta);
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
            if (!(m > 0)) return;
            if (m < 1) {
                if (rng.uniform() >= m) return;
                for (int c = 0; c < C; ++c) beta[c] /= m;
            }
        }
    }
}

void LayeredBSDF::eval_projected(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                                 int samples, uint64_t seed, const double *P, int rows,
                                 bool include_direct, double *out, double *err) const {
    const int C = channels(), K = static_cast<int>(slabs_.size());
    const int R = P ? rows : C;
    for (int r = 0; r < R; ++r) out[r] = err[r] = 0.0;
    if (!usable_direction(wi) || !usable_direction(wo) || samples < 1) return;
    const bool base_transmits = boundaries_.back()->lobes() & kTransmission;
    if (wi.z < 0 && !base_transmits) return;
    if (wo.z < 0 && !base_transmits) return;
    const bool reflect = wi.z * wo.z > 0;
    if (!(lobes & (reflect ? kReflection : kTransmission) & ~kDelta)) return;
    const int entry = wi.z > 0 ? 0 : K, exit = wo.z > 0 ? 0 : K;

    // Projects a per-channel vector v into rows (identity without P).
    auto project = [&](const double *v, double *dst) {
        if (!P) { std::copy(v, v + C, dst); return; }
        for (int r = 0; r < R; ++r) {
            double acc = 0;
            for (int c = 0; c < C; ++c) acc += P[r * C + c] * v[c];
            dst[r] = acc;
        }
    };
    PCG32 rng(hash_directions(seed, wi, wo));
    std::vector<double> contrib(C), x(R), mean(R, 0.0), m2(R, 0.0);
    const double cos_o = std::abs(wo.z);
    for (int n = 1; n <= samples; ++n) {
        std::fill(contrib.begin(), contrib.end(), 0.0);
        one_walk(wi, wo, entry, exit, q, rng, contrib.data());
        for (int c = 0; c < C; ++c) contrib[c] = std::isfinite(contrib[c]) ? contrib[c] * cos_o : 0.0;
        project(contrib.data(), x.data());
        for (int r = 0; r < R; ++r) { // Welford: running mean and sum of squared deviations
            double d = x[r] - mean[r];
            mean[r] += d / n;
            m2[r] += d * (x[r] - mean[r]);
        }
    }
    // The entry boundary's own (non-delta) reflection is known exactly.
    std::vector<double> direct(C, 0.0), direct_p(R, 0.0);
    if (include_direct && entry == exit) boundaries_[entry]->eval(wi, wo, kReflection, q, direct.data());
    project(direct.data(), direct_p.data());
    for (int r = 0; r < R; ++r) {
        out[r] = mean[r] + direct_p[r];
        err[r] = samples > 1 ? std::sqrt(m2[r] / (double(samples) * (samples - 1))) : 0.0;
    }
}

void LayeredBSDF::eval_with_error(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                                  int samples, uint64_t seed, double *out, double *err) const {
    eval_projected(wi, wo, lobes, q, samples, seed, nullptr, 0, true, out, err);
}

void LayeredBSDF::eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                       double *out) const {
    std::vector<double> err(channels());
    eval_with_error(wi, wo, lobes, q, options_.samples, options_.seed, out, err.data());
}

void LayeredBSDF::delta_reflectance(const Vec3 &wi, const Query &q, double *out) const {
    zero(out);
    if (!usable_direction(wi) || wi.z <= 0) return;
    boundaries_.front()->sample(wi, 0.5, 0.5, 0.5, kDeltaReflection, q, out);
}

double LayeredBSDF::pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const {
    // A deterministic approximation for MIS (sample() is a random walk whose exact density
    // is not available): the top's own glossy lobe weighted by its reflectance, the rest
    // spread as a cosine lobe over the exit hemisphere(s).
    if (!usable_direction(wi) || !usable_direction(wo)) return 0.0;
    const bool base_transmits = boundaries_.back()->lobes() & kTransmission;
    if ((wi.z < 0 || wo.z < 0) && !base_transmits) return 0.0;
    const bool reflect = wi.z * wo.z > 0;
    if (!(lobes & (reflect ? kReflection : kTransmission) & ~kDelta)) return 0.0;
    const BSDF &E = *boundaries_[wi.z > 0 ? 0 : boundaries_.size() - 1];
    const int C = channels();
    std::vector<double> w(C);
    E.sample(wi, 0.5, 0.5, 0.5, kReflection, q, w.data());
    double r = std::clamp(channel_mean(w.data(), C), 0.0, 1.0);
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
    std::vector<double> beta(C), w(C);

    BSDFSample s = boundaries_[entry]->sample(wi, u1, u2x, u2y, kAll, q, w.data());
    if (!s.lobe) return {};
    if (s.lobe & kReflection) { // the top's own reflection (delta or glossy)
        if (!(s.lobe & lobes)) return {};
        std::copy(w.begin(), w.end(), weight);
        // A renderer weights this direction by MIS against light sampling with pdf():
        // report that same density (the weight does not depend on it).
        if (!(s.lobe & kDelta)) s.pdf = pdf(wi, s.wo, kAll, q);
        return s;
    }
    beta = w;
    const double beta_entry = *std::max_element(beta.begin(), beta.end());
    if (!(beta_entry > 0)) return {};
    int j = entry == 0 ? 0 : K - 1;
    Vec3 dir = s.wo;
    double zd = entry == 0 ? 0.0 : slabs_[j].thickness; // depth below the top of slab j
    for (int depth = 0; depth < options_.max_depth; ++depth) {
        if (depth >= kRouletteDepth) { // every event, scattering ones included
            double m = *std::max_element(beta.begin(), beta.end()) / beta_entry;
            if (!(m > 0)) return {};
            if (m < 1) {
                if (rng.uniform() >= m) return {};
                for (double &v : beta) v /= m;
            }
        }
        const Slab &S = slabs_[j];
        const bool down = dir.z < 0;
        const double cz = std::abs(dir.z);
        if (!(cz > 1e-9)) return {};
        const double room = down ? S.thickness - zd : zd;
        const double t = fly(S, room, cz, rng, beta.data());
        if (t >= 0) {
            zd += down ? t * cz : -t * cz;
            dir = S.phase.sample(dir, rng.uniform(), rng.uniform());
            continue;
        }
        const int b = down ? j + 1 : j;
        s = boundaries_[b]->sample(-dir, rng.uniform(), rng.uniform(), rng.uniform(), kAll, q, w.data());
        if (!s.lobe) return {};
        for (int c = 0; c < C; ++c) beta[c] *= w[c];
        dir = s.wo;
        if (s.lobe & kTransmission) {
            if (b == 0 || b == K) { // left the stack
                BSDFSample out;
                out.wo = dir;
                out.lobe = wi.z * dir.z > 0 ? kGlossyReflection : kGlossyTransmission;
                if (!(out.lobe & lobes)) return {};
                out.pdf = pdf(wi, dir, kAll, q);
                std::copy(beta.begin(), beta.end(), weight);
                return out;
            }
            j += down ? 1 : -1;
            zd = down ? 0.0 : slabs_[j].thickness;
        } else {
            zd = down ? S.thickness : 0.0;
        }
    }
    return {};
}

} // namespace bsdflab
