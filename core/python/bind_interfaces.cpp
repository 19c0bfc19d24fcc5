// Bindings of Fresnel terms and the smooth / rough interface BSDFs built from them.
#include <array>
#include <cmath>
#include <pybind11/complex.h>
#include <pybind11/stl.h>
#include "arrays.h"
#include "bsdflab/interfaces.h"
#include "bsdflab/tabulated_term.h"

namespace py = pybind11;
using namespace bsdflab;
using cvec = std::vector<std::complex<double>>;

void bind_interfaces(py::module_ &m) {
    py::class_<FresnelTerm, std::shared_ptr<FresnelTerm>>(m, "FresnelTerm")
        .def_property_readonly("eta", &FresnelTerm::eta)
        .def_property_readonly("transmissive", &FresnelTerm::transmissive)
        .def(
            "eval",
            [](const FresnelTerm &t, double cos_i, double thickness) {
                std::vector<double> R(t.channels()), T(t.channels());
                Query q;
                q.film_thickness_nm = thickness;
                t.eval(cos_i, q, R.data(), T.data());
                return py::make_tuple(R, T);
            },
            py::arg("cos_i"), py::arg("thickness_nm") = -1.0, "(R, T) per channel");
    py::class_<DielectricTerm, FresnelTerm, std::shared_ptr<DielectricTerm>>(m, "DielectricTerm")
        .def(py::init<int, double, double>(), py::arg("channels"), py::arg("int_ior"), py::arg("ext_ior"));
    py::class_<ConductorTerm, FresnelTerm, std::shared_ptr<ConductorTerm>>(m, "ConductorTerm")
        .def(py::init<cvec, double>(), py::arg("n_int"), py::arg("ext_ior"));
    py::class_<TabulatedTerm, FresnelTerm, std::shared_ptr<TabulatedTerm>>(m, "TabulatedTerm")
        .def(py::init<std::vector<std::vector<double>>>(), py::arg("reflectance"));
    py::class_<FilmTerm, FresnelTerm, std::shared_ptr<FilmTerm>>(m, "FilmTerm")
        .def(py::init<std::vector<double>, double, std::vector<cvec>, std::vector<double>, cvec, bool>(),
             py::arg("wavelengths"), py::arg("ext_ior"), py::arg("layer_n"), py::arg("layer_d_nm"),
             py::arg("n_substrate"), py::arg("substrate_transmits"));

    py::class_<SmoothInterface, BSDF, std::shared_ptr<SmoothInterface>>(m, "SmoothInterface")
        .def(py::init<std::vector<double>, std::shared_ptr<const FresnelTerm>, bool>(),
             py::arg("wavelengths"), py::arg("term"), py::arg("two_sided"));
    py::class_<RoughInterface, BSDF, std::shared_ptr<RoughInterface>>(m, "RoughInterface")
        .def(py::init([](std::vector<double> wl, std::shared_ptr<const FresnelTerm> term, double alpha,
                         bool two_sided, const std::string &distribution, bool multiscatter) {
                 MicrofacetType type;
                 if (distribution == "ggx") type = MicrofacetType::GGX;
                 else if (distribution == "beckmann") type = MicrofacetType::Beckmann;
                 else throw std::invalid_argument("distribution must be 'ggx' or 'beckmann'");
                 py::gil_scoped_release release; // the energy tables take a moment
                 return std::make_shared<RoughInterface>(std::move(wl), std::move(term), alpha, two_sided,
                                                         type, multiscatter);
             }),
             py::arg("wavelengths"), py::arg("term"), py::arg("alpha"), py::arg("two_sided"),
             py::arg("distribution") = "ggx", py::arg("multiscatter") = false)
        .def_property_readonly("pass_through", &RoughInterface::pass_through)
        .def(
            "single_scattering_albedo",
            [](const RoughInterface &r, int side, double mu) {
                const MultiScatter *ms = r.multiscatter();
                if (!ms)
                    throw std::invalid_argument("only an energy-compensated interface has albedo tables");
                std::vector<double> out(r.channels());
                for (int c = 0; c < r.channels(); ++c) out[c] = ms->albedo(side, mu, c);
                return out;
            },
            py::arg("side"), py::arg("mu"),
            "the tabulated single-scattering albedo per channel (side 0 above, 1 below)");
    // Scalar access to the distributions, for tests against quadrature.
    auto distribution = [](const std::string &name, double alpha) {
        if (name != "ggx" && name != "beckmann")
            throw std::invalid_argument("distribution must be 'ggx' or 'beckmann'");
        if (!(alpha > 0) || !std::isfinite(alpha)) throw std::invalid_argument("alpha must be > 0");
        return Microfacet(name == "ggx" ? MicrofacetType::GGX : MicrofacetType::Beckmann, alpha);
    };
    m.def(
        "microfacet_d",
        [distribution](const std::string &name, double alpha, std::array<double, 3> v) {
            return distribution(name, alpha).D(Vec3{v[0], v[1], v[2]});
        },
        py::arg("distribution"), py::arg("alpha"), py::arg("m"), "D(m) of a unit normal");
    m.def(
        "microfacet_lambda",
        [distribution](const std::string &name, double alpha, std::array<double, 3> v) {
            return distribution(name, alpha).Lambda(Vec3{v[0], v[1], v[2]});
        },
        py::arg("distribution"), py::arg("alpha"), py::arg("v"), "Smith's Lambda of a direction");
}
