// Binding of the RGL measured material (bsdflab/measured.h). Arrays arrive as flat
// float32 lists with their shapes; eval / pdf / sample come from the BSDF base binding
// (vectorised, GIL released).
#include <pybind11/stl.h>
#include "bsdflab/measured.h"

namespace py = pybind11;
using namespace bsdflab;

void bind_measured(py::module_ &m) {
    py::class_<MeasuredBSDF, BSDF, std::shared_ptr<MeasuredBSDF>>(m, "MeasuredBSDF")
        .def(py::init([](std::vector<double> channel_ids, bool jacobian, std::vector<double> theta_i,
                         std::vector<double> phi_i, std::vector<double> channel_nodes, std::vector<float> ndf,
                         int ndf_h, int ndf_w, std::vector<float> sigma, int sigma_h, int sigma_w,
                         std::vector<float> vndf, int vndf_h, int vndf_w, std::vector<float> luminance,
                         std::vector<float> values, int n) {
                 MeasuredArrays a;
                 a.jacobian = jacobian;
                 a.theta_i = std::move(theta_i);
                 a.phi_i = std::move(phi_i);
                 a.channel_nodes = std::move(channel_nodes);
                 a.ndf = std::move(ndf);
                 a.ndf_h = ndf_h;
                 a.ndf_w = ndf_w;
                 a.sigma = std::move(sigma);
                 a.sigma_h = sigma_h;
                 a.sigma_w = sigma_w;
                 a.vndf = std::move(vndf);
                 a.vndf_h = vndf_h;
                 a.vndf_w = vndf_w;
                 a.luminance = std::move(luminance);
                 a.values = std::move(values);
                 a.n = n;
                 return std::make_shared<MeasuredBSDF>(std::move(channel_ids), a);
             }),
             py::arg("channel_ids"), py::arg("jacobian"), py::arg("theta_i"), py::arg("phi_i"),
             py::arg("channel_nodes"), py::arg("ndf"), py::arg("ndf_h"), py::arg("ndf_w"), py::arg("sigma"),
             py::arg("sigma_h"), py::arg("sigma_w"), py::arg("vndf"), py::arg("vndf_h"), py::arg("vndf_w"),
             py::arg("luminance"), py::arg("values"), py::arg("n"));

    py::class_<MerlBSDF, BSDF, std::shared_ptr<MerlBSDF>>(m, "MerlBSDF")
        .def(py::init<std::vector<float>>(), py::arg("values"),
             "values: 3 x 90 x 90 x 180 f values (1/sr), scales applied");
}
