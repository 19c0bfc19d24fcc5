// A BSDF read from a table (see table_grid.h for the axes): multilinear interpolation of
// f over (thickness, theta_i, theta_o, phi), times |cos theta_o|; optionally plus an exact
// "direct" BSDF (a layered model's top interface: its glossy and delta reflection), whose
// channels are projected by P to the table's channels.
//
// Sampling is a one-sample mixture of (a) the direct model's delta reflection, (b) its
// glossy reflection and (c) the table: per (thickness node, theta_i node) a discrete CDF
// over patches (lobe, theta_o cell, phi cell) weighted by luminance x solid angle (with a
// small floor so every patch where interpolation can be non-zero is reachable), then
// uniform in (cos theta_o, phi) within the patch; theta_i and thickness nodes are picked
// with their interpolation weights. pdf() is the exact density of that mixture.
// One- and two-lobe tables describe light arriving from above (wi.z > 0): from below
// everything is zero. Four-lobe (two-sided) tables also hold light arriving from below
// (lobes 2, 3 of table_grid.h): each side has its own CDFs, and its own exact part
// (`direct` above: the top interface; `direct_below` below: the base, asked with its own
// film), added to reflection on its side.
// With a delta stack (table_delta.h: a layered model's smooth boundaries and slabs) the
// delta parts are the stack's complete delta lobes instead of the side's own delta
// reflection: reflection (the entry boundary's own plus every path that crosses it, is
// reflected by smooth boundaries below and crosses back, all unscattered) and the
// unscattered transmission, from either side; the mixture picks each with probability
// proportional to its luminance, as the delta reflection alone before.
// Film thicknesses outside a multi-node thickness range are clamped to its ends, for the
// table part and the exact part alike. Transmitted samples report eta = n_t / n_i of the
// whole stack (their weights carry (n_i / n_t)^2); from below its inverse.
#pragma once
#include <memory>
#include <vector>
#include "bsdf.h"
#include "table_delta.h"
#include "table_grid.h"

namespace bsdflab {

class TabulatedBSDF final : public BSDF {
  public:
    // values: f per cell and channel, [cell * C + c] (cell order of TableGrid::cell_index);
    // luminance: per channel weights for the sampling CDFs.
    TabulatedBSDF(std::vector<double> channel_ids, TableGrid grid, std::vector<float> values,
                  std::vector<double> luminance, std::shared_ptr<const BSDF> direct, std::vector<double> P,
                  double default_thickness, double transmission_eta = 1.0,
                  std::shared_ptr<const BSDF> direct_below = nullptr,
                  std::shared_ptr<const TableDeltaStack> delta = nullptr, std::vector<double> delta_P = {});
    uint32_t lobes() const override;
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const override;
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q) const override;
    BSDFSample sample(const Vec3 &wi, double u1, double u2x, double u2y, uint32_t lobes, const Query &q,
                      double *weight) const override;

  private:
    struct Weights {
        int i0, i1;
        double w1;
    }; // linear interpolation between two nodes
    Weights thickness_weights(const Query &q) const;
    Query direct_query(const Query &q, int side) const; // the film thickness the exact part sees
    int side_of(const Vec3 &wi) const { return wi.z > 0 ? 0 : 1; }
    int table_lobe(const Vec3 &wi, const Vec3 &wo) const { // -1: not in the table
        int l = wi.z * wo.z > 0 ? 0 : 1;
        return l < per_side_ ? 2 * side_of(wi) + l : -1;
    }
    const BSDF *direct(int side) const { return side == 0 ? direct_.get() : direct_below_.get(); }
    std::size_t node(int side, int t, int ti) const {
        return (std::size_t(side) * grid_.n_thickness() + t) * grid_.n_theta_i + ti;
    }
    Weights angle_weights(double theta, int n) const;
    Weights phi_weights(double phi) const;
    void table_eval(const Vec3 &wi, const Vec3 &wo, const Query &q, double *out) const;
    double table_pdf(const Vec3 &wi, const Vec3 &wo, const Query &q) const;
    double table_albedo(const Vec3 &wi, const Query &q) const;
    // Luminance share of light that crosses the side's smooth interface at theta (1 - its
    // delta reflectance; 1 without one): the table is interpolated in f / (entry(theta_i)
    // entry(theta_o)), wo leaving through its own side.
    double entry(int side, double theta, const Query &q) const;
    struct Entry {
        double c0, c1; // the two nodes' interpolation weights, times entry(theta) / entry(node)
    };
    Entry entry_weights(const Vec3 &w, const Weights &wa, int n, const Query &q) const; // n: nodes
    void direct_eval(const BSDF &d, const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q,
                     double *out) const;
    // The one-sample mixture's probabilities for wi: delta reflection, delta transmission
    // (toward `wt`, reporting `eta`), the direct model's glossy part; the rest is the table.
    // The weights (channels(), may be null) are the delta lobes' reflectance and transmittance.
    struct Mixture {
        double p_delta = 0, p_transmit = 0, p_direct = 0;
        Vec3 wt{0.0, 0.0, 1.0};
        double eta = 1.0;
    };
    Mixture mixture(const Vec3 &wi, const Query &q, double *delta_weight, double *transmit_weight) const;
    // pdf() of a non-delta wo inside the mask, given wi's mixture (sample() passes its own:
    // one delta solve per call; a local value, so nothing is shared between threads).
    double mixture_pdf(const Mixture &m, const Vec3 &wi, const Vec3 &wo, const Query &q) const;
    // The delta lobes' weights projected to the table's channels (R, T may be null); the
    // delta stack's when there is one, else the side's own delta reflection.
    void delta_lobes(const Vec3 &wi, const Query &q, double *R, double *T, Vec3 &wt, double &eta) const;
    // Patch geometry of (theta_o cell k, phi cell m).
    void patch_bounds(int k, int m, double &cos_hi, double &cos_lo, double &phi_lo, double &phi_hi) const;
    // Patches of one side: (lobe of the side, theta_o cell, phi cell).
    std::size_t patches() const { return std::size_t(per_side_) * grid_.n_theta_o * grid_.n_phi; }

    TableGrid grid_;
    std::vector<float> values_;
    std::vector<double> luminance_;
    std::shared_ptr<const BSDF> direct_, direct_below_;
    std::shared_ptr<const TableDeltaStack> delta_;
    std::vector<double> delta_P_; // (C x delta channels) row-major
    int sides_ = 1, per_side_ = 1; // sides lit (1: above only, 2: both) and lobes per side
    std::vector<double> P_; // (C x direct channels) row-major, or empty
    double default_thickness_;
    double transmission_eta_; // n_t / n_i across the whole stack, reported by transmitted samples
    // Per (side, thickness node, theta_i node) (node()): patch CDF (patches() + 1
    // entries), patch probabilities, and the table albedo (luminance) at that node.
    std::vector<double> cdf_, prob_, albedo_;
    std::vector<double> direct_albedo_; // per (side, theta_i node), glossy reflection luminance
};

} // namespace bsdflab
