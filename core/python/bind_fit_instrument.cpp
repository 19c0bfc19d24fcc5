// bsdflab._core.InstrumentStack: a multilayer's specular reflectance through an instrument
// (fit_instrument.h) over numpy arrays.
#include <complex>
#include <vector>
#include "arrays.h"
#include "bsdflab/fit_instrument.h"

namespace py = pybind11;
using namespace bsdflab;
using namespace bsdflab::py_helpers;
using Carr = py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>;

namespace {

std::vector<double> to_vector(const Darr &a) { return {a.data(), a.data() + a.size()}; }

py::array_t<double> evaluate(const fit::InstrumentStack &model, const Carr &n, const Darr &wl, const Darr &d,
                             const Darr &inst) {
    const std::size_t E = model.wavelengths() * model.band_nodes();
    if (n.ndim() != 3 || n.shape(1) != static_cast<py::ssize_t>(model.media()) ||
        n.shape(2) != static_cast<py::ssize_t>(E))
        throw std::invalid_argument("n must have shape (P, media, wavelengths * band nodes)");
    const py::ssize_t P = n.shape(0);
    if (wl.ndim() != 2 || wl.shape(0) != P || wl.shape(1) != static_cast<py::ssize_t>(E))
        throw std::invalid_argument("wl must have shape (P, wavelengths * band nodes)");
    if (d.ndim() != 2 || d.shape(0) != P || d.shape(1) != static_cast<py::ssize_t>(model.layers()))
        throw std::invalid_argument("d must have shape (P, layers)");
    if (inst.ndim() != 2 || inst.shape(0) != P || inst.shape(1) != 3)
        throw std::invalid_argument("inst must have shape (P, 3)");
    py::array_t<double> out({static_cast<std::size_t>(P), model.angles(), model.wavelengths()});
    double *o = out.mutable_data();
    const cplx *pn = reinterpret_cast<const cplx *>(n.data());
    const double *pw = wl.data(), *pd = d.data(), *pi = inst.data();
    {
        py::gil_scoped_release nogil;
        model.evaluate(pn, pw, pd, pi, static_cast<std::size_t>(P), o);
    }
    return out;
}

py::array_t<double> smear(const Darr &r, const Darr &sigma, double step, std::size_t first,
                          std::size_t stride, std::size_t wavelengths, std::size_t reach) {
    if (r.ndim() != 3 || sigma.ndim() != 1 || sigma.shape(0) != r.shape(0))
        throw std::invalid_argument("r must have shape (P, angles, grid) and sigma (P,)");
    if (!(step > 0)) throw std::invalid_argument("step must be > 0");
    const std::size_t P = r.shape(0), A = r.shape(1), G = r.shape(2);
    py::array_t<double> out({P, A, wavelengths});
    double *o = out.mutable_data();
    const double *pr = r.data(), *ps = sigma.data();
    {
        py::gil_scoped_release nogil;
        fit::smear_uniform(pr, P, A, G, ps, step, first, stride, wavelengths, reach, o);
    }
    return out;
}

} // namespace

void bind_fit_instrument(py::module_ &m) {
    py::class_<fit::InstrumentStack>(
        m, "InstrumentStack",
        "Specular reflectance of a multilayer through an instrument (fit_instrument.h).")
        .def(py::init([](const Darr &angles, std::size_t wavelengths, std::size_t layers, const Darr &band_w,
                         const Darr &cone_u, const Darr &cone_w, std::size_t azimuths) {
                 return fit::InstrumentStack(to_vector(angles), wavelengths, layers, to_vector(band_w),
                                             to_vector(cone_u), to_vector(cone_w), azimuths);
             }),
             py::arg("angles_deg"), py::arg("wavelengths"), py::arg("layers"), py::arg("band_w"),
             py::arg("cone_u"), py::arg("cone_w"), py::arg("azimuths"))
        .def_property_readonly("angles", &fit::InstrumentStack::angles)
        .def_property_readonly("media", &fit::InstrumentStack::media)
        .def("evaluate", &evaluate, py::arg("n"), py::arg("wavelengths"), py::arg("d_nm"), py::arg("inst"),
             "Smeared specular reflectance (P, angles, wavelengths); NaN outside the domain.");
    m.def(
        "smear_uniform", &smear, py::arg("r"), py::arg("sigma_nm"), py::arg("step_nm"), py::arg("first"),
        py::arg("stride"), py::arg("wavelengths"), py::arg("reach"),
        "Gaussian slit on a uniform grid (fit_instrument.h): (P, angles, grid) -> (P, angles, wavelengths).");
}
