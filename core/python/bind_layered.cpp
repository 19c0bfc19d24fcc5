// Bindings of the layered PFMC BSDF: construction from boundary BSDFs and slabs, plus the
// estimator's extra entry points (explicit effort and seed, standard error, the count of
// non-finite walks, the delta lobe) and its scattered part (the model without the top's
// own reflection).
#include <pybind11/stl.h>
#include <atomic>
#include "arrays.h"
#include "bsdflab/estimate.h"
#include "bsdflab/layered.h"
#include "bsdflab/parallel.h"
#include "bsdflab/walk_statistics.h"

namespace py = pybind11;
using namespace bsdflab;
using namespace bsdflab::py_helpers;

static Query query_of(const Darr &t, std::size_t i) {
    Query q;
    if (t.size() > 0) q.film_thickness_nm = t.data()[i];
    return q;
}

// (value, standard error, non-finite walks) of any stochastic model, for N pairs.
static py::tuple estimate_many(const BSDF &model, const Darr &wi, const Darr &wo, uint32_t lobes,
                               const py::object &thickness, int samples, uint64_t seed, int error_walks) {
    const StochasticEstimator *est = model.stochastic();
    if (!est) throw std::invalid_argument("this model is not stochastic");
    require_rows3(wi, "wi");
    require_rows3(wo, "wo");
    std::size_t n = wi.shape(0), C = model.channels();
    if (static_cast<std::size_t>(wo.shape(0)) != n)
        throw std::invalid_argument("wi and wo must have the same length");
    if (samples < 1) throw std::invalid_argument("samples must be >= 1");
    if (error_walks < 0) throw std::invalid_argument("error_walks must be >= 0");
    Darr t = thickness.is_none() ? Darr() : py::cast<Darr>(thickness);
    if (t.size() > 0 && static_cast<std::size_t>(t.size()) != n)
        throw std::invalid_argument("thickness must have shape (N,)");
    py::array_t<double> out({n, C}), err({n, C});
    const double *pi = wi.data(), *po = wo.data();
    double *o = out.mutable_data(), *e = err.mutable_data();
    std::atomic<std::uint64_t> nonfinite{0}, capped{0};
    {
        py::gil_scoped_release nogil;
        // Each pair is a whole Monte Carlo estimate: parallelise from a single pair up.
        parallel_for(n, 1, [&](std::size_t s, std::size_t end) {
            ThreadWorkspace lease;
            std::uint64_t bad = 0, cut = 0;
            EstimateRequest req{samples, seed};
            req.capped = &cut;
            req.error_walks = error_walks;
            for (std::size_t i = s; i < end; ++i)
                bad += estimate_pooled(*est, row(pi, i), row(po, i), lobes, query_of(t, i), req,
                                       static_cast<int>(C), lease.get(), o + i * C, e + i * C);
            nonfinite += bad;
            capped += cut;
        });
    }
    return py::make_tuple(out, err, static_cast<std::uint64_t>(nonfinite),
                          static_cast<std::uint64_t>(capped));
}

static py::array_t<double> delta_reflectance_many(const LayeredBSDF &b, const Darr &wi,
                                                  const py::object &thickness) {
    require_rows3(wi, "wi");
    std::size_t n = wi.shape(0), C = b.channels();
    Darr t = thickness.is_none() ? Darr() : py::cast<Darr>(thickness);
    py::array_t<double> out({n, C});
    double *o = out.mutable_data();
    for (std::size_t i = 0; i < n; ++i) b.delta_reflectance(row(wi.data(), i), query_of(t, i), o + i * C);
    return out;
}

void bind_layered(py::module_ &m) {
    m.attr("estimator_version") = kEstimatorVersion;
    // Keyword-only: the walk options by name, never by position.
    py::class_<LayeredOptions>(m, "LayeredOptions")
        .def(
            py::init([](int samples, uint64_t seed, int max_depth, bool nee, int pdf_samples, int estimator) {
                if (samples < 1 || max_depth < 1)
                    throw std::invalid_argument("samples and max_depth must be >= 1");
                if (pdf_samples < 0) throw std::invalid_argument("pdf_samples must be >= 0");
                if (estimator != kEstimatorPfmc && estimator != kEstimatorPfmc2)
                    throw std::invalid_argument("unknown estimator");
                return LayeredOptions{samples, seed, max_depth, nee, pdf_samples, estimator};
            }),
            py::kw_only(), py::arg("samples"), py::arg("seed"), py::arg("max_depth"), py::arg("nee") = true,
            py::arg("pdf_samples") = 1, py::arg("estimator") = kEstimatorPfmc2)
        .def_readonly("samples", &LayeredOptions::samples)
        .def_readonly("seed", &LayeredOptions::seed)
        .def_readonly("max_depth", &LayeredOptions::max_depth)
        .def_readonly("nee", &LayeredOptions::nee)
        .def_readonly("pdf_samples", &LayeredOptions::pdf_samples)
        .def_readonly("estimator", &LayeredOptions::estimator);

    py::class_<LayeredBSDF, BSDF, std::shared_ptr<LayeredBSDF>>(m, "LayeredBSDF")
        .def(py::init([](std::vector<double> wavelengths, std::vector<std::shared_ptr<BSDF>> boundaries,
                         std::vector<double> thickness, std::vector<std::vector<double>> sigma_a,
                         std::vector<double> sigma_s, std::vector<int> phase_kind,
                         std::vector<double> phase_param, const LayeredOptions &options) {
                 std::size_t K = thickness.size();
                 if (sigma_a.size() != K || sigma_s.size() != K || phase_kind.size() != K ||
                     phase_param.size() != K)
                     throw std::invalid_argument("slab parameter lists must have equal length");
                 std::vector<Slab> slabs(K);
                 for (std::size_t j = 0; j < K; ++j) {
                     if (phase_kind[j] < 0 || phase_kind[j] > 2)
                         throw std::invalid_argument("unknown phase function");
                     slabs[j] = Slab{thickness[j], sigma_a[j], sigma_s[j],
                                     PhaseFunction(PhaseFunction::Kind(phase_kind[j]), phase_param[j])};
                 }
                 std::vector<std::shared_ptr<const BSDF>> b(boundaries.begin(), boundaries.end());
                 return std::make_shared<LayeredBSDF>(std::move(wavelengths), std::move(b), std::move(slabs),
                                                      options);
             }),
             py::arg("wavelengths"), py::arg("boundaries"), py::kw_only(), py::arg("thickness_um"),
             py::arg("sigma_a"), py::arg("sigma_s"), py::arg("phase_kind"), py::arg("phase_param"),
             py::arg("options"))
        .def("estimate", &estimate_many, py::arg("wi"), py::arg("wo"), py::arg("lobes"),
             py::arg("thickness_nm"), py::arg("samples"), py::arg("seed"), py::arg("error_walks") = 0,
             "(value, stderr, non-finite walk count, capped walk count) with an explicit effort and seed;\n"
             "error_walks > 0 pools the error with that many extra walks (walk_statistics.h)")
        .def_property_readonly("capped_walks", &LayeredBSDF::capped_walks,
                               "walks of eval(), sample() and pdf() cut by max_depth since construction")
        .def("delta_reflectance", &delta_reflectance_many, py::arg("wi"),
             py::arg("thickness_nm") = py::none())
        .def(
            "scattered_part",
            [](const std::shared_ptr<LayeredBSDF> &self) { return std::make_shared<ScatteredPart>(self); },
            "the model without its top boundary's own reflection (a stochastic BSDF)");

    py::class_<ScatteredPart, BSDF, std::shared_ptr<ScatteredPart>>(m, "LayeredScatteredPart")
        .def("estimate", &estimate_many, py::arg("wi"), py::arg("wo"), py::arg("lobes"),
             py::arg("thickness_nm"), py::arg("samples"), py::arg("seed"), py::arg("error_walks") = 0,
             "(value, stderr, non-finite walk count, capped walk count) with an explicit effort and seed;\n"
             "error_walks > 0 pools the error with that many extra walks (walk_statistics.h)");
}
