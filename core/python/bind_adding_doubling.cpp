// Bindings of the adding-doubling solver: construction from the core BSDFs of a stack,
// and eval of direction pairs with the GIL released (the solve is threaded over
// wavelengths and Fourier orders).
#include <pybind11/stl.h>
#include "arrays.h"
#include "bsdflab/adding_doubling.h"

namespace py = pybind11;
using namespace bsdflab;
using namespace bsdflab::py_helpers;

void bind_adding_doubling(py::module_ &m) {
    py::class_<AddingDoubling, std::shared_ptr<AddingDoubling>>(m, "AddingDoubling")
        .def(py::init([](std::vector<double> wavelengths, std::vector<std::shared_ptr<BSDF>> boundaries,
                         std::vector<double> media, std::vector<double> thickness,
                         std::vector<std::vector<double>> sigma_a, std::vector<double> sigma_s,
                         std::vector<double> g, int nodes, int orders, double thin_depth,
                         double order_tolerance, int azimuth_samples, bool film_lookup, int spectral_stride,
                         double fine_step) {
                 std::size_t K = thickness.size();
                 if (sigma_a.size() != K || sigma_s.size() != K || g.size() != K)
                     throw std::invalid_argument("slab parameter lists must have equal length");
                 std::vector<ADSlab> slabs(K);
                 for (std::size_t j = 0; j < K; ++j)
                     slabs[j] = ADSlab{thickness[j], sigma_a[j], sigma_s[j], g[j]};
                 ADSettings s{nodes,           orders,      thin_depth,      order_tolerance,
                              azimuth_samples, film_lookup, spectral_stride, fine_step};
                 py::gil_scoped_release nogil;  // the film lookups take a moment
                 std::vector<std::shared_ptr<const BSDF>> b(boundaries.begin(), boundaries.end());
                 return std::make_shared<AddingDoubling>(std::move(wavelengths), std::move(b),
                                                         std::move(media), std::move(slabs), s);
             }),
             py::arg("wavelengths"), py::arg("boundaries"), py::arg("media"), py::arg("thickness_um"),
             py::arg("sigma_a"), py::arg("sigma_s"), py::arg("g"), py::arg("nodes"), py::arg("orders"),
             py::arg("thin_depth"), py::arg("order_tolerance"), py::arg("azimuth_samples"),
             py::arg("film_lookup") = false, py::arg("spectral_stride") = 1, py::arg("fine_step") = 0.25)
        .def_property_readonly("orders", &AddingDoubling::orders)
        .def_property_readonly("azimuth_samples", &AddingDoubling::azimuth_samples)
        .def_property_readonly("nodes", &AddingDoubling::nodes)
        .def_property_readonly("weights", &AddingDoubling::weights)
        .def_property_readonly("two_sided", &AddingDoubling::two_sided)
        .def_property_readonly("every_pair", &AddingDoubling::every_pair)
        .def_property_readonly("film_lookup_error", &AddingDoubling::film_lookup_error)
        .def(
            "eval",
            [](const AddingDoubling &s, const Darr &wi, const Darr &wo, bool scattered_only) {
                require_rows3(wi, "wi");
                require_rows3(wo, "wo");
                std::size_t n = wi.shape(0), C = s.channels();
                if (static_cast<std::size_t>(wo.shape(0)) != n)
                    throw std::invalid_argument("wi and wo must have the same length");
                py::array_t<double> out({n, C});
                double *o = out.mutable_data();
                {
                    py::gil_scoped_release nogil;
                    s.eval(wi.data(), wo.data(), n, o, scattered_only);
                }
                return out;
            },
            py::arg("wi"), py::arg("wo"), py::arg("scattered_only") = false,
            "f |cos theta_o| (N, C), no delta lobe: reflection from above; every pair when two_sided")
        .def(
            "with_top",
            [](const AddingDoubling &s, std::shared_ptr<BSDF> top) {
                py::gil_scoped_release nogil;
                return s.with_top(std::move(top));
            },
            py::arg("top"), "the solver with another rough top, sharing what lies below")
        .def_static("hg_orders_needed", &hg_orders_needed, py::arg("g"), py::arg("tolerance"));
}
