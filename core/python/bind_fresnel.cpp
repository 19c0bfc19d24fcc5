// Vectorised Fresnel coefficients over 1-D arrays of equal length (Python broadcasts).
#include <complex>
#include "arrays.h"
#include "bsdflab/complex_fresnel.h"
#include "bsdflab/parallel.h"

namespace py = pybind11;
using namespace bsdflab;
using namespace bsdflab::py_helpers;
using Carr = py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>;

static py::tuple amplitudes_many(const Carr &n_i, const Carr &n_t, const Carr &cos_i) {
    std::size_t n = n_i.size();
    if (n_t.size() != static_cast<py::ssize_t>(n) || cos_i.size() != static_cast<py::ssize_t>(n))
        throw std::invalid_argument("n_i, n_t and cos_i must have the same length");
    py::array_t<cplx> rs(n), rp(n), ts(n), tp(n), ct(n);
    const cplx *a = n_i.data(), *b = n_t.data(), *c = cos_i.data();
    cplx *prs = rs.mutable_data(), *prp = rp.mutable_data(), *pts = ts.mutable_data(),
         *ptp = tp.mutable_data(), *pct = ct.mutable_data();
    {
        py::gil_scoped_release nogil;
        parallel_for(n, kGrain, [&](std::size_t s, std::size_t e) {
            for (std::size_t i = s; i < e; ++i) {
                FresnelAmplitudes f = fresnel_amplitudes(a[i], b[i], c[i]);
                prs[i] = f.r_s;
                prp[i] = f.r_p;
                pts[i] = f.t_s;
                ptp[i] = f.t_p;
                pct[i] = f.cos_t;
            }
        });
    }
    return py::make_tuple(rs, rp, ts, tp, ct);
}

void bind_fresnel(py::module_ &m) {
    m.def("fresnel_amplitudes", &amplitudes_many, py::arg("n_i"), py::arg("n_t"), py::arg("cos_i"),
          "(r_s, r_p, t_s, t_p, cos_t) complex arrays");
}
