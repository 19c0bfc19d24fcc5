#include "bsdflab/table_bsdf.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "bsdflab/frame.h"
#include "bsdflab/rng.h"
#include "bsdflab/sampling.h"
#include "bsdflab/scratch.h"

namespace bsdflab {

namespace {
constexpr double kPatchFloor = 1e-3;   // fraction of the mean patch weight every patch gets
constexpr int kDirectAlbedoSamples = 2048;

double wrap_phi(const Vec3 &wi, const Vec3 &wo) {
    double d = std::abs(std::atan2(wo.y, wo.x) - std::atan2(wi.y, wi.x));
    return d > kPi ? 2.0 * kPi - d : d;
}
} // namespace

TabulatedBSDF::TabulatedBSDF(std::vector<double> channel_ids, TableGrid grid, std::vector<float> values,
                             std::vector<double> luminance, std::shared_ptr<const BSDF> direct,
                             std::vector<double> P, double default_thickness, double transmission_eta,
                             std::shared_ptr<const BSDF> direct_below,
                             std::shared_ptr<const TableDeltaStack> delta, std::vector<double> delta_P)
    : BSDF(std::move(channel_ids)), grid_(std::move(grid)), values_(std::move(values)),
      luminance_(std::move(luminance)), direct_(std::move(direct)), direct_below_(std::move(direct_below)),
      delta_(std::move(delta)), delta_P_(std::move(delta_P)), P_(std::move(P)),
      default_thickness_(default_thickness), transmission_eta_(transmission_eta) {
    if (!(transmission_eta_ > 0) || !std::isfinite(transmission_eta_))
        throw std::invalid_argument("transmission_eta must be finite and > 0");
    const int C = channels();
    if (grid_.thickness.empty()) grid_.thickness = {-1.0};
    if (values_.size() != grid_.cells() * C)
        throw std::invalid_argument("table values do not match the grid");
    if (static_cast<int>(luminance_.size()) != C)
        throw std::invalid_argument("luminance needs one weight per channel");
    if (grid_.n_lobes != 1 && grid_.n_lobes != 2 && grid_.n_lobes != 4)
        throw std::invalid_argument("a table has 1, 2 or 4 lobes");
    sides_ = grid_.n_lobes == 4 ? 2 : 1;
    per_side_ = grid_.n_lobes == 1 ? 1 : 2;
    if (direct_below_ && sides_ < 2) throw std::invalid_argument("direct_below needs a two-sided table");
    for (const BSDF *d : {direct_.get(), direct_below_.get()})
        if (d && P_.size() != std::size_t(C) * d->channels())
            throw std::invalid_argument("P must map the direct model's channels to the table's");
    if (delta_ && delta_P_.size() != std::size_t(C) * delta_->channels())
        throw std::invalid_argument("delta_P must map the delta stack's channels to the table's");
    if (direct_ && direct_below_ && direct_->channels() != direct_below_->channels())
        throw std::invalid_argument("the exact parts above and below must share their channels");

    // Sampling CDFs per (side, thickness node, theta_i node).
    const std::size_t NP = patches();
    const int NT = grid_.n_thickness(), NI = grid_.n_theta_i;
    const std::size_t nodes = std::size_t(sides_) * NT * NI;
    cdf_.assign(nodes * (NP + 1), 0.0);
    prob_.assign(nodes * NP, 0.0);
    albedo_.assign(nodes, 0.0);
    std::vector<double> w(NP);
    for (int side = 0; side < sides_; ++side)
        for (int t = 0; t < NT; ++t)
            for (int ti = 0; ti < NI; ++ti) {
                double total = 0;
                for (int l = 0; l < per_side_; ++l)
                    for (int k = 0; k < grid_.n_theta_o; ++k)
                        for (int m = 0; m < grid_.n_phi; ++m) {
                            double ch, cl, pl, ph;
                            patch_bounds(k, m, ch, cl, pl, ph);
                            double solid = (ch - cl) * 2.0 * (ph - pl);
                            const float *v = &values_[grid_.cell_index(2 * side + l, t, ti, k, m) * C];
                            double lum = 0;
                            for (int c = 0; c < C; ++c) lum += luminance_[c] * v[c];
                            double cos_mid = std::cos(grid_.theta_o(k));
                            std::size_t p = (std::size_t(l) * grid_.n_theta_o + k) * grid_.n_phi + m;
                            w[p] = std::max(lum, 0.0) * cos_mid * solid; // f cos dOmega
                            total += w[p];
                        }
                albedo_[node(side, t, ti)] = total;
                double mean = total / NP;
                double floor = mean > 0 ? kPatchFloor * mean : 1.0;
                double *cdf = &cdf_[node(side, t, ti) * (NP + 1)];
                double *prob = &prob_[node(side, t, ti) * NP];
                double acc = 0;
                for (std::size_t p = 0; p < NP; ++p) acc += w[p] + floor;
                cdf[0] = 0;
                for (std::size_t p = 0; p < NP; ++p) {
                    prob[p] = (w[p] + floor) / acc;
                    cdf[p + 1] = cdf[p] + prob[p];
                }
                cdf[NP] = 1.0;
            }

    // Glossy albedo of the direct models per (side, theta_i node) (mixture weights only).
    direct_albedo_.assign(std::size_t(sides_) * NI, 0.0);
    for (int side = 0; side < sides_; ++side) {
        const BSDF *d = this->direct(side);
        if (!d || !(d->lobes() & (kGlossyReflection | kDiffuseReflection))) continue;
        std::vector<double> wd(d->channels());
        Query q;
        q.film_thickness_nm = side == 0 ? default_thickness_ : -1.0;
        PCG32 rng(0x5eed);
        for (int ti = 0; ti < NI; ++ti) {
            double a = grid_.theta_i(ti), sum = 0;
            Vec3 wi{std::sin(a), 0.0, side == 0 ? std::cos(a) : -std::cos(a)};
            for (int n = 0; n < kDirectAlbedoSamples; ++n) {
                // Named draws: argument evaluation order is unspecified (GCC and Clang differ).
                const double u1 = rng.uniform(), u2x = rng.uniform(), u2y = rng.uniform();
                BSDFSample s =
                    d->sample(wi, u1, u2x, u2y, kGlossyReflection | kDiffuseReflection, q, wd.data());
                if (!s.lobe) continue;
                for (int c = 0; c < C; ++c) {
                    double proj = 0;
                    for (int e = 0; e < d->channels(); ++e) proj += P_[c * d->channels() + e] * wd[e];
                    sum += luminance_[c] * proj;
                }
            }
            direct_albedo_[std::size_t(side) * NI + ti] = std::max(sum / kDirectAlbedoSamples, 0.0);
        }
    }
}

uint32_t TabulatedBSDF::lobes() const {
    uint32_t l = kGlossyReflection | (grid_.n_lobes > 1 ? kGlossyTransmission : 0u);
    for (const BSDF *d : {direct_.get(), direct_below_.get()})
        if (d) l |= d->lobes() & kReflection;
    if (delta_) l |= kDeltaReflection | (delta_->transmits() ? kDeltaTransmission : 0u);
    return l;
}

void TabulatedBSDF::patch_bounds(int k, int m, double &cos_hi, double &cos_lo, double &phi_lo,
                                 double &phi_hi) const {
    double step = 0.5 * kPi / grid_.n_theta_o;
    cos_hi = std::cos(k * step);
    cos_lo = std::cos((k + 1) * step);
    double dp = grid_.n_phi > 1 ? kPi / (grid_.n_phi - 1) : kPi;
    phi_lo = std::max(0.0, grid_.phi(m) - 0.5 * dp);
    phi_hi = std::min(kPi, grid_.phi(m) + 0.5 * dp);
}

TabulatedBSDF::Weights TabulatedBSDF::angle_weights(double theta, int n) const {
    double x = theta / (0.5 * kPi / n) - 0.5;
    x = std::clamp(x, 0.0, double(n - 1));
    int i0 = std::min(static_cast<int>(x), n - 1);
    int i1 = std::min(i0 + 1, n - 1);
    return {i0, i1, x - i0};
}

TabulatedBSDF::Weights TabulatedBSDF::phi_weights(double phi) const {
    if (grid_.n_phi < 2) return {0, 0, 0.0};
    double x = std::clamp(phi / (kPi / (grid_.n_phi - 1)), 0.0, double(grid_.n_phi - 1));
    int i0 = std::min(static_cast<int>(x), grid_.n_phi - 1);
    return {i0, std::min(i0 + 1, grid_.n_phi - 1), x - i0};
}

// The exact part must describe the same film as the table part: without a thickness axis
// the table holds the model's own film (-1) and with one node that node's, whatever the
// query asks for; with several nodes the query's thickness (or the model's), clamped to
// the nodes' range as the table part is (thickness_weights): outside the tabulated range
// the whole BSDF is that of the nearest end node, so the two parts never describe
// different films.
Query TabulatedBSDF::direct_query(const Query &q, int side) const {
    Query d = q;
    if (side == 1) { // the base keeps its own film: a query's thickness is the top film's
        d.film_thickness_nm = -1.0;
        return d;
    }
    const auto &T = grid_.thickness;
    if (T.size() == 1) {
        d.film_thickness_nm = T[0];
    } else {
        double t = q.film_thickness_nm >= 0 ? q.film_thickness_nm : default_thickness_;
        if (t >= 0) d.film_thickness_nm = std::clamp(t, T.front(), T.back());
    }
    return d;
}

TabulatedBSDF::Weights TabulatedBSDF::thickness_weights(const Query &q) const {
    const auto &T = grid_.thickness;
    if (T.size() < 2) return {0, 0, 0.0};
    double t = q.film_thickness_nm >= 0 ? q.film_thickness_nm : default_thickness_;
    if (!(t > T.front())) return {0, 0, 0.0};
    if (!(t < T.back())) return {int(T.size()) - 1, int(T.size()) - 1, 0.0};
    int i1 = static_cast<int>(std::upper_bound(T.begin(), T.end(), t) - T.begin());
    int i0 = i1 - 1;
    return {i0, i1, (t - T[i0]) / (T[i1] - T[i0])};
}

// The scattered part of a smooth interface's side carries its Fresnel transmission at
// theta_i, which falls to 0 at grazing: interpolating f itself between theta_i nodes (and
// holding the last node's value up to 90 degrees) gained up to 45 % of the albedo at 89
// degrees and lost 5 % at 80. Interpolating f / entry and multiplying by entry(theta_i)
// is exact at the nodes and follows the Fresnel factor between and beyond them.
double TabulatedBSDF::entry(int side, double theta, const Query &q) const {
    const BSDF *d = direct(side);
    if (!d || !(d->lobes() & kDeltaReflection)) return 1.0;
    const double c = std::cos(theta);
    Vec3 wi{std::sin(theta), 0.0, side == 0 ? c : -c};
    if (!(c > 0)) return 0.0;
    const int C = channels(), D = d->channels();
    double *r = scratch(2, D);
    BSDFSample s = d->sample(wi, 0.5, 0.5, 0.5, kDeltaReflection, direct_query(q, side), r);
    double reflected = 0, all = 0;
    for (int k = 0; k < C; ++k) {
        double acc = 0;
        if (s.lobe)
            for (int e = 0; e < D; ++e) acc += P_[k * D + e] * r[e];
        reflected += luminance_[k] * acc;
        all += luminance_[k];
    }
    return all > 0 ? std::clamp(1.0 - reflected / all, 0.0, 1.0) : 1.0;
}

TabulatedBSDF::Entry TabulatedBSDF::entry_weights(const Vec3 &w, const Weights &wa, int n,
                                                  const Query &q) const {
    const int side = side_of(w);
    if (!direct(side) || !(direct(side)->lobes() & kDeltaReflection)) return {1 - wa.w1, wa.w1};
    const double at = entry(side, std::acos(std::clamp(std::abs(w.z), 0.0, 1.0)), q);
    const double n0 = entry(side, (wa.i0 + 0.5) * (0.5 * kPi / n), q);
    const double n1 = entry(side, (wa.i1 + 0.5) * (0.5 * kPi / n), q);
    // A node where (almost) nothing crosses (total internal reflection) holds f ~ 0 and
    // says nothing of f / entry: the other node's ratio stands for both.
    constexpr double kNone = 1e-6;
    if (!(n0 > kNone) && !(n1 > kNone)) return {0.0, 0.0};
    if (!(n1 > kNone)) return {at / n0, 0.0};
    if (!(n0 > kNone)) return {0.0, at / n1};
    return {(1 - wa.w1) * at / n0, wa.w1 * at / n1};
}

void TabulatedBSDF::table_eval(const Vec3 &wi, const Vec3 &wo, const Query &q, double *out) const {
    const int C = channels();
    for (int c = 0; c < C; ++c) out[c] = 0.0;
    int lobe = table_lobe(wi, wo);
    if (lobe < 0 || lobe >= grid_.n_lobes) return;
    Weights wt = thickness_weights(q);
    Weights wa = angle_weights(std::acos(std::clamp(std::abs(wi.z), 0.0, 1.0)), grid_.n_theta_i);
    Weights wb = angle_weights(std::acos(std::clamp(std::abs(wo.z), 0.0, 1.0)), grid_.n_theta_o);
    Weights wp = phi_weights(wrap_phi(wi, wo));
    // Both ways, so the lookup stays reciprocal: wo leaves through its own side's interface.
    const Entry en = entry_weights(wi, wa, grid_.n_theta_i, q),
                ex = entry_weights(wo, wb, grid_.n_theta_o, q);
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            for (int d = 0; d < 2; ++d)
                for (int e = 0; e < 2; ++e) {
                    double w = (a ? wt.w1 : 1 - wt.w1) * (b ? en.c1 : en.c0) * (d ? ex.c1 : ex.c0) *
                               (e ? wp.w1 : 1 - wp.w1);
                    if (w == 0) continue;
                    std::size_t cell = grid_.cell_index(lobe, a ? wt.i1 : wt.i0, b ? wa.i1 : wa.i0,
                                                        d ? wb.i1 : wb.i0, e ? wp.i1 : wp.i0);
                    const float *v = &values_[cell * C];
                    for (int c = 0; c < C; ++c) out[c] += w * v[c];
                }
    double cos_o = std::abs(wo.z);
    for (int c = 0; c < C; ++c) out[c] *= cos_o;
}

void TabulatedBSDF::direct_eval(const BSDF &direct, const Vec3 &wi, const Vec3 &wo, uint32_t lobes,
                                const Query &q, double *out) const {
    const int C = channels(), D = direct.channels();
    double *v = scratch(3, D); // slots 0-1 belong to the interfaces' own evaluation
    direct.eval(wi, wo, lobes & kReflection, q, v);
    for (int c = 0; c < C; ++c) {
        double acc = 0;
        for (int d = 0; d < D; ++d) acc += P_[c * D + d] * v[d];
        out[c] += acc;
    }
}

void TabulatedBSDF::eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const {
    zero(out);
    if (!usable_direction(wi) || !usable_direction(wo) || wi.z == 0) return;
    const int side = side_of(wi);
    if (side >= sides_) return;
    const bool reflect = wi.z * wo.z > 0;
    uint32_t lobe = reflect ? kGlossyReflection : kGlossyTransmission;
    if (lobes & lobe) table_eval(wi, wo, q, out);
    if (const BSDF *d = direct(side); d && reflect && (lobes & kReflection))
        direct_eval(*d, wi, wo, lobes, direct_query(q, side), out);
}

double TabulatedBSDF::table_albedo(const Vec3 &wi, const Query &q) const {
    Weights wt = thickness_weights(q);
    Weights wa = angle_weights(std::acos(std::clamp(std::abs(wi.z), 0.0, 1.0)), grid_.n_theta_i);
    const int side = side_of(wi);
    auto A = [&](int t, int ti) { return albedo_[node(side, t, ti)]; };
    const Entry en = entry_weights(wi, wa, grid_.n_theta_i, q); // as table_eval interpolates
    const double w0 = en.c0, w1 = en.c1;
    return (1 - wt.w1) * (w0 * A(wt.i0, wa.i0) + w1 * A(wt.i0, wa.i1)) +
           wt.w1 * (w0 * A(wt.i1, wa.i0) + w1 * A(wt.i1, wa.i1));
}

double TabulatedBSDF::table_pdf(const Vec3 &wi, const Vec3 &wo, const Query &q) const {
    int lobe = table_lobe(wi, wo);
    if (lobe < 0 || lobe >= grid_.n_lobes) return 0.0;
    double theta_o = std::acos(std::clamp(std::abs(wo.z), 0.0, 1.0));
    int k = std::min(static_cast<int>(theta_o / (0.5 * kPi / grid_.n_theta_o)), grid_.n_theta_o - 1);
    double phi = wrap_phi(wi, wo);
    double dp = grid_.n_phi > 1 ? kPi / (grid_.n_phi - 1) : kPi;
    int m = grid_.n_phi > 1 ? std::min(static_cast<int>(phi / dp + 0.5), grid_.n_phi - 1) : 0;
    double ch, cl, pl, ph;
    patch_bounds(k, m, ch, cl, pl, ph);
    double area = (ch - cl) * 2.0 * (ph - pl);
    if (!(area > 0)) return 0.0;
    std::size_t p = (std::size_t(lobe % 2) * grid_.n_theta_o + k) * grid_.n_phi + m;
    Weights wt = thickness_weights(q);
    Weights wa = angle_weights(std::acos(std::clamp(std::abs(wi.z), 0.0, 1.0)), grid_.n_theta_i);
    const std::size_t NP = patches();
    const int side = side_of(wi);
    auto P = [&](int t, int ti) { return prob_[node(side, t, ti) * NP + p]; };
    double prob = (1 - wt.w1) * ((1 - wa.w1) * P(wt.i0, wa.i0) + wa.w1 * P(wt.i0, wa.i1)) +
                  wt.w1 * ((1 - wa.w1) * P(wt.i1, wa.i0) + wa.w1 * P(wt.i1, wa.i1));
    return prob / area;
}

void TabulatedBSDF::delta_lobes(const Vec3 &wi, const Query &q, double *R, double *T, Vec3 &wt,
                                double &eta) const {
    const int C = channels();
    for (int c = 0; c < C; ++c) {
        if (R) R[c] = 0.0;
        if (T) T[c] = 0.0;
    }
    eta = 1.0;
    if (delta_) {
        // The stack's delta lobes per channel of the model, then projected (the series is
        // not linear in the Fresnel factors: it is summed before the projection).
        const int D = delta_->channels();
        thread_local std::vector<double> buf;
        buf.resize(std::size_t(2) * D);
        double *r = buf.data(), *t = r + D;
        // The top sees the query's film thickness, the other boundaries their own, as in
        // PFMC's walk (boundary_query).
        if (!delta_->solve(wi, direct_query(q, 0), r, t, wt, eta)) eta = 1.0;
        for (int c = 0; c < C; ++c) {
            double ar = 0, at = 0;
            for (int e = 0; e < D; ++e) {
                ar += delta_P_[c * D + e] * r[e];
                at += delta_P_[c * D + e] * t[e];
            }
            if (R) R[c] = ar;
            if (T) T[c] = at;
        }
        return;
    }
    const int side = side_of(wi);
    const BSDF *d = direct(side);
    if (!d || !(d->lobes() & kDeltaReflection) || !R) return;
    double *r = scratch(2, d->channels());
    BSDFSample s = d->sample(wi, 0.5, 0.5, 0.5, kDeltaReflection, direct_query(q, side), r);
    if (!(s.lobe & kDeltaReflection)) return;
    const int D = d->channels();
    for (int c = 0; c < C; ++c) {
        double acc = 0;
        for (int e = 0; e < D; ++e) acc += P_[c * D + e] * r[e];
        R[c] = acc;
    }
}

TabulatedBSDF::Mixture TabulatedBSDF::mixture(const Vec3 &wi, const Query &q, double *delta_weight,
                                              double *transmit_weight) const {
    const int C = channels();
    Mixture m;
    thread_local std::vector<double> own;
    own.resize(std::size_t(2) * C);
    double *R = delta_weight ? delta_weight : own.data();
    double *T = transmit_weight ? transmit_weight : own.data() + C;
    delta_lobes(wi, q, R, T, m.wt, m.eta);
    double a_delta = 0, a_transmit = 0, a_direct = 0;
    for (int c = 0; c < C; ++c) {
        a_delta += luminance_[c] * R[c];
        a_transmit += luminance_[c] * T[c];
    }
    a_delta = std::max(a_delta, 0.0);
    a_transmit = std::max(a_transmit, 0.0);
    const int side = side_of(wi);
    if (direct(side)) {
        Weights wa = angle_weights(std::acos(std::clamp(std::abs(wi.z), 0.0, 1.0)), grid_.n_theta_i);
        const double *da = &direct_albedo_[std::size_t(side) * grid_.n_theta_i];
        a_direct = (1 - wa.w1) * da[wa.i0] + wa.w1 * da[wa.i1];
    }
    double a_table = table_albedo(wi, q);
    double total = a_delta + a_transmit + a_direct + a_table;
    if (!(total > 0) || !std::isfinite(total)) return m;
    m.p_delta = a_delta / total;
    m.p_transmit = a_transmit / total;
    m.p_direct = a_direct / total;
    return m;
}

double TabulatedBSDF::pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const {
    if (!usable_direction(wi) || !usable_direction(wo) || wi.z == 0 || side_of(wi) >= sides_) return 0.0;
    // sample() draws from the whole mixture and drops a direction outside the mask, so
    // the density of what it returns is the mixture's inside the mask and 0 outside.
    const bool reflect = wi.z * wo.z > 0;
    if (!(lobes & (reflect ? kGlossyReflection : kGlossyTransmission))) return 0.0;
    return mixture_pdf(mixture(wi, q, nullptr, nullptr), wi, wo, q);
}

double TabulatedBSDF::mixture_pdf(const Mixture &m, const Vec3 &wi, const Vec3 &wo, const Query &q) const {
    double p = std::max(0.0, 1.0 - m.p_delta - m.p_transmit - m.p_direct) * table_pdf(wi, wo, q);
    const int side = side_of(wi);
    if (const BSDF *d = direct(side); d && m.p_direct > 0 && wi.z * wo.z > 0)
        p += m.p_direct * d->pdf(wi, wo, kGlossyReflection | kDiffuseReflection, direct_query(q, side));
    return p;
}

BSDFSample TabulatedBSDF::sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes,
                                 const Query &q, double *weight) const {
    zero(weight);
    if (!usable_direction(wi) || wi.z == 0 || side_of(wi) >= sides_) return {};
    const int C = channels(), side = side_of(wi);
    double small[32]; // RGB tables: no allocation in the render loop
    std::vector<double> large(C > 16 ? 2 * C : 0);
    double *delta_w = C > 16 ? large.data() : small, *transmit_w = delta_w + C;
    const Mixture m = mixture(wi, q, delta_w, transmit_w);
    const double p_delta = m.p_delta, p_transmit = m.p_transmit, p_direct = m.p_direct;
    PCG32 rng(hash_directions(0x7ab1e, wi, Vec3{u1, u2x, u2y}));
    BSDFSample s;
    // Delta lobes: picked with probability p proportional to their luminance, weight
    // (reflectance or transmittance) / p, so the expected weight is the lobe's own.
    if (u1 < p_delta) { // the exact delta reflection (the stack's, or the entry boundary's)
        if (!(lobes & kDeltaReflection)) return {};
        s.wo = reflect(wi);
        s.pdf = p_delta;
        s.lobe = kDeltaReflection;
        for (int c = 0; c < C; ++c) weight[c] = delta_w[c] / p_delta;
        return s;
    }
    if (u1 < p_delta + p_transmit) { // the stack's unscattered transmission
        if (!(lobes & kDeltaTransmission)) return {};
        s.wo = m.wt;
        s.pdf = p_transmit;
        s.lobe = kDeltaTransmission;
        s.eta = m.eta;
        for (int c = 0; c < C; ++c) weight[c] = transmit_w[c] / p_transmit;
        return s;
    }
    if (u1 < p_delta + p_transmit + p_direct) {
        const BSDF *direct_side = direct(side);
        double *wd = scratch(3, direct_side->channels());
        const double u_lobe = rng.uniform();
        BSDFSample d = direct_side->sample(wi, u_lobe, u2x, u2y, kGlossyReflection | kDiffuseReflection,
                                           direct_query(q, side), wd);
        if (!d.lobe) return {};
        s.wo = d.wo;
    } else {
        // Table: theta_i and thickness nodes by their interpolation weights, then a patch.
        Weights wt = thickness_weights(q);
        Weights wa = angle_weights(std::acos(std::clamp(std::abs(wi.z), 0.0, 1.0)), grid_.n_theta_i);
        int t = rng.uniform() < wt.w1 ? wt.i1 : wt.i0;
        int ti = rng.uniform() < wa.w1 ? wa.i1 : wa.i0;
        const std::size_t NP = patches();
        const double *cdf = &cdf_[node(side, t, ti) * (NP + 1)];
        double u = rng.uniform();
        std::size_t p = std::min<std::size_t>(std::upper_bound(cdf, cdf + NP + 1, u) - cdf - 1, NP - 1);
        int m = static_cast<int>(p % grid_.n_phi);
        int k = static_cast<int>((p / grid_.n_phi) % grid_.n_theta_o);
        int l = static_cast<int>(p / (std::size_t(grid_.n_phi) * grid_.n_theta_o)); // 0: reflection
        double ch, cl, pl, ph;
        patch_bounds(k, m, ch, cl, pl, ph);
        double cz = cl + u2x * (ch - cl);
        double phi = pl + u2y * (ph - pl);
        if (rng.uniform() < 0.5) phi = -phi;
        double sz = std::sqrt(std::max(0.0, 1.0 - cz * cz));
        double base = std::atan2(wi.y, wi.x) + phi;
        const bool up = (l == 0) == (wi.z > 0);
        s.wo = {sz * std::cos(base), sz * std::sin(base), up ? cz : -cz};
    }
    s.lobe = wi.z * s.wo.z > 0 ? kGlossyReflection : kGlossyTransmission;
    if (!(s.lobe & lobes)) return {};
    // pdf() of s.wo (its lobe is in the mask, wi checked above) with this call's mixture:
    // the delta stack's 1-D adding is solved once per sample, not again by pdf().
    s.pdf = usable_direction(s.wo) ? mixture_pdf(m, wi, s.wo, q) : 0.0;
    if (!(s.pdf > 0)) return {};
    eval(wi, s.wo, lobes & ~kDelta, q, weight);
    for (int c = 0; c < C; ++c) weight[c] /= s.pdf;
    // Transmitted weights carry (n_i / n_t)^2 of the whole stack: report its eta so a
    // path tracer's Russian roulette (throughput x eta^2) sees the radiance scaling.
    if (s.lobe == kGlossyTransmission) s.eta = side == 0 ? transmission_eta_ : 1.0 / transmission_eta_;
    return s;
}

} // namespace bsdflab
