// The query values of one (channel, order) for the adding-doubling solve
// (adding_doubling_parts.h): read at the extras (smooth top, two-sided stack), or carried
// through a rough top's transmission kernels.
#include "adding_doubling_parts.h"

namespace bsdflab::ad {

void smooth_top_values(const Op &Y, const std::vector<int> &xo, const std::vector<int> &xi, std::size_t N,
                       double *V) {
    if (Y.K.empty()) return;
    const std::size_t Qo = xo.size(), Qi = xi.size();
    for (std::size_t a = 0; a < Qo; ++a)
        for (std::size_t b = 0; b < Qi; ++b) V[a * Qi + b] = Y.K[xo[a] * N + xi[b]];
}

void rough_top_values(const Op &Y, const std::vector<double> &Td, const std::vector<double> &Tu,
                      const Grid &g, std::size_t N, std::size_t Qo, std::size_t Qi, double *V) {
    const int n = g.n;
    std::vector<double> Z(N * Qi, 0.0);  // (Y_D + Y_K W) Td
    for (std::size_t i = 0; i < N; ++i) {
        double *z = &Z[i * Qi];
        if (!Y.D.empty())
            for (std::size_t b = 0; b < Qi; ++b) z[b] = Y.D[i] * Td[i * Qi + b];
        if (!Y.K.empty())
            for (int k = 0; k < n; ++k) {
                double s = Y.K[i * N + k] * g.W[k];
                if (s == 0.0) continue;
                for (std::size_t b = 0; b < Qi; ++b) z[b] += s * Td[k * Qi + b];
            }
    }
    for (std::size_t a = 0; a < Qo; ++a)
        for (int k = 0; k < n; ++k) {
            double s = Tu[a * N + k] * g.W[k];
            if (s == 0.0) continue;
            for (std::size_t b = 0; b < Qi; ++b) V[a * Qi + b] += s * Z[k * Qi + b];
        }
}

void two_sided_values(const LayerOperators &S, const std::vector<int> &op, const std::vector<int> &row,
                      const std::vector<int> &col, int n, std::size_t N, double *V) {
    const Op *ops[4] = {&S.Rt, &S.Td, &S.Rb, &S.Tu};
    for (std::size_t p = 0; p < op.size(); ++p) {
        const Op &o = *ops[op[p]];
        if (!o.K.empty()) V[p] = o.K[(n + row[p]) * N + n + col[p]];
    }
}

} // namespace bsdflab::ad
