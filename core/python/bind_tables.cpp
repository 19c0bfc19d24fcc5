// Bindings of the tabulator (a job object so Python can show progress and cancel) and of
// the table BSDF.
#include <pybind11/stl.h>
#include "arrays.h"
#include "bsdflab/projected_term.h"
#include "bsdflab/table_bsdf.h"
#include "bsdflab/tabulation.h"

namespace py = pybind11;
using namespace bsdflab;

static TableGrid make_grid(int n_lobes, int n_theta_i, int n_theta_o, int n_phi,
                           std::vector<double> thickness) {
    if (n_lobes < 1 || n_lobes > 2 || n_theta_i < 2 || n_theta_o < 2 || n_phi < 2)
        throw std::invalid_argument("bad table grid");
    TableGrid g;
    g.n_lobes = n_lobes;
    g.n_theta_i = n_theta_i;
    g.n_theta_o = n_theta_o;
    g.n_phi = n_phi;
    g.thickness = thickness.empty() ? std::vector<double>{-1.0} : std::move(thickness);
    return g;
}

void bind_tables(py::module_ &m) {
    py::class_<TabulationJob, std::shared_ptr<TabulationJob>>(m, "TabulationJob")
        .def(py::init([](std::shared_ptr<BSDF> model, int n_lobes, int n_theta_i, int n_theta_o,
                         int n_phi, std::vector<double> thickness, std::vector<double> P, int rows,
                         double rel_error, double floor, int min_samples, int max_samples,
                         uint64_t seed, bool split_direct) {
                 TabulationSettings s{rel_error, floor, min_samples, max_samples, seed, split_direct};
                 return std::make_shared<TabulationJob>(
                     model, make_grid(n_lobes, n_theta_i, n_theta_o, n_phi, std::move(thickness)),
                     std::move(P), rows, s);
             }),
             py::arg("model"), py::arg("n_lobes"), py::arg("n_theta_i"), py::arg("n_theta_o"),
             py::arg("n_phi"), py::arg("thickness"), py::arg("P"), py::arg("rows"),
             py::arg("rel_error"), py::arg("floor"), py::arg("min_samples"), py::arg("max_samples"),
             py::arg("seed"), py::arg("split_direct"))
        .def("run", &TabulationJob::run, py::call_guard<py::gil_scoped_release>(),
             "tabulate (blocking, GIL released)")
        .def("cancel", &TabulationJob::cancel)
        .def_property_readonly("cancelled", &TabulationJob::cancelled)
        .def_property_readonly("done", &TabulationJob::done)
        .def_property_readonly("total", &TabulationJob::total)
        .def_property_readonly("value", [](const TabulationJob &j) {
            return py::array_t<double>(j.value.size(), j.value.data());
        })
        .def_property_readonly("error", [](const TabulationJob &j) {
            return py::array_t<double>(j.error.size(), j.error.data());
        })
        .def_property_readonly("lum_value", [](const TabulationJob &j) {
            return py::array_t<double>(j.lum_value.size(), j.lum_value.data());
        })
        .def_property_readonly("lum_error", [](const TabulationJob &j) {
            return py::array_t<double>(j.lum_error.size(), j.lum_error.data());
        })
        .def_property_readonly("samples", [](const TabulationJob &j) {
            return py::array_t<int>(j.samples.size(), j.samples.data());
        });

    py::class_<TabulatedBSDF, BSDF, std::shared_ptr<TabulatedBSDF>>(m, "TabulatedBSDF")
        .def(py::init([](std::vector<double> channel_ids, int n_lobes, int n_theta_i, int n_theta_o,
                         int n_phi, std::vector<double> thickness, std::vector<float> values,
                         std::vector<double> luminance, std::shared_ptr<BSDF> direct,
                         std::vector<double> P, double default_thickness, double transmission_eta) {
                 return std::make_shared<TabulatedBSDF>(
                     std::move(channel_ids), make_grid(n_lobes, n_theta_i, n_theta_o, n_phi, std::move(thickness)),
                     std::move(values), std::move(luminance), direct, std::move(P), default_thickness,
                     transmission_eta);
             }),
             py::arg("channel_ids"), py::arg("n_lobes"), py::arg("n_theta_i"), py::arg("n_theta_o"),
             py::arg("n_phi"), py::arg("thickness"), py::arg("values"), py::arg("luminance"),
             py::arg("direct"), py::arg("P"), py::arg("default_thickness"), py::arg("transmission_eta") = 1.0);

    py::class_<ProjectedFresnelTerm, FresnelTerm, std::shared_ptr<ProjectedFresnelTerm>>(m, "ProjectedFresnelTerm")
        .def(py::init<std::shared_ptr<const FresnelTerm>, std::vector<double>, int, double, double, double, int,
                      int>(),
             py::arg("exact"), py::arg("P"), py::arg("out_channels"), py::arg("thickness_lo"),
             py::arg("thickness_hi"), py::arg("default_thickness"), py::arg("n_cos"), py::arg("n_thickness"))
        .def_property_readonly("n_cos", &ProjectedFresnelTerm::n_cos)
        .def_property_readonly("n_thickness", &ProjectedFresnelTerm::n_thickness);
}
