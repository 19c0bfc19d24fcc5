// exp and cos over arrays of doubles, for the per-channel loops of the layered walk
// (transmittances, flight weights) and of thin films (Airy phases): with 81 wavelengths
// these were a third of a snake walk's time (docs/estimators.md, "Profile").
//
// On x86-64 glibc they call libmvec, glibc's vector math library (2-wide SSE2 kernels,
// max error 4 ulp, IEEE special values: exp(-inf) = 0, NaN in NaN out), two values per
// call; elsewhere, and for an odd last value, the scalar std::exp / std::cos. Results are
// the same whichever compiler builds the core (both call the same library).
#pragma once

namespace bsdflab {

// y[i] = exp(x[i]) for i < n; x and y may be the same array.
void exp_array(const double *x, double *y, int n);

// y[i] = cos(x[i]) for i < n; x and y may be the same array.
void cos_array(const double *x, double *y, int n);

} // namespace bsdflab
