// Gauss-Legendre quadrature, shared by the adding-doubling solver and the multiple-scattering
// energy tables.
#pragma once

#include <vector>

namespace bsdflab {

// Nodes x (ascending) and weights w of the n-point Gauss-Legendre rule on [-1, 1], by
// Newton's method on the Legendre polynomial P_n (exact for polynomials of degree 2n - 1).
void gauss_legendre(int n, std::vector<double> &x, std::vector<double> &w);

} // namespace bsdflab
