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
    wi = {std::sin(a), 0.0, std::cos(a)};
    wo = {std::sin(b) * std::cos(p), std::sin(b) * std::sin(p), lobe == 0 ? std::cos(b) : -std::cos(b)};
}

} // namespace bsdflab
