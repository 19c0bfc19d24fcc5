// bsdflab._core.FitForwardModel: the fitting forward model (fit_forward.h) over numpy arrays.
#include <vector>
#include "arrays.h"
#include "bsdflab/fit_forward.h"

namespace py = pybind11;
using namespace bsdflab;
using namespace bsdflab::py_helpers;
using Iarr = py::array_t<int, py::array::c_style | py::array::forcecast>;

namespace {

std::vector<double> to_vector(const Darr &a) { return {a.data(), a.data() + a.size()}; }

fit::ForwardModel make_model(const Darr &wavelengths, const Iarr &geometry, const Iarr &wavelength_index,
                             const Darr &cos_in, const Darr &cos_out, const Darr &gh_x, const Darr &gh_w,
                             const Darr &gl_x, const Darr &gl_w) {
    const py::ssize_t n = geometry.size();
    if (wavelength_index.size() != n || cos_in.size() != n || cos_out.size() != n)
        throw std::invalid_argument(
            "geometry, wavelength_index, cos_in and cos_out must have one entry per row");
    std::vector<fit::Observation> rows(static_cast<std::size_t>(n));
    for (py::ssize_t i = 0; i < n; ++i)
        rows[i] = {geometry.data()[i], wavelength_index.data()[i], cos_in.data()[i], cos_out.data()[i]};
    return fit::ForwardModel(to_vector(wavelengths), std::move(rows), to_vector(gh_x), to_vector(gh_w),
                             to_vector(gl_x), to_vector(gl_w));
}

py::array_t<double> evaluate(const fit::ForwardModel &model, const Darr &params) {
    if (params.ndim() != 2 || params.shape(1) != fit::kParamCount)
        throw std::invalid_argument("params must have shape (P, " + std::to_string(fit::kParamCount) + ")");
    const std::size_t count = params.shape(0);
    py::array_t<double> out({count, model.rows()});
    double *o = out.mutable_data();
    const double *p = params.data();
    {
        py::gil_scoped_release nogil;
        model.evaluate(p, count, o);
    }
    return out;
}

} // namespace

void bind_fit(py::module_ &m) {
    py::class_<fit::ForwardModel>(m, "FitForwardModel",
                                  "Deterministic reflectance forward model of bsdflab.fit (fit_forward.h).")
        .def(py::init(&make_model), py::arg("wavelengths"), py::arg("geometry"), py::arg("wavelength_index"),
             py::arg("cos_in"), py::arg("cos_out"), py::arg("gh_x"), py::arg("gh_w"), py::arg("gl_x"),
             py::arg("gl_w"))
        .def_property_readonly("rows", &fit::ForwardModel::rows)
        .def_property_readonly_static("param_count", [](py::object) { return int(fit::kParamCount); })
        .def("evaluate", &evaluate, py::arg("params"),
             "Observables (P, rows) for parameter sets (P, param_count); NaN outside the domain.");
}
