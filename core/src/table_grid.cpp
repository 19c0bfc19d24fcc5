#include "bsdflab/table_grid.h"
#include <cmath>
#include "bsdflab/sampling.h"

namespace bsdflab {

double TableGrid::theta_i(int k) const { return (k + 0.5) * (0.5 * kPi / n_theta_i); }
double TableGrid::theta_o(int k) const { return (k + 0.5) * (0.5 * kPi / n_theta_o); }
double TableGrid::phi(int k) const { return n_phi > 1 ? k * kPi / (n_phi - 1) : 0.0; }

void TableGrid::cell_directions(std::size_t cell, Vec3 &wi, Vec3 &wo, int &lobe, int &t) const {
    int ph = static_cast<int>(cell % n_phi);
    cell /= n_phi;
    int to = static_cast<int>(cell % n_theta_o);
    cell /= n_theta_o;
    int ti = static_cast<int>(cell % n_theta_i);
    cell /= n_theta_i;
    t = static_cast<int>(cell % n_thickness());
    lobe = static_cast<int>(cell / n_thickness());
    double a = theta_i(ti), b = theta_o(to), p = phi(ph);
    // Lobes 2 and 3 (two-sided tables) are lit from below: wi.z < 0; wo lies above for
    // reflection from above and transmission upward (lobes 0 and 3).
    const bool below = lobe >= 2, up = lobe == 0 || lobe == 3;
    wi = {std::sin(a), 0.0, below ? -std::cos(a) : std::cos(a)};
    wo = {std::sin(b) * std::cos(p), std::sin(b) * std::sin(p), up ? std::cos(b) : -std::cos(b)};
}

} // namespace bsdflab
