// Bindings of the tabulator (its stage functions as job objects, so Python can show
// progress and cancel, and a distributed driver can run blocks of cells) and of the
// table BSDF.
#include <pybind11/stl.h>
#include <array>
#include "arrays.h"
#include "bsdflab/film_lookup.h"
#include "bsdflab/projected_term.h"
#include "bsdflab/table_bsdf.h"
#include "bsdflab/table_delta.h"
#include "bsdflab/tabulation.h"

namespace py = pybind11;
using namespace bsdflab;

static TableGrid make_grid(int n_lobes, int n_theta_i, int n_theta_o, int n_phi,
                           std::vector<double> thickness) {
    if ((n_lobes != 1 && n_lobes != 2 && n_lobes != 4) || n_theta_i < 2 || n_theta_o < 2 || n_phi < 2)
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
    // Keyword-only structs: the settings by name, never by position.
    py::class_<TabulationSettings> settings(m, "TabulationSettings");
    // The defaults live in tabulation.h only; Python reads them from here.
    settings.attr("default_min_samples") = TabulationSettings{}.min_samples;
    settings.attr("default_max_samples") = TabulationSettings{}.max_samples;
    settings.attr("default_floor") = TabulationSettings{}.floor;
    settings
        .def(py::init([](double rel_error, double floor, int min_samples, int max_samples, uint64_t seed,
                         bool film_lookup) {
                 if (min_samples < 1 || max_samples < min_samples)
                     throw std::invalid_argument("need 1 <= min_samples <= max_samples");
                 return TabulationSettings{rel_error, floor, min_samples, max_samples, seed, film_lookup};
             }),
             py::kw_only(), py::arg("rel_error"), py::arg("floor"), py::arg("min_samples"),
             py::arg("max_samples"), py::arg("seed"), py::arg("film_lookup") = true)
        .def_readonly("rel_error", &TabulationSettings::rel_error)
        .def_readonly("floor", &TabulationSettings::floor)
        .def_readonly("min_samples", &TabulationSettings::min_samples)
        .def_readonly("max_samples", &TabulationSettings::max_samples)
        .def_readonly("seed", &TabulationSettings::seed)
        .def_readonly("film_lookup", &TabulationSettings::film_lookup);

    py::class_<Tabulator, std::shared_ptr<Tabulator>>(m, "Tabulator")
        .def(py::init([](std::shared_ptr<BSDF> model, int n_lobes, int n_theta_i, int n_theta_o, int n_phi,
                         std::vector<double> thickness, std::vector<double> P, int rows,
                         const TabulationSettings &settings) {
                 return std::make_shared<Tabulator>(
                     model, make_grid(n_lobes, n_theta_i, n_theta_o, n_phi, std::move(thickness)),
                     std::move(P), rows, settings);
             }),
             py::arg("model"), py::kw_only(), py::arg("n_lobes"), py::arg("n_theta_i"), py::arg("n_theta_o"),
             py::arg("n_phi"), py::arg("thickness_nm"), py::arg("P"), py::arg("rows"), py::arg("settings"))
        .def("with_settings", &Tabulator::with_settings, py::arg("settings"),
             "the same model, grid and film lookups (shared) with other settings")
        .def_property_readonly("settings", &Tabulator::settings)
        .def_property_readonly("cells", &Tabulator::cells)
        .def_property_readonly("film_lookup_error", &Tabulator::film_lookup_error,
                               "largest measured error of the film lookups in use (-1: none)")
        .def_property_readonly("out_channels", &Tabulator::out_channels)
        .def_property_readonly("stochastic", &Tabulator::stochastic)
        .def("floor_scale", &Tabulator::floor_scale, py::arg("lum"),
             "per-lobe mean |pilot luminance|, reduced in cell order")
        .def(
            "pilot_job",
            [](const std::shared_ptr<Tabulator> &t, std::vector<std::size_t> cells) {
                return std::make_shared<TabulationStageJob>(t, TabulationStageJob::kPilot, std::move(cells));
            },
            py::arg("cells"))
        .def(
            "finish_job",
            [](const std::shared_ptr<Tabulator> &t, std::vector<std::size_t> cells,
               std::vector<double> pilot_lum, std::vector<double> pilot_error, std::vector<double> scale,
               std::vector<double> pilot_channel_error) {
                return std::make_shared<TabulationStageJob>(t, TabulationStageJob::kFinish, std::move(cells),
                                                            std::move(pilot_lum), std::move(pilot_error),
                                                            std::move(scale), std::move(pilot_channel_error));
            },
            py::arg("cells"), py::arg("pilot_lum"), py::arg("pilot_error"), py::arg("scale"),
            py::arg("pilot_channel_error") = std::vector<double>{},
            "pilot_channel_error: the pilot job's pilot_channel_error (pooled per-channel errors)");

    auto doubles = [](const std::vector<double> &v) { return py::array_t<double>(v.size(), v.data()); };
    py::class_<TabulationStageJob, std::shared_ptr<TabulationStageJob>>(m, "TabulationStageJob")
        .def("run", &TabulationStageJob::run, py::call_guard<py::gil_scoped_release>(),
             "run the stage over its cells (blocking, GIL released, all cores)")
        .def("cancel", &TabulationStageJob::cancel)
        .def_property_readonly("cancelled", &TabulationStageJob::cancelled)
        .def_property_readonly("done", &TabulationStageJob::done)
        .def_property_readonly("total", &TabulationStageJob::total)
        .def_property_readonly("pilot_lum", [=](const TabulationStageJob &j) { return doubles(j.pilot.lum); })
        .def_property_readonly("pilot_error",
                               [=](const TabulationStageJob &j) { return doubles(j.pilot.lum_error); })
        .def_property_readonly("pilot_channel_error",
                               [=](const TabulationStageJob &j) { return doubles(j.pilot.error); })
        .def_property_readonly("pilot_nonfinite",
                               [](const TabulationStageJob &j) { return j.pilot.nonfinite; })
        .def_property_readonly("value",
                               [=](const TabulationStageJob &j) { return doubles(j.finished.value); })
        .def_property_readonly("error",
                               [=](const TabulationStageJob &j) { return doubles(j.finished.error); })
        .def_property_readonly("lum_value",
                               [=](const TabulationStageJob &j) { return doubles(j.finished.lum); })
        .def_property_readonly("lum_error",
                               [=](const TabulationStageJob &j) { return doubles(j.finished.lum_error); })
        .def_property_readonly("samples",
                               [](const TabulationStageJob &j) {
                                   return py::array_t<int>(j.finished.samples.size(),
                                                           j.finished.samples.data());
                               })
        .def_property_readonly("nonfinite", [](const TabulationStageJob &j) { return j.finished.nonfinite; })
        .def_property_readonly("pilot_capped", [](const TabulationStageJob &j) { return j.pilot.capped; })
        .def_property_readonly("capped", [](const TabulationStageJob &j) { return j.finished.capped; });

    py::class_<TabulatedBSDF, BSDF, std::shared_ptr<TabulatedBSDF>>(m, "TabulatedBSDF")
        .def(
            py::init([](std::vector<double> channel_ids, int n_lobes, int n_theta_i, int n_theta_o, int n_phi,
                        std::vector<double> thickness, std::vector<float> values,
                        std::vector<double> luminance, std::shared_ptr<BSDF> direct, std::vector<double> P,
                        double default_thickness, double transmission_eta, std::shared_ptr<BSDF> direct_below,
                        std::shared_ptr<TableDeltaStack> delta, std::vector<double> delta_P) {
                return std::make_shared<TabulatedBSDF>(
                    std::move(channel_ids),
                    make_grid(n_lobes, n_theta_i, n_theta_o, n_phi, std::move(thickness)), std::move(values),
                    std::move(luminance), direct, std::move(P), default_thickness, transmission_eta,
                    direct_below, delta, std::move(delta_P));
            }),
            py::arg("channel_ids"), py::arg("n_lobes"), py::arg("n_theta_i"), py::arg("n_theta_o"),
            py::arg("n_phi"), py::arg("thickness_nm"), py::arg("values"), py::arg("luminance"),
            py::arg("direct"), py::arg("P"), py::arg("default_thickness_nm"),
            py::arg("transmission_eta") = 1.0, py::arg("direct_below") = nullptr, py::arg("delta") = nullptr,
            py::arg("delta_P") = std::vector<double>{});

    // The delta lobes of a layered stack (table_delta.h), exposed for the tests.
    py::class_<TableDeltaStack, std::shared_ptr<TableDeltaStack>>(m, "TableDeltaStack")
        .def(py::init([](std::vector<std::shared_ptr<BSDF>> boundaries, std::vector<double> thickness_um,
                         std::vector<std::vector<double>> sigma_t) {
                 std::vector<std::shared_ptr<const BSDF>> b(boundaries.begin(), boundaries.end());
                 return std::make_shared<TableDeltaStack>(std::move(b), std::move(thickness_um),
                                                          std::move(sigma_t));
             }),
             py::arg("boundaries"), py::kw_only(), py::arg("thickness_um"), py::arg("sigma_t"))
        .def_property_readonly("channels", &TableDeltaStack::channels)
        .def_property_readonly("transmits", &TableDeltaStack::transmits)
        .def_property_readonly("extends", &TableDeltaStack::extends)
        .def(
            "solve",
            [](const TableDeltaStack &d, std::array<double, 3> wi, double thickness_nm) {
                const int C = d.channels();
                std::vector<double> R(C), T(C);
                Vec3 wt{0.0, 0.0, 0.0};
                double eta = 1.0;
                Query q;
                q.film_thickness_nm = thickness_nm;
                d.solve(Vec3{wi[0], wi[1], wi[2]}, q, R.data(), T.data(), wt, eta);
                return py::make_tuple(py::array_t<double>(C, R.data()), py::array_t<double>(C, T.data()),
                                      std::array<double, 3>{wt.x, wt.y, wt.z}, eta);
            },
            py::arg("wi"), py::arg("thickness_nm") = -1.0,
            "(R, T, wt, eta): the delta reflectance and transmittance of light along wi (radiance mode)");

    py::class_<ProjectedFresnelTerm, FresnelTerm, std::shared_ptr<ProjectedFresnelTerm>>(
        m, "ProjectedFresnelTerm")
        .def(py::init<std::shared_ptr<const FresnelTerm>, std::vector<double>, int, double, double, double,
                      int, int>(),
             py::arg("exact"), py::arg("P"), py::arg("out_channels"), py::arg("thickness_lo_nm"),
             py::arg("thickness_hi_nm"), py::arg("default_thickness_nm"), py::arg("n_cos"),
             py::arg("n_thickness"))
        .def_property_readonly("n_cos", &ProjectedFresnelTerm::n_cos)
        .def_property_readonly("n_thickness", &ProjectedFresnelTerm::n_thickness);

    py::class_<FilmLookupTerm, FresnelTerm, std::shared_ptr<FilmLookupTerm>>(m, "FilmLookupTerm")
        .def_static(
            "build",
            [](std::shared_ptr<const FresnelTerm> exact, double thickness, double max_error) {
                // None when no lookup meets max_error (the caller keeps the exact term).
                return std::const_pointer_cast<FilmLookupTerm>(
                    FilmLookupTerm::build(std::move(exact), thickness, max_error));
            },
            py::arg("exact"), py::arg("thickness_nm"),
            py::arg("max_error") = FilmLookupTerm::kDefaultMaxError)
        .def_property_readonly("measured_error", &FilmLookupTerm::measured_error)
        .def_property_readonly("intervals", &FilmLookupTerm::intervals)
        .def_property_readonly("thickness_nm", &FilmLookupTerm::thickness_nm)
        .def("kink", &FilmLookupTerm::kink, py::arg("side"),
             "critical cosine of light from side 0 (above) or 1");
}
