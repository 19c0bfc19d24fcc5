#include "bsdflab/vector_math.h"
#include <cmath>

#if defined(BSDFLAB_LIBMVEC)
#include <emmintrin.h>
// glibc's SSE2 variants under their vector-ABI names (math.h declares them only with
// -ffast-math, which the core does not use).
extern "C" __m128d _ZGVbN2v_exp(__m128d);
extern "C" __m128d _ZGVbN2v_cos(__m128d);
#endif

namespace bsdflab {

void exp_array(const double *x, double *y, int n) {
    int i = 0;
#if defined(BSDFLAB_LIBMVEC)
    for (; i + 2 <= n; i += 2) _mm_storeu_pd(y + i, _ZGVbN2v_exp(_mm_loadu_pd(x + i)));
#endif
    for (; i < n; ++i) y[i] = std::exp(x[i]);
}

void cos_array(const double *x, double *y, int n) {
    int i = 0;
#if defined(BSDFLAB_LIBMVEC)
    for (; i + 2 <= n; i += 2) _mm_storeu_pd(y + i, _ZGVbN2v_cos(_mm_loadu_pd(x + i)));
#endif
    for (; i < n; ++i) y[i] = std::cos(x[i]);
}

} // namespace bsdflab
