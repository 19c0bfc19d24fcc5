// Bindings of Fresnel terms and the smooth / rough interface BSDFs built from them.
#include <pybind11/complex.h>
#include <pybind11/stl.h>
#include "arrays.h"
#include "bsdflab/interfaces.h"

namespace py = pybind11;
using namespace bsdflab;
using cvec = std::vector<std::complex<double>>;

void bind_interfaces(py::module_ &m) {
    py::class_<FresnelTerm, std::shared_ptr<FresnelTerm>>(m, "FresnelTerm")
        .def_property_readonly("eta", &FresnelTerm::eta)
        .def_property_readonly("transmissive", &FresnelTerm::transmissive)
        .def("eval",
             [](const FresnelTerm &t, double cos_i, double thickness) {
                 std::vector<double> R(t.channels()), T(t.channels());
                 Query q;
                 q.film_thickness_nm = thickness;
                 t.eval(cos_i, q, R.data(), T.data());
                 return py::make_tuple(R, T);
             },
             py::arg("cos_i"), py::arg("thickness") = -1.0, "(R, T) per channel");
    py::class_<DielectricTerm, FresnelTerm, std::shared_ptr<DielectricTerm>>(m, "DielectricTerm")
        .def(py::init<int, double, double>(), py::arg("channels"), py::arg("int_ior"), py::arg("ext_ior"));
    py::class_<ConductorTerm, FresnelTerm, std::shared_ptr<ConductorTerm>>(m, "ConductorTerm")
        .def(py::init<cvec, double>(), py::arg("n_int"), py::arg("ext_ior"));
    py::class_<FilmTerm, FresnelTerm, std::shared_ptr<FilmTerm>>(m, "FilmTerm")
        .def(py::init<std::vector<double>, double, std::vector<cvec>, std::vector<double>, cvec, bool>(),
             py::arg("wavelengths"), py::arg("ext_ior"), py::arg("layer_n"), py::arg("layer_d_nm"),
             py::arg("n_substrate"), py::arg("substrate_transmits"));

    py::class_<SmoothInterface, BSDF, std::shared_ptr<SmoothInterface>>(m, "SmoothInterface")
        .def(py::init<std::vector<double>, std::shared_ptr<const FresnelTerm>, bool>(),
             py::arg("wavelengths"), py::arg("term"), py::arg("two_sided"));
    py::class_<RoughInterface, BSDF, std::shared_ptr<RoughInterface>>(m, "RoughInterface")
        .def(py::init<std::vector<double>, std::shared_ptr<const FresnelTerm>, double, bool>(),
             py::arg("wavelengths"), py::arg("term"), py::arg("alpha"), py::arg("two_sided"));
}
