// A film's R and T per channel at ONE film thickness, tabulated over the cosine, so that a
// walk pays a cubic interpolation instead of an Airy summation (a complex sincos and
// divisions per wavelength) at every crossing of the film. The tabulator builds one per
// thickness node of its grid (BSDF::with_film_lookup), where the thickness is fixed for a
// whole cell; a query at any other thickness is evaluated exactly.
//
// Nodes. Per side of the interface (light from above: cos_i >= 0, from below: cos_i < 0),
// R and T are smooth in the cosine except at the critical angle k of total internal
// reflection (light arriving from the denser side), where the transmitted wave's normal
// wavenumber q ~ sqrt(cos_i^2 - k^2) has a square-root kink. Each side is split at k into
// [k, 1] and [0, k] (no kink: k = 0, one segment) and each segment is parametrised by
//     cos = k + (end - k) v^2,   v uniform in [0, 1],
// which turns sqrt(cos - k) into a multiple of v: smooth in v, with a node exactly at the
// kink (holding the limit, extrapolated from the smooth side: the exact term is
// ill-conditioned right at the kink). Between nodes: the 4-point cubic (Lagrange)
// interpolant in v (one-sided at the segment ends), error O(h^4).
//
// The error is MEASURED at construction, not assumed: at every interval's midpoint (and the
// quarter points of each segment's end intervals) the interpolant is compared with the
// exact term for every channel; the node count doubles (from kStartIntervals to
// kMaxIntervals) until the largest |error| of R and T there is <= max_error / 2 (margin
// for the error between check points), else build() gives
// nullptr and callers keep the exact term (a kink the split does not know of, e.g. a
// dispersive substrate with a critical angle per channel; film layers add none, even one
// less dense than the incident medium: a layer's response depends on q^2 only).
#pragma once
#include <memory>
#include <vector>
#include "fresnel_terms.h"

namespace bsdflab {

class FilmLookupTerm final : public FresnelTerm {
  public:
    static constexpr int kStartIntervals = 128;
    static constexpr int kMaxIntervals = 2048;
    static constexpr double kDefaultMaxError = 1e-7; // absolute, on R and T in [0, 1]

    // thickness_nm: the Query::film_thickness_nm the lookup answers (< 0: the film's own).
    static std::shared_ptr<const FilmLookupTerm>
    build(std::shared_ptr<const FresnelTerm> exact, double thickness_nm, double max_error = kDefaultMaxError);
    void eval(double cos_i, const Query &q, double *R, double *T) const override;
    bool transmissive() const override { return exact_->transmissive(); }
    double thickness_nm() const { return thickness_; }
    double measured_error() const { return measured_error_; } // max |lookup - exact| checked
    int intervals() const { return intervals_; }              // per segment
    double kink(int side) const { return segments_[side][0].kink; }
    std::size_t bytes() const;                                 // memory of the nodes

    struct Segment {
        double kink = 0, end = 1; // cos = kink + (end - kink) v^2
        std::vector<double> nodes; // [(node) * 2C + c]: R_c then T_c
    };

    FilmLookupTerm(std::shared_ptr<const FresnelTerm> exact, double thickness_nm, int intervals);

  private:
    void fill(Segment &s, int side) const;
    double check(const Segment &s, int side) const; // largest |error| at the check points
    void interpolate(const Segment &s, double v, double *R, double *T) const;
    void exact_at(int side, double cos, double *R, double *T) const;

    std::shared_ptr<const FresnelTerm> exact_;
    double thickness_;
    int intervals_;
    double measured_error_ = 0;
    bool sides_[2] = {true, false}; // side 1 (from below) only for transmissive terms
    Segment segments_[2][2];        // [side][0: kink..1, 1: kink..0 (TIR, may be empty)]
};

// The lookup of `term` at `thickness_nm` when it is a thin-film term and a lookup meets
// the default bound; nullptr otherwise (keep the exact term).
// `stats` accumulates the lookup's measured error and memory.
std::shared_ptr<const FresnelTerm> film_lookup_for(const std::shared_ptr<const FresnelTerm> &term,
                                                   double thickness_nm, FilmLookupStats &stats);

} // namespace bsdflab
