// Vectorised bindings of the BSDF interface: every call takes (N, 3) arrays, releases the
// GIL and runs in parallel over N. Subclasses inherit these methods from `BSDF`.
#include <pybind11/stl.h>
#include "arrays.h"
#include "bsdflab/basic_bsdfs.h"
#include "bsdflab/parallel.h"

namespace py = pybind11;
using namespace bsdflab;
using namespace bsdflab::py_helpers;

// Optional per-row film thickness (nm); None -> every row uses the model's default.
static Darr thickness_rows(const py::object &thickness, std::size_t n) {
    if (thickness.is_none()) return Darr();
    Darr t = py::cast<Darr>(thickness);
    if (t.ndim() != 1 || static_cast<std::size_t>(t.shape(0)) != n)
        throw std::invalid_argument("thickness must have shape (N,)");
    return t;
}

static Query query_row(const Darr &t, std::size_t i) {
    Query q;
    if (t.size() > 0) q.film_thickness_nm = t.data()[i];
    return q;
}

static py::array_t<double> eval_many(const BSDF &b, const Darr &wi, const Darr &wo, uint32_t lobes,
                                     const py::object &thickness) {
    require_rows3(wi, "wi");
    require_rows3(wo, "wo");
    if (wi.shape(0) != wo.shape(0)) throw std::invalid_argument("wi and wo must have the same length");
    std::size_t n = wi.shape(0), C = b.channels();
    Darr t = thickness_rows(thickness, n);
    py::array_t<double> out({n, C});
    const double *pi = wi.data(), *po = wo.data();
    double *o = out.mutable_data();
    {
        py::gil_scoped_release nogil;
        parallel_for(n, kGrain, [&](std::size_t s, std::size_t e) {
            for (std::size_t i = s; i < e; ++i)
                b.eval(row(pi, i), row(po, i), lobes, query_row(t, i), o + i * C);
        });
    }
    return out;
}

static py::array_t<double> pdf_many(const BSDF &b, const Darr &wi, const Darr &wo, uint32_t lobes,
                                    const py::object &thickness) {
    require_rows3(wi, "wi");
    require_rows3(wo, "wo");
    if (wi.shape(0) != wo.shape(0)) throw std::invalid_argument("wi and wo must have the same length");
    std::size_t n = wi.shape(0);
    Darr t = thickness_rows(thickness, n);
    py::array_t<double> out(n);
    const double *pi = wi.data(), *po = wo.data();
    double *o = out.mutable_data();
    {
        py::gil_scoped_release nogil;
        parallel_for(n, kGrain, [&](std::size_t s, std::size_t e) {
            for (std::size_t i = s; i < e; ++i) o[i] = b.pdf(row(pi, i), row(po, i), lobes, query_row(t, i));
        });
    }
    return out;
}

static py::tuple sample_many(const BSDF &b, const Darr &wi, const Darr &u1, const Darr &u2, uint32_t lobes,
                             const py::object &thickness) {
    require_rows3(wi, "wi");
    std::size_t n = wi.shape(0), C = b.channels();
    if (u1.ndim() != 1 || static_cast<std::size_t>(u1.shape(0)) != n)
        throw std::invalid_argument("u1 must have shape (N,)");
    if (u2.ndim() != 2 || static_cast<std::size_t>(u2.shape(0)) != n || u2.shape(1) != 2)
        throw std::invalid_argument("u2 must have shape (N, 2)");
    Darr t = thickness_rows(thickness, n);
    py::array_t<double> wo({n, std::size_t(3)}), weight({n, C}), pdf(n), eta(n);
    py::array_t<uint32_t> lobe(n);
    const double *pi = wi.data(), *pu1 = u1.data(), *pu2 = u2.data();
    double *pwo = wo.mutable_data(), *pw = weight.mutable_data(), *pp = pdf.mutable_data(),
           *pe = eta.mutable_data();
    uint32_t *pl = lobe.mutable_data();
    {
        py::gil_scoped_release nogil;
        parallel_for(n, kGrain, [&](std::size_t s, std::size_t e) {
            for (std::size_t i = s; i < e; ++i) {
                BSDFSample bs = b.sample(row(pi, i), pu1[i], pu2[2 * i], pu2[2 * i + 1], lobes,
                                         query_row(t, i), pw + i * C);
                pwo[3 * i] = bs.wo.x;
                pwo[3 * i + 1] = bs.wo.y;
                pwo[3 * i + 2] = bs.wo.z;
                pp[i] = bs.pdf;
                pl[i] = bs.lobe;
                pe[i] = bs.eta;
            }
        });
    }
    return py::make_tuple(wo, weight, pdf, lobe, eta);
}

void bind_bsdf(py::module_ &m) {
    py::enum_<Lobe>(m, "LobeBits", py::arithmetic())
        .value("DiffuseReflection", kDiffuseReflection)
        .value("GlossyReflection", kGlossyReflection)
        .value("DeltaReflection", kDeltaReflection)
        .value("DiffuseTransmission", kDiffuseTransmission)
        .value("GlossyTransmission", kGlossyTransmission)
        .value("DeltaTransmission", kDeltaTransmission)
        .value("All", kAll);

    py::class_<BSDF, std::shared_ptr<BSDF>>(m, "BSDF")
        .def_property_readonly("channels", &BSDF::channels)
        .def_property_readonly("wavelengths", &BSDF::wavelengths)
        .def_property_readonly("lobes", &BSDF::lobes)
        .def("eval", &eval_many, py::arg("wi"), py::arg("wo"), py::arg("lobes") = uint32_t(kAll),
             py::arg("thickness_nm") = py::none(), "f * |cos theta_o| per channel, shape (N, C)")
        .def("pdf", &pdf_many, py::arg("wi"), py::arg("wo"), py::arg("lobes") = uint32_t(kAll),
             py::arg("thickness_nm") = py::none(), "solid-angle density of sample(), shape (N,)")
        .def("sample", &sample_many, py::arg("wi"), py::arg("u1"), py::arg("u2"),
             py::arg("lobes") = uint32_t(kAll), py::arg("thickness_nm") = py::none(),
             "(wo, weight, pdf, lobe, eta)");

    py::class_<Diffuse, BSDF, std::shared_ptr<Diffuse>>(m, "Diffuse")
        .def(py::init<std::vector<double>, std::vector<double>, bool>(), py::arg("wavelengths"),
             py::arg("reflectance"), py::arg("two_sided"));
}
