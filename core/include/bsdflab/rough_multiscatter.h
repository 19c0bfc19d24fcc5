// Multiple-scattering energy compensation of a rough interface (Kulla & Conty 2017,
// "Revisiting physically based shading at Imageworks"): the energy that the
// single-scattering microfacet model loses, 1 - E(mu_i), is given back as a separable,
// reciprocal lobe proportional to (1 - E(mu_i)) (1 - E(mu_o)).
//
//   conductor (bare or film-coated): E is the single-scattering albedo with F = 1; the
//     lobe is tinted by Kulla-Conty's F_avg^2 E_avg / (1 - F_avg (1 - E_avg)), F_avg the
//     hemispherical average of the Fresnel term per channel (at the query's film
//     thickness), so a white (F = 1) conductor conserves energy exactly.
//   dielectric (bare or film-coated substrate): E_s is the single-scattering R + T
//     (transmission without the radiance scaling) from side s, per channel, so the
//     lossless interface conserves energy from both sides. The lost energy of side s is
//     split into reflection and transmission; the transmitted share t_s of the less
//     dense side is its average Fresnel transmittance, the dense side's follows from
//     reciprocity: eta^2 t_in (1 - Eavg_in) = t_out (1 - Eavg_out), eta = n_int / n_ext
//     (capped at 1, the other side then following). Film stacks enter through their R
//     and T at the model's own thickness (a per-query thickness is not re-tabulated).
//
// Tables: E(mu) per channel and side at kNodes cosines mu = t^2 (t uniform, denser at
// grazing), each by a kGrid x kGrid product rule over the visible-normal warp's uniforms,
// cosine-spaced to resolve the warp's tails (the integrand R G1(wo_r) + T G1(wo_t) is
// continuous there, with square-root kinks at total internal reflection); linear in t
// between nodes.
// E_avg = 2 int E mu dmu of that interpolant exactly, so the lobe's energy is
// 1 - E_table(mu_i): the compensated albedo differs from 1 by E_true - E_table, measured
// in tests/test_rough_multiscatter.py (about 1e-3; TABLE_ERROR there is 2e-3).
#pragma once
#include <memory>
#include <vector>
#include "bsdf.h"
#include "fresnel_terms.h"
#include "microfacet.h"

namespace bsdflab {

class MultiScatter {
  public:
    static constexpr int kNodes = 33;
    static constexpr int kGrid = 64;

    MultiScatter(const Microfacet &mf, std::shared_ptr<const FresnelTerm> term);
    // The compensation lobe, f |cos theta_o| per channel, for wi, wo on a transmissive
    // interface's either side or (conductors) both above.
    void eval(const Vec3 &wi, const Vec3 &wo, uint32_t lobes, const Query &q, double *out) const;
    // Probability that sample() picks the compensation lobe at wi, and within it the
    // probability of reflection (channel means of the lobe's energies).
    void probabilities(const Vec3 &wi, uint32_t lobes, double &p_lobe, double &p_reflect) const;
    // The compensation lobe's share of the model's solid-angle density at wo (times p_lobe).
    double pdf(const Vec3 &wi, const Vec3 &wo, uint32_t lobes) const;
    // Tabulated single-scattering albedo of side (0: above, 1: below) at |cos| mu, channel c.
    double albedo(int side, double mu, int c) const;
    double average_albedo(int side, int c) const { return avg_[side][c]; }

  private:
    double interpolate(const std::vector<double> &table, double mu, int c) const;
    // Per channel: the tint of a conductor's lobe at the query's film thickness.
    void conductor_tint(const Query &q, double *tint) const;

    std::shared_ptr<const FresnelTerm> term_;
    int channels_;
    bool transmits_;
    double eta_;                           // n_int / n_ext
    bool film_;                            // a film stack (its tint depends on thickness)
    std::vector<double> table_[2];         // [side][node * channels + c]
    std::vector<double> avg_[2];           // [side][c]
    std::vector<double> transmit_share_[2];// dielectric: t_s per channel
    std::vector<double> tint_;             // conductor: at the model's own thickness
    std::vector<double> ss_energy_mean_;   // conductor: channel-mean F_avg (for probabilities)
};

} // namespace bsdflab
