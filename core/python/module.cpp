// Entry point of bsdflab._core: one bind_* function per header group.
#include <pybind11/pybind11.h>
#include "bsdflab/parallel.h"

namespace py = pybind11;
void bind_adding_doubling(py::module_ &m);
void bind_bsdf(py::module_ &m);
void bind_fit(py::module_ &m);
void bind_fit_instrument(py::module_ &m);
void bind_fresnel(py::module_ &m);
void bind_interfaces(py::module_ &m);
void bind_layered(py::module_ &m);
void bind_measured(py::module_ &m);
void bind_render(py::module_ &m);
void bind_scales(py::module_ &m);
void bind_tables(py::module_ &m);
void bind_thin_film(py::module_ &m);

PYBIND11_MODULE(_core, m) {
    m.doc() = "bsdflab C++ core: optics, BSDFs and estimators (vectorised, GIL released)";
    m.def("worker_count", &bsdflab::worker_count, "threads used by parallel loops");
    bind_adding_doubling(m);
    bind_bsdf(m);
    bind_fit(m);
    bind_fit_instrument(m);
    bind_fresnel(m);
    bind_interfaces(m);
    bind_layered(m);
    bind_measured(m);
    bind_render(m);
    bind_scales(m);
    bind_tables(m);
    bind_thin_film(m);
}
