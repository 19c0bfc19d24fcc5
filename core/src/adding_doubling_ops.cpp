// Operator algebra of the adding-doubling solver (adding_doubling_ops.h has the formulas).
#include "bsdflab/adding_doubling_ops.h"
#include <cmath>
#include <stdexcept>
#include <utility>

namespace bsdflab::ad {

namespace {

// C += A W B over the weighted inner index (A, B, C all N x N).
void add_kwk(const std::vector<double> &A, const std::vector<double> &B, const Grid &g,
             std::vector<double> &C) {
    const int N = g.N, n = g.n;
    for (int i = 0; i < N; ++i) {
        double *c = &C[i * N];
        const double *a = &A[i * N];
        for (int k = 0; k < n; ++k) {
            double s = a[k] * g.W[k];
            if (s == 0.0) continue;
            const double *b = &B[k * N];
            for (int j = 0; j < N; ++j) c[j] += s * b[j];
        }
    }
}

// Solves A X = B in place (A n x n, B n x cols, row-major) by Gaussian elimination with
// partial pivoting; A is destroyed.
void solve_in_place(std::vector<double> &A, int n, std::vector<double> &B, int cols) {
    for (int k = 0; k < n; ++k) {
        int p = k;
        double best = std::abs(A[k * n + k]);
        for (int i = k + 1; i < n; ++i)
            if (std::abs(A[i * n + k]) > best) {
                best = std::abs(A[i * n + k]);
                p = i;
            }
        if (!(best > 0) || !std::isfinite(best))
            throw std::runtime_error("adding-doubling: singular system (an energy-conserving loop "
                                     "without loss?)");
        if (p != k) {
            for (int j = 0; j < n; ++j) std::swap(A[k * n + j], A[p * n + j]);
            for (int j = 0; j < cols; ++j) std::swap(B[k * cols + j], B[p * cols + j]);
        }
        double inv = 1.0 / A[k * n + k];
        for (int i = k + 1; i < n; ++i) {
            double f = A[i * n + k] * inv;
            if (f == 0.0) continue;
            for (int j = k + 1; j < n; ++j) A[i * n + j] -= f * A[k * n + j];
            for (int j = 0; j < cols; ++j) B[i * cols + j] -= f * B[k * cols + j];
        }
    }
    for (int k = n - 1; k >= 0; --k) {
        double inv = 1.0 / A[k * n + k];
        for (int j = 0; j < cols; ++j) B[k * cols + j] *= inv;
        for (int i = 0; i < k; ++i) {
            double f = A[i * n + k];
            if (f == 0.0) continue;
            for (int j = 0; j < cols; ++j) B[i * cols + j] -= f * B[k * cols + j];
        }
    }
}

} // namespace

Op mul(const Op &a, const Op &b, const Grid &g) {
    const int N = g.N;
    Op r;
    if (!a.D.empty() && !b.D.empty()) {
        r.D.resize(N);
        for (int i = 0; i < N; ++i) r.D[i] = a.D[i] * b.D[i];
    }
    bool any =
        (!a.D.empty() && !b.K.empty()) || (!a.K.empty() && !b.D.empty()) || (!a.K.empty() && !b.K.empty());
    if (!any) return r;
    r.K.assign(static_cast<std::size_t>(N) * N, 0.0);
    if (!a.D.empty() && !b.K.empty())
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < N; ++j) r.K[i * N + j] += a.D[i] * b.K[i * N + j];
    if (!a.K.empty() && !b.D.empty())
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < N; ++j) r.K[i * N + j] += a.K[i * N + j] * b.D[j];
    if (!a.K.empty() && !b.K.empty()) add_kwk(a.K, b.K, g, r.K);
    return r;
}

Op add(const Op &a, const Op &b) {
    Op r;
    auto sum = [](const std::vector<double> &x, const std::vector<double> &y) {
        if (x.empty()) return y;
        if (y.empty()) return x;
        std::vector<double> s(x);
        for (std::size_t i = 0; i < s.size(); ++i) s[i] += y[i];
        return s;
    };
    r.D = sum(a.D, b.D);
    r.K = sum(a.K, b.K);
    return r;
}

Op inverse_one_minus(const Op &a, const Grid &g) {
    const int N = g.N, n = g.n;
    Op r;
    r.D.assign(N, 1.0);
    if (!a.D.empty())
        for (int i = 0; i < N; ++i) r.D[i] = 1.0 / (1.0 - a.D[i]);
    if (a.K.empty()) return r;
    const std::vector<double> &G = r.D;
    // GK, then the node block of I - G K W and the node rows of X = (I - GKW)^-1 GK.
    std::vector<double> GK(a.K);
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) GK[i * N + j] *= G[i];
    std::vector<double> A(static_cast<std::size_t>(n) * n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) A[i * n + j] = (i == j ? 1.0 : 0.0) - GK[i * N + j] * g.W[j];
    std::vector<double> X(GK.begin(), GK.begin() + static_cast<std::ptrdiff_t>(n) * N);
    solve_in_place(A, n, X, N);
    r.K.assign(static_cast<std::size_t>(N) * N, 0.0);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < N; ++j) r.K[i * N + j] = X[i * N + j];
    // Extra rows: X_e = GK_e + GK_e,nodes W X_nodes (the extras never feed back).
    for (int i = n; i < N; ++i) {
        double *row = &r.K[i * N];
        for (int j = 0; j < N; ++j) row[j] = GK[i * N + j];
        for (int k = 0; k < n; ++k) {
            double s = GK[i * N + k] * g.W[k];
            if (s == 0.0) continue;
            for (int j = 0; j < N; ++j) row[j] += s * X[k * N + j];
        }
    }
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) r.K[i * N + j] *= G[j];
    return r;
}

Op reflect_over(const LayerOperators &top, const Op &R, const Grid &g) {
    // Rt + Tu (I - R Rb)^-1 R Td
    Op inner = inverse_one_minus(mul(R, top.Rb, g), g);
    Op path = mul(top.Tu, mul(inner, mul(R, top.Td, g), g), g);
    return add(top.Rt, path);
}

LayerOperators add_layers(const LayerOperators &a, const LayerOperators &b, const Grid &g) {
    // Downward radiance between the two per unit incident from above: (I - a.Rb b.Rt)^-1 a.Td;
    // upward radiance there per unit incident from below: (I - b.Rt a.Rb)^-1 b.Tu.
    Op down = mul(inverse_one_minus(mul(a.Rb, b.Rt, g), g), a.Td, g);
    Op up = mul(inverse_one_minus(mul(b.Rt, a.Rb, g), g), b.Tu, g);
    LayerOperators r;
    r.Rt = add(a.Rt, mul(a.Tu, mul(b.Rt, down, g), g));
    r.Td = mul(b.Td, down, g);
    r.Rb = add(b.Rb, mul(b.Td, mul(a.Rb, up, g), g));
    r.Tu = mul(a.Tu, up, g);
    return r;
}

void double_symmetric(Op &R, Op &T, const Grid &g) {
    Op S = inverse_one_minus(mul(R, R, g), g);
    Op ST = mul(S, T, g);
    Op SRT = mul(S, mul(R, T, g), g);
    Op T2 = mul(T, ST, g);
    R = add(R, mul(T, SRT, g));
    T = std::move(T2);
}

} // namespace bsdflab::ad
