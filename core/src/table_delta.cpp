// The stack's delta lobes by 1-D adding (derivation: table_delta.h).
#include "bsdflab/table_delta.h"
#include <cmath>
#include <stdexcept>
#include "bsdflab/frame.h"

namespace bsdflab {

namespace {
Vec3 mirror(const Vec3 &v) { return {v.x, v.y, -v.z}; }

// The weight of boundary b's masked delta sample of light arriving along -w (w the direction
// toward the light, as BSDF::sample takes it); false (weights 0) when it has none.
bool delta_sample(const BSDF &b, const Vec3 &w, uint32_t mask, const Query &q, double *weight,
                  BSDFSample &s) {
    s = b.sample(w, 0.5, 0.5, 0.5, mask, q, weight);
    if (s.lobe & mask) return true;
    for (int c = 0; c < b.channels(); ++c) weight[c] = 0.0;
    return false;
}
} // namespace

TableDeltaStack::TableDeltaStack(std::vector<std::shared_ptr<const BSDF>> boundaries,
                                 std::vector<double> thickness_um, std::vector<std::vector<double>> sigma_t)
    : boundaries_(std::move(boundaries)), thickness_(std::move(thickness_um)), sigma_t_(std::move(sigma_t)) {
    if (boundaries_.size() < 2 || thickness_.size() + 1 != boundaries_.size() ||
        sigma_t_.size() != thickness_.size())
        throw std::invalid_argument("a delta stack needs K + 1 boundaries and K slabs (K >= 1)");
    C_ = boundaries_.front() ? boundaries_.front()->channels() : 0;
    transmits_ = true;
    for (const auto &b : boundaries_) {
        if (!b || b->channels() != C_)
            throw std::invalid_argument("the boundaries must share their channels");
        transmits_ = transmits_ && (b->lobes() & kDeltaTransmission);
    }
    const std::size_t K = thickness_.size();
    bool below_top = false, above_base = false; // a delta reflection under the top, over the base
    for (std::size_t b = 1; b <= K; ++b)
        below_top = below_top || (boundaries_[b]->lobes() & kDeltaReflection);
    for (std::size_t b = 0; b < K; ++b)
        above_base = above_base || (boundaries_[b]->lobes() & kDeltaReflection);
    extends_ = transmits_ || ((boundaries_.front()->lobes() & kDeltaTransmission) && below_top) ||
               ((boundaries_.back()->lobes() & kDeltaTransmission) && above_base);
    for (std::size_t j = 0; j < thickness_.size(); ++j) {
        if (!(thickness_[j] >= 0) || !std::isfinite(thickness_[j]) ||
            static_cast<int>(sigma_t_[j].size()) != C_)
            throw std::invalid_argument(
                "each slab needs a finite thickness >= 0 and one sigma_t per channel");
        // A negative extinction would amplify (T > 1 through a glass plate) and NaN would
        // silently drop the transmission: both are refused, as the Python Slab does.
        for (double s : sigma_t_[j])
            if (!(s >= 0) || !std::isfinite(s))
                throw std::invalid_argument("each slab's sigma_t must be finite and >= 0 (1/um)");
    }
}

bool TableDeltaStack::solve(const Vec3 &wi, const Query &q, double *R, double *T, Vec3 &wt,
                            double &eta) const {
    const int C = C_, K = static_cast<int>(thickness_.size());
    for (int c = 0; c < C; ++c) R[c] = T[c] = 0.0;
    eta = 1.0;
    if (!usable_direction(wi) || wi.z == 0) return false;
    const bool from_above = wi.z > 0;
    auto index = [&](int i) { return from_above ? i : K - i; }; // boundary i's in the stack (0 the top)
    auto boundary = [&](int i) -> const BSDF & { return *boundaries_[std::size_t(index(i))]; };
    auto slab = [&](int i) { return from_above ? i : K - 1 - i; }; // the slab after boundary i
    // Per boundary i (entry order): r, t, s, u (table_delta.h), and the slab after it: a.
    thread_local std::vector<double> buf;
    buf.resize(std::size_t(5) * (K + 1) * C);
    double *r = buf.data(), *t = r + (K + 1) * C, *s = t + (K + 1) * C, *u = s + (K + 1) * C,
           *a = u + (K + 1) * C;
    int reached = 0;      // boundaries the inward beam reaches (the rest: R = T = 0)
    bool through = false; // it leaves through the last boundary
    Vec3 v = -wi;
    BSDFSample smp;
    for (int i = 0; i <= K; ++i) {
        const BSDF &b = boundary(i);
        const Query &qb = boundary_query(q, index(i)); // the query's film is the top's alone
        reached = i + 1;
        delta_sample(b, -v, kDeltaReflection, qb, r + i * C, smp);
        if (!delta_sample(b, -v, kDeltaTransmission, qb, t + i * C, smp)) break;
        const Vec3 in = smp.wo; // v_{i+1}
        eta *= smp.eta;
        if (i == K) {
            wt = in;
            through = true;
            break;
        }
        if (!(std::abs(in.z) > 1e-12)) { // grazing inside: nothing crosses the slab
            for (int c = 0; c < C; ++c) t[i * C + c] = 0.0;
            break;
        }
        delta_sample(b, -mirror(in), kDeltaReflection, qb, s + i * C, smp);
        delta_sample(b, -mirror(in), kDeltaTransmission, qb, u + i * C, smp);
        const int j = slab(i);
        for (int c = 0; c < C; ++c) a[i * C + c] = std::exp(-sigma_t_[j][c] * thickness_[j] / std::abs(in.z));
        v = in;
    }
    // Inward to outward. At the deepest boundary reached, R = r and T = t (t = 0 unless it
    // is the last boundary and transmits).
    const int last = reached - 1;
    for (int c = 0; c < C; ++c) {
        double Rc = r[last * C + c], Tc = through ? t[last * C + c] : 0.0;
        for (int i = last - 1; i >= 0; --i) {
            const double aa = a[i * C + c], round = aa * aa * Rc;
            const double denom = 1.0 - s[i * C + c] * round;
            if (!(denom > 1e-12)) { // a lossless cavity with R = 1 on both sides: no light out
                Rc = r[i * C + c];
                Tc = 0.0;
                continue;
            }
            const double Ri = r[i * C + c] + t[i * C + c] * round * u[i * C + c] / denom;
            Tc = t[i * C + c] * aa * Tc / denom;
            Rc = Ri;
        }
        R[c] = std::isfinite(Rc) ? std::max(Rc, 0.0) : 0.0;
        T[c] = std::isfinite(Tc) ? std::max(Tc, 0.0) : 0.0;
    }
    if (!through) {
        for (int c = 0; c < C; ++c) T[c] = 0.0;
        eta = 1.0;
        return false;
    }
    return true;
}

} // namespace bsdflab
