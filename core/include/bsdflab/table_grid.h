// Axes of a BSDF table and the mapping between cells and directions.
//   lobe      0 = reflection (wo above), 1 = transmission (wo below, theta_o from -z);
//             two-sided tables add 2 = reflection from below (wi and wo below) and
//             3 = transmission from below (wi below, wo above); theta_i then from -z
//   thickness film-thickness nodes in nm (one node with value < 0 = the model's own)
//   theta_i, theta_o  cell-centred nodes (k + 1/2) (pi/2) / n, never normal or grazing
//   phi       |phi_o - phi_i| nodes evenly over [0, pi], both ends included
// Incident directions lie in the x-z plane at azimuth 0 (wi.x >= 0).
#pragma once
#include <cstddef>
#include <vector>
#include "vector.h"

namespace bsdflab {

struct TableGrid {
    int n_lobes = 1, n_theta_i = 12, n_theta_o = 24, n_phi = 13;
    std::vector<double> thickness{-1.0};

    int n_thickness() const { return static_cast<int>(thickness.size()); }
    std::size_t cells() const { return std::size_t(n_lobes) * n_thickness() * n_theta_i * n_theta_o * n_phi; }
    double theta_i(int k) const;
    double theta_o(int k) const;
    double phi(int k) const;
    std::size_t cell_index(int lobe, int t, int ti, int to, int ph) const {
        return (((std::size_t(lobe) * n_thickness() + t) * n_theta_i + ti) * n_theta_o + to) * n_phi + ph;
    }
    // Directions of a cell (wi, wo) and its indices.
    void cell_directions(std::size_t cell, Vec3 &wi, Vec3 &wo, int &lobe, int &t) const;
};

} // namespace bsdflab
