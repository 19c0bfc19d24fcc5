// The adding-doubling solver (adding_doubling.h): setup and the evaluation of direction
// pairs; the solve itself is adding_doubling_solve.cpp, its parts adding_doubling_parts.h.
#include "bsdflab/adding_doubling.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include "adding_doubling_parts.h"
#include "bsdflab/adding_doubling_ops.h"
#include "bsdflab/constants.h"
#include "bsdflab/frame.h"
#include "bsdflab/interfaces.h"
#include "bsdflab/parallel.h"

namespace bsdflab {

namespace {

constexpr double kIndexTolerance = 1e-9;

} // namespace

int hg_orders_needed(double g, double tolerance) {
    if (g == 0.0) return 1;
    double y = std::acosh(1.0 + (1.0 - std::abs(g)) * (1.0 - std::abs(g)) / (2.0 * std::abs(g)));
    return static_cast<int>(std::ceil(-std::log(tolerance) / y)) + 2;
}

std::shared_ptr<AddingDoubling> AddingDoubling::with_top(std::shared_ptr<const BSDF> top) const {
    if (!top || top->channels() != channels()) throw std::invalid_argument("top channel count mismatch");
    if (smooth_top_ || ad::is_delta(*top)) throw std::invalid_argument("with_top needs rough tops");
    if (settings_.film_lookup) {
        FilmLookupStats stats;
        if (auto fast = top->with_film_lookup(-1.0, stats)) top = fast;
    }
    auto copy = std::make_shared<AddingDoubling>(*this);
    copy->boundaries_[0] = std::move(top);
    return copy;
}

AddingDoubling::AddingDoubling(std::vector<double> wavelengths,
                               std::vector<std::shared_ptr<const BSDF>> boundaries, std::vector<double> media,
                               std::vector<ADSlab> slabs, ADSettings settings)
    : wavelengths_(std::move(wavelengths)), boundaries_(std::move(boundaries)), media_(std::move(media)),
      slabs_(std::move(slabs)), settings_(settings) {
    const std::size_t K = slabs_.size();
    if (boundaries_.size() != K + 1) throw std::invalid_argument("need one boundary more than slabs");
    if (media_.size() != K + 2) throw std::invalid_argument("need K + 2 media indices");
    for (auto &b : boundaries_)
        if (!b || b->channels() != channels()) throw std::invalid_argument("boundary channel count mismatch");
    for (auto &s : slabs_)
        if (static_cast<int>(s.sigma_a.size()) != channels())
            throw std::invalid_argument("sigma_a needs one value per channel");
    if (settings_.nodes < 2) throw std::invalid_argument("nodes must be >= 2");
    if (!(settings_.thin_depth > 0)) throw std::invalid_argument("thin_depth must be > 0");
    if (settings_.spectral_stride < 1) throw std::invalid_argument("spectral_stride must be >= 1");
    if (!(settings_.fine_step > 0)) throw std::invalid_argument("fine_step must be > 0");
    if (settings_.film_lookup) {
        FilmLookupStats stats;
        for (auto &b : boundaries_)
            if (auto fast = b->with_film_lookup(-1.0, stats)) b = fast;
        film_lookup_error_ = stats.max_error;
    }
    smooth_top_ = ad::is_delta(*boundaries_[0]);
    two_sided_ = smooth_top_ && K >= 1 && ad::is_delta(*boundaries_[K]) && media_[K + 1] > 0;
    inner_ = std::make_shared<Inner>();
    for (std::size_t j = 1; j < K; ++j)
        snell_ = snell_ || (ad::is_delta(*boundaries_[j]) && !index_matched(j));
    if (snell_) {
        // One node set in p = n sin(theta) for every slab (solve_snell): the densest slab's
        // panels cut at the critical cosine of every lower index of the stack.
        if (!smooth_top_)
            throw std::invalid_argument("adding-doubling: a smooth interior interface between unequal "
                                        "indices is solved under a smooth top only");
        for (std::size_t j = 1; j <= K; ++j) n_max_ = std::max(n_max_, media_[j]);
        for (double a : media_)
            if (a > 0 && a < n_max_ * (1.0 - kIndexTolerance)) {
                double r = a / n_max_;
                breaks_.push_back(std::sqrt((1.0 - r) * (1.0 + r)));
                // Graded cuts after a small critical cosine c: seen from the denser side the
                // Fresnel knee past the critical angle is ~c wide, which neither the solve nor
                // its coarse twin resolved at a vanishing contrast (error 9e-4, bound 1e-5).
                const double c = breaks_.back();
                for (double f = 4.0; c * f < 0.2; f *= 4.0) breaks_.push_back(c * f);
            }
    } else {
        for (std::size_t j = 0; j + 1 < media_.size(); ++j) {  // critical cosines of every index step
            double a = media_[j], b = media_[j + 1];
            if (a > 0 && b > 0 && std::abs(a - b) > kIndexTolerance * std::max(a, b)) {
                double r = std::min(a, b) / std::max(a, b);
                breaks_.push_back(std::sqrt((1.0 - r) * (1.0 + r)));
            }
        }
    }
    ad::panel_nodes(settings_.nodes, breaks_, mu_, w_);
    rough_base_exit_ = (smooth_top_ || ad::rough_alpha(*boundaries_[0]) > 0) && !snell_ && K >= 1 &&
                       media_[K + 1] > 0 && ad::rough_alpha(*boundaries_[K]) > 0;
    rough_top_exit_ = !smooth_top_ && ad::rough_alpha(*boundaries_[0]) > 0 && K >= 1 && media_[K + 1] > 0 &&
                      ad::is_delta(*boundaries_[K]);
    // Fourier orders: what the slabs' phase functions and the boundaries below the top
    // carry (the top's own reflection is evaluated directly; below it, only orders the
    // stack under it scatters into survive the adding).
    double alpha_min = 1.0;
    int M = 1;
    for (auto &s : slabs_)
        if (s.sigma_s > 0 && s.thickness > 0)
            M = std::max(M, hg_orders_needed(s.g, settings_.order_tolerance));
    for (std::size_t j = 0; j < boundaries_.size(); ++j) {
        double a = ad::rough_alpha(*boundaries_[j]);
        if (a > 0) alpha_min = std::min(alpha_min, a);
        if (j > 0 && ad::is_delta(*boundaries_[j])) delta_below_ = true;
        if (j == 0 || ad::is_delta(*boundaries_[j])) continue;
        if (a > 0) M = std::max(M, static_cast<int>(std::ceil(6.0 / a)) + 2);
        else if (boundaries_[j]->lobes() & (kGlossyReflection | kGlossyTransmission)) M = std::max(M, 64);
    }
    // A rough top over a delta reflection path: the returning beam crosses the top twice,
    // in lobes of its own width (ad::rough_top_values' fine-node product); over a rough
    // base (eval_rough_base) the unscattered beam joins the top's lobe to the base's. In
    // orders_, so an explicit orders= and the bound's coarser solve reach them.
    const double top_alpha = ad::rough_alpha(*boundaries_[0]);
    if (!smooth_top_ && (delta_below_ || rough_base_exit_) && top_alpha > 0)
        M = std::max(M, static_cast<int>(std::ceil(6.0 / top_alpha)) + 2);
    orders_ = settings_.orders > 0 ? settings_.orders : M;
    int H = 32;
    double need = std::max(4.0 * orders_, orders_ + 10.0 / alpha_min);
    while (2 * H < need && H < (1 << 14)) H *= 2;
    half_samples_ = settings_.azimuth_samples > 0 ? settings_.azimuth_samples : H;
}

bool AddingDoubling::index_matched(std::size_t j) const {
    return !(std::abs(media_[j] - media_[j + 1]) > kIndexTolerance * media_[j]);
}

std::vector<double> AddingDoubling::order_weights(int m, std::size_t N) const {
    std::vector<double> W(N, 0.0);
    for (std::size_t i = 0; i < mu_.size(); ++i) W[i] = (m == 0 ? 2.0 : 1.0) * kPi * mu_[i] * w_[i];
    return W;
}

void AddingDoubling::eval_two_sided(const double *wi_, const double *wo_, std::size_t count,
                                    double *out) const {
    const int C = channels(), M = orders_;
    const std::size_t K = slabs_.size();
    const BSDF &top = *boundaries_[0], &base = *boundaries_[K];
    std::vector<std::size_t> active;
    std::vector<double> cosines, scale;  // per active pair: (viewer, light) inside cosines
    std::vector<int> op;
    std::vector<double> tv(C), tl(C);
    for (std::size_t p = 0; p < count; ++p) {
        Vec3 wi{wi_[3 * p], wi_[3 * p + 1], wi_[3 * p + 2]}, wo{wo_[3 * p], wo_[3 * p + 1], wo_[3 * p + 2]};
        if (!usable_direction(wi) || !usable_direction(wo) || wi.z == 0 || wo.z == 0) continue;
        const bool view_up = wi.z > 0, light_up = wo.z > 0;
        double mu_v = 0, mu_l = 0;
        ad::delta_weight(view_up ? top : base, wi.z, kDeltaTransmission, tv.data(), &mu_v);
        ad::delta_weight(light_up ? top : base, wo.z, kDeltaTransmission, tl.data(), &mu_l);
        if (!(mu_v > 0) || !(mu_l > 0)) continue;
        // The delta weights carry the radiance scaling of both crossings; the light's
        // solid angle inside is (n_out / n_in)^2 times its own outside.
        double r = light_up ? media_[1] / media_[0] : media_[K] / media_[K + 1];
        for (int c = 0; c < C; ++c) scale.push_back(tv[c] * tl[c] * r * r * std::abs(wo.z));
        op.push_back(view_up ? (light_up ? 0 : 3) : (light_up ? 1 : 2));
        if (snell_) {  // solve_snell's extras are p = n sin(theta), the same in every slab
            mu_v = (view_up ? media_[1] : media_[K]) * std::sqrt((1.0 - mu_v) * (1.0 + mu_v));
            mu_l = (light_up ? media_[1] : media_[K]) * std::sqrt((1.0 - mu_l) * (1.0 + mu_l));
        }
        cosines.push_back(mu_v);
        cosines.push_back(mu_l);
        active.push_back(p);
    }
    if (active.empty()) return;
    Queries q;
    std::vector<int> index;
    q.cosines = ad::distinct(cosines, index);
    q.op = op;
    for (std::size_t a = 0; a < active.size(); ++a) {
        q.row.push_back(index[2 * a]);
        q.col.push_back(index[2 * a + 1]);
    }
    std::vector<double> V;
    solve({}, {}, V, &q);
    const std::size_t P = active.size();
    parallel_for(P, 256, [&](std::size_t begin, std::size_t end) {
        std::vector<double> cm(M);
        for (std::size_t a = begin; a < end; ++a) {
            std::size_t p = active[a];
            double dphi =
                std::atan2(wi_[3 * p + 1], wi_[3 * p]) - std::atan2(wo_[3 * p + 1], wo_[3 * p]) - kPi;
            for (int m = 0; m < M; ++m) cm[m] = std::cos(m * dphi);
            for (int c = 0; c < C; ++c) {
                double s = 0.0;
                for (int m = 0; m < M; ++m) s += V[(static_cast<std::size_t>(c) * M + m) * P + a] * cm[m];
                double v = s * scale[a * C + c];
                out[p * C + c] = std::isfinite(v) ? v : 0.0;
            }
        }
    });
}

void AddingDoubling::eval(const double *wi_, const double *wo_, std::size_t count, double *out,
                          bool scattered_only) const {
    const int C = channels(), M = orders_;
    std::fill(out, out + count * C, 0.0);
    if (two_sided_) return eval_two_sided(wi_, wo_, count, out);
    if (rough_base_exit_) eval_rough_base(wi_, wo_, count, out, scattered_only);
    if (rough_top_exit_) eval_rough_top(wi_, wo_, count, out);
    std::vector<std::size_t> active;
    std::vector<double> cos_out, cos_in, scale;  // scale: per active pair and channel
    const BSDF &top = *boundaries_[0];
    std::vector<double> tv(C), tl(C);
    for (std::size_t p = 0; p < count; ++p) {
        Vec3 wi{wi_[3 * p], wi_[3 * p + 1], wi_[3 * p + 2]}, wo{wo_[3 * p], wo_[3 * p + 1], wo_[3 * p + 2]};
        if (!usable_direction(wi) || !usable_direction(wo) || !(wi.z > 0) || !(wo.z > 0)) continue;
        double mu_v = wi.z, mu_l = wo.z;
        if (smooth_top_) {
            ad::delta_weight(top, wi.z, kDeltaTransmission, tv.data(), &mu_v);
            ad::delta_weight(top, wo.z, kDeltaTransmission, tl.data(), &mu_l);
            if (!(mu_v > 0) || !(mu_l > 0)) continue;
            double r = media_[1] / media_[0];
            for (int c = 0; c < C; ++c) scale.push_back(tv[c] * tl[c] * r * r * wo.z);
        } else {
            for (int c = 0; c < C; ++c) scale.push_back(wo.z);
        }
        active.push_back(p);
        cos_out.push_back(mu_v);
        cos_in.push_back(mu_l);
    }
    if (active.empty()) return;
    std::vector<int> io, ii;
    std::vector<double> qo = ad::distinct(cos_out, io), qi = ad::distinct(cos_in, ii);
    std::vector<double> V;
    solve(qo, qi, V);
    const std::size_t Qo = qo.size(), Qi = qi.size();
    parallel_for(active.size(), 256, [&](std::size_t begin, std::size_t end) {
        std::vector<double> direct(C), cm(M);
        Query q;
        for (std::size_t a = begin; a < end; ++a) {
            std::size_t p = active[a];
            Vec3 wi{wi_[3 * p], wi_[3 * p + 1], wi_[3 * p + 2]},
                wo{wo_[3 * p], wo_[3 * p + 1], wo_[3 * p + 2]};
            double dphi = std::atan2(wi.y, wi.x) - std::atan2(wo.y, wo.x) - kPi;
            for (int m = 0; m < M; ++m) cm[m] = std::cos(m * dphi);
            if (!smooth_top_ && !scattered_only) top.eval(wi, wo, kAll, q, direct.data());
            std::size_t cell = io[a] * Qi + ii[a];
            for (int c = 0; c < C; ++c) {
                double s = 0.0;
                for (int m = 0; m < M; ++m)
                    s += V[(static_cast<std::size_t>(c) * M + m) * Qo * Qi + cell] * cm[m];
                double v = s * scale[a * C + c] + (smooth_top_ || scattered_only ? 0.0 : direct[c]);
                out[p * C + c] = std::isfinite(v) ? v : 0.0;
            }
        }
    });
}

} // namespace bsdflab
