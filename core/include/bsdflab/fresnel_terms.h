// What an interface does to light, per channel: reflectance R and transmittance T as
// functions of the (signed) cosine of the angle to the interface's (micro)normal.
//   cos_i > 0: light arrives from the exterior (above); cos_i < 0: from the interior.
// A term also knows the real relative index eta = n_int / n_ext that bends refracted rays
// (thin films are parallel layers: they change R and T, never the exit direction).
#pragma once
#include <complex>
#include <memory>
#include <vector>
#include "bsdf.h"

namespace bsdflab {

// Deepest film stack a FilmTerm accepts (its evaluation uses fixed-size scratch arrays).
constexpr std::size_t kMaxFilmLayers = 32;

class FresnelTerm {
  public:
    virtual ~FresnelTerm() = default;
    // Writes `channels` values to R and T. T is zero for opaque (conductor) interfaces.
    virtual void eval(double cos_i, const Query &q, double *R, double *T) const = 0;
    virtual bool transmissive() const = 0;
    double eta() const { return eta_; }
    int channels() const { return channels_; }

  protected:
    FresnelTerm(int channels, double eta) : channels_(channels), eta_(eta) {}
    int channels_;
    double eta_;
};

// Bare interface between two real indices (the same for every channel).
class DielectricTerm final : public FresnelTerm {
  public:
    DielectricTerm(int channels, double int_ior, double ext_ior);
    void eval(double cos_i, const Query &q, double *R, double *T) const override;
    bool transmissive() const override { return true; }
};

// Bare interface from a real exterior index into a complex index per channel.
class ConductorTerm final : public FresnelTerm {
  public:
    ConductorTerm(std::vector<std::complex<double>> n_int, double ext_ior);
    void eval(double cos_i, const Query &q, double *R, double *T) const override;
    bool transmissive() const override { return false; }

  private:
    std::vector<std::complex<double>> n_int_;
    double ext_ior_;
};

// A stack of films (indices per channel, thicknesses in nm) coating a substrate that is
// either a real-index dielectric (transmissive) or a complex-index conductor (opaque).
// Query::film_thickness_nm >= 0 replaces the stack's total thickness, scaling every layer
// in proportion (for one film: its thickness), so a texture can vary it across a surface.
class FilmTerm final : public FresnelTerm {
  public:
    FilmTerm(std::vector<double> wavelengths, double ext_ior,
             std::vector<std::vector<std::complex<double>>> layer_n, std::vector<double> layer_d_nm,
             std::vector<std::complex<double>> n_substrate, bool substrate_transmits);
    void eval(double cos_i, const Query &q, double *R, double *T) const override;
    bool transmissive() const override { return transmits_; }

  private:
    std::vector<double> wavelengths_;
    double ext_ior_;
    std::vector<std::vector<std::complex<double>>> layer_n_; // [layer][channel]
    std::vector<double> layer_d_;
    std::vector<std::complex<double>> n_sub_;                // [channel]
    bool transmits_;
    double total_d_;
    // No index depends on the channel: the stack's angular part is shared by all channels
    // (film_stack_spectrum), the fast path for non-dispersive films.
    bool uniform_;
};

} // namespace bsdflab
