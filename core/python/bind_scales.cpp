// Bindings of the hexagonal scale texture: parameters, the texture (shared with the
// renderer's materials), a vectorised lookup and the lattice's centres and ids for tests.
#include "arrays.h"
#include "bsdflab/parallel.h"
#include "bsdflab/scale_texture.h"

namespace py = pybind11;
using namespace bsdflab;
using namespace bsdflab::py_helpers;

// Looks up every (u[i], v[i]); returns (gap, id, slope_u, slope_v, thickness_factor,
// edge_distance) as 1-D arrays.
static py::tuple lookup_many(const ScaleTexture &t, const Darr &u, const Darr &v) {
    if (u.ndim() != 1 || v.ndim() != 1 || u.shape(0) != v.shape(0))
        throw std::invalid_argument("u and v must be 1-D arrays of the same length");
    std::size_t n = u.shape(0);
    py::array_t<bool> gap(n);
    py::array_t<uint64_t> id(n);
    py::array_t<double> slope_u(n), slope_v(n), thickness(n), edge(n);
    const double *pu = u.data(), *pv = v.data();
    bool *pg = gap.mutable_data();
    uint64_t *pid = id.mutable_data();
    double *psu = slope_u.mutable_data(), *psv = slope_v.mutable_data(), *pt = thickness.mutable_data(),
           *pe = edge.mutable_data();
    {
        py::gil_scoped_release nogil;
        parallel_for(n, kGrain, [&](std::size_t s, std::size_t e) {
            for (std::size_t i = s; i < e; ++i) {
                ScaleSample r = t.lookup(pu[i], pv[i]);
                pg[i] = r.gap;
                pid[i] = r.id;
                psu[i] = r.slope_u;
                psv[i] = r.slope_v;
                pt[i] = r.thickness_factor;
                pe[i] = r.edge_distance;
            }
        });
    }
    return py::make_tuple(gap, id, slope_u, slope_v, thickness, edge);
}

void bind_scales(py::module_ &m) {
    py::class_<ScaleParams>(m, "ScaleParams")
        .def(py::init<>())
        .def_readwrite("scales_per_unit_u", &ScaleParams::scales_per_unit_u)
        .def_readwrite("scales_around", &ScaleParams::scales_around)
        .def_readwrite("gap", &ScaleParams::gap)
        .def_readwrite("jitter", &ScaleParams::jitter)
        .def_readwrite("dome", &ScaleParams::dome)
        .def_readwrite("tilt_deg", &ScaleParams::tilt_deg)
        .def_readwrite("thickness_jitter", &ScaleParams::thickness_jitter)
        .def_readwrite("seed", &ScaleParams::seed)
        .def_readwrite("periodic_v", &ScaleParams::periodic_v);

    py::class_<ScaleTexture, std::shared_ptr<ScaleTexture>>(m, "ScaleTexture")
        .def(py::init<const ScaleParams &>(), py::arg("params"))
        .def_property_readonly("params", &ScaleTexture::params)
        .def("lookup", &lookup_many, py::arg("u"), py::arg("v"),
             "(gap, id, slope_u, slope_v, thickness_factor, edge_distance), each shape (N,)")
        .def(
            "scale_centre",
            [](const ScaleTexture &t, int64_t i, int64_t j) {
                double u, v;
                t.centre(i, j, u, v);
                return py::make_tuple(u, v);
            },
            py::arg("i"), py::arg("j"), "jittered centre (u, v) of the scale in row i, column j")
        .def("scale_id", &ScaleTexture::scale_id, py::arg("i"), py::arg("j"),
             "id of the scale in row i, column j");
}
