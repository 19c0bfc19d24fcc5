// Bindings of the renderer: build a RenderScene from numpy arrays and core BSDFs, then run
// a RenderJob (GIL released) that Python drives from a worker thread for progress/cancel.
#include <pybind11/stl.h>
#include "arrays.h"
#include "bsdflab/render/path_tracer.h"
#include "bsdflab/sampling.h"

namespace py = pybind11;
using namespace bsdflab;
using namespace bsdflab::py_helpers;
using Farr = py::array_t<float, py::array::c_style | py::array::forcecast>;
using Uarr = py::array_t<uint32_t, py::array::c_style | py::array::forcecast>;

namespace {

std::vector<float> rows_of(const py::object &obj, std::size_t cols, const char *name) {
    if (obj.is_none()) return {};
    Farr a = py::cast<Farr>(obj);
    if (a.ndim() != 2 || std::size_t(a.shape(1)) != cols)
        throw std::invalid_argument(std::string(name) + " must have shape (V, " + std::to_string(cols) + ")");
    return std::vector<float>(a.data(), a.data() + a.size());
}

Vec3 vec3(const std::vector<double> &v, const char *name) {
    if (v.size() != 3) throw std::invalid_argument(std::string(name) + " must have 3 components");
    return {v[0], v[1], v[2]};
}

RenderBSDF render_bsdf(const std::shared_ptr<BSDF> &b, const std::vector<double> &P,
                       const std::vector<double> &U) {
    RenderBSDF r;
    r.bsdf = b;
    r.P = P;
    r.U = U;
    return r;
}

} // namespace

void bind_render(py::module_ &m) {
    py::class_<RenderScene, std::shared_ptr<RenderScene>>(m, "RenderScene")
        .def(py::init<>())
        .def(
            "add_material",
            [](RenderScene &s, const std::shared_ptr<BSDF> &surface, const std::vector<double> &P,
               const std::shared_ptr<BSDF> &gap, const std::vector<double> &gap_P,
               const std::shared_ptr<ScaleTexture> &scales, double film_thickness_nm,
               const std::vector<double> &U, const std::vector<double> &gap_U) {
                Material mat;
                if (!surface) throw std::invalid_argument("material: a BSDF is required");
                mat.surface = render_bsdf(surface, P, U);
                if (gap) {
                    mat.gap = render_bsdf(gap, gap_P, gap_U);
                    mat.has_gap = true;
                }
                mat.scales = scales;
                mat.film_thickness_nm = film_thickness_nm;
                return s.add_material(std::move(mat));
            },
            py::arg("surface"), py::arg("P"), py::arg("gap") = nullptr,
            py::arg("gap_P") = std::vector<double>(), py::arg("scales") = nullptr,
            py::arg("film_thickness_nm") = -1.0, py::arg("U") = std::vector<double>(),
            py::arg("gap_U") = std::vector<double>(),
            "P: the (3 x C) row-major projection of the BSDF's channels to RGB, [] if it answers in RGB; "
            "U: the (81 x C) lift to the spectral bins, [] if its channels are those bins")
        .def("set_spectral", &RenderScene::set_spectral, py::arg("U"), py::arg("W"),
             "U (81 x 3) lifts RGB emission to the spectral bins, W (3 x 81) takes them to linear sRGB")
        .def_property_readonly("spectral_ready", &RenderScene::spectral_ready)
        .def(
            "add_mesh",
            [](RenderScene &s, const py::object &positions, const py::object &indices,
               const py::object &normals, const py::object &uvs, int material,
               const std::vector<double> &emission) {
                MeshInput in;
                in.positions = rows_of(positions, 3, "positions");
                Uarr idx = py::cast<Uarr>(indices);
                if (idx.ndim() != 2 || idx.shape(1) != 3)
                    throw std::invalid_argument("indices must have shape (F, 3)");
                in.indices.assign(idx.data(), idx.data() + idx.size());
                in.normals = rows_of(normals, 3, "normals");
                in.uvs = rows_of(uvs, 2, "uvs");
                in.material = material;
                Vec3 e = vec3(emission, "emission");
                in.emission[0] = e.x;
                in.emission[1] = e.y;
                in.emission[2] = e.z;
                return s.add_mesh(std::move(in));
            },
            py::arg("positions"), py::arg("indices"), py::arg("normals") = py::none(),
            py::arg("uvs") = py::none(), py::arg("material") = -1,
            py::arg("emission") = std::vector<double>{0, 0, 0})
        .def("set_camera",
             [](RenderScene &s, const std::vector<double> &origin, const std::vector<double> &target,
                const std::vector<double> &up, double fov_deg, int width, int height) {
                 s.set_camera(Camera(vec3(origin, "origin"), vec3(target, "target"), vec3(up, "up"), fov_deg,
                                     width, height));
             })
        .def("set_environment_constant",
             [](RenderScene &s, const std::vector<double> &rgb) {
                 Vec3 c = vec3(rgb, "radiance");
                 double v[3] = {c.x, c.y, c.z};
                 s.set_environment(Environment::constant(v));
             })
        .def("set_environment_map",
             [](RenderScene &s, const Farr &image, double scale) {
                 if (image.ndim() != 3 || image.shape(2) != 3)
                     throw std::invalid_argument("environment map must have shape (H, W, 3)");
                 s.set_environment(Environment::latlong(
                     int(image.shape(1)), int(image.shape(0)),
                     std::vector<float>(image.data(), image.data() + image.size()), scale));
             })
        .def(
            "add_point_light",
            [](RenderScene &s, const std::vector<double> &position, const std::vector<double> &intensity,
               const std::vector<double> &spectrum) {
                Vec3 I = vec3(intensity, "intensity");
                const double v[3] = {I.x, I.y, I.z};
                s.add_light(AnalyticLight::point(vec3(position, "position"), v), spectrum);
            },
            py::arg("position"), py::arg("intensity"), py::arg("spectrum") = std::vector<double>(),
            "a point light of intensity I (W/sr, linear sRGB); spectrum: its 81 bins for spectral mode, or "
            "[]")
        .def(
            "add_spot_light",
            [](RenderScene &s, const std::vector<double> &position, const std::vector<double> &direction,
               const std::vector<double> &intensity, double cutoff_deg, double beam_width_deg,
               const std::vector<double> &spectrum) {
                Vec3 I = vec3(intensity, "intensity");
                const double v[3] = {I.x, I.y, I.z}, rad = kPi / 180;
                s.add_light(AnalyticLight::spot(vec3(position, "position"), vec3(direction, "direction"), v,
                                                cutoff_deg * rad, beam_width_deg * rad),
                            spectrum);
            },
            py::arg("position"), py::arg("direction"), py::arg("intensity"), py::arg("cutoff_deg"),
            py::arg("beam_width_deg"), py::arg("spectrum") = std::vector<double>(),
            "a spot light with Mitsuba 3's falloff (angles from the axis); spectrum as for a point light")
        .def(
            "add_directional_light",
            [](RenderScene &s, const std::vector<double> &direction, const std::vector<double> &irradiance,
               double angular_diameter_deg, const std::vector<double> &spectrum) {
                Vec3 E = vec3(irradiance, "irradiance");
                const double v[3] = {E.x, E.y, E.z};
                s.add_light(AnalyticLight::directional(vec3(direction, "direction"), v,
                                                       0.5 * angular_diameter_deg * kPi / 180),
                            spectrum);
            },
            py::arg("direction"), py::arg("irradiance"), py::arg("angular_diameter_deg") = 0.0,
            py::arg("spectrum") = std::vector<double>(),
            "light from infinitely far along `direction` (the way it travels), irradiance E facing it; "
            "an angular diameter > 0 spreads it over a cone (a soft sun); spectrum as for a point light")
        .def("commit", &RenderScene::commit, py::call_guard<py::gil_scoped_release>())
        .def_property("robust", &RenderScene::robust, &RenderScene::set_robust,
                      "Embree's robust (watertight) traversal; set before commit()")
        .def(
            "first_hits",
            [](const RenderScene &sc, py::array_t<float, py::array::c_style | py::array::forcecast> rays) {
                if (rays.ndim() != 2 || rays.shape(1) != 6)
                    throw std::invalid_argument("rays must be (N, 6)");
                if (!sc.committed()) throw std::invalid_argument("commit() the scene first");
                const std::size_t n = rays.shape(0);
                py::array_t<int> out(n);
                const float *p = rays.data();
                int *o = out.mutable_data();
                {
                    py::gil_scoped_release release;
                    sc.first_hits(p, n, o);
                }
                return out;
            },
            py::arg("rays"), "mesh id of each ray's first hit (-1: none); rays (N, 6): origin, direction")
        .def(
            "embree_seconds",
            [](const RenderScene &sc, py::array_t<float, py::array::c_style | py::array::forcecast> rays,
               int packet) {
                if (rays.ndim() != 2 || rays.shape(1) != 8)
                    throw std::invalid_argument("rays must be (N, 8)");
                if (!sc.committed()) throw std::invalid_argument("commit() the scene first");
                if (packet != 1 && packet != 16) throw std::invalid_argument("packet must be 1 or 16");
                const float *p = rays.data();
                std::size_t n = rays.shape(0);
                py::gil_scoped_release release;
                return sc.trace_recorded(p, n, packet);
            },
            py::arg("rays"), py::arg("packet") = 1,
            "wall seconds Embree alone takes to trace recorded rays on all cores (packet: 1 or 16 wide)")
        .def(
            "environment_eval",
            [](const RenderScene &s, const Darr &d) {
                require_rows3(d, "d");
                std::size_t n = d.shape(0);
                py::array_t<double> out({n, std::size_t(3)});
                for (std::size_t i = 0; i < n; ++i)
                    s.environment().eval(row(d.data(), i), out.mutable_data() + 3 * i);
                return out;
            },
            "radiance from directions d (N, 3): for tests")
        .def("environment_pdf",
             [](const RenderScene &s, const Darr &d) {
                 require_rows3(d, "d");
                 std::size_t n = d.shape(0);
                 py::array_t<double> out(n);
                 for (std::size_t i = 0; i < n; ++i)
                     out.mutable_data()[i] = s.environment().pdf(row(d.data(), i));
                 return out;
             })
        .def(
            "environment_sample",
            [](const RenderScene &s, const Darr &u, bool radiance) -> py::tuple {
                if (u.ndim() != 2 || u.shape(1) != 2) throw std::invalid_argument("u must have shape (N, 2)");
                std::size_t n = u.shape(0);
                py::array_t<double> dirs({n, std::size_t(3)}), pdf(n), rgb({n, std::size_t(3)});
                for (std::size_t i = 0; i < n; ++i) {
                    Vec3 d = s.environment().sample(u.data()[2 * i], u.data()[2 * i + 1],
                                                    pdf.mutable_data()[i], rgb.mutable_data() + 3 * i);
                    double *o = dirs.mutable_data() + 3 * i;
                    o[0] = d.x;
                    o[1] = d.y;
                    o[2] = d.z;
                }
                if (radiance) return py::make_tuple(dirs, pdf, rgb);
                return py::make_tuple(dirs, pdf);
            },
            py::arg("u"), py::arg("radiance") = false,
            "directions and densities from uniform (N, 2) numbers; with radiance=True also the radiance "
            "the sampler reads at each direction");

    py::class_<RenderJob, std::shared_ptr<RenderJob>>(m, "RenderJob")
        .def(py::init([](std::shared_ptr<RenderScene> scene, int spp, int pass_spp, int max_depth,
                         int rr_depth, uint64_t seed, int tile, int strategy, bool spectral) {
                 if (strategy < 0 || strategy > 2)
                     throw std::invalid_argument("strategy must be 0 (MIS), 1 (BSDF) or 2 (light)");
                 RenderSettings s;
                 s.strategy = LightStrategy(strategy);
                 s.spp = spp;
                 s.pass_spp = pass_spp;
                 s.max_depth = max_depth;
                 s.rr_depth = rr_depth;
                 s.seed = seed;
                 s.tile = tile;
                 s.spectral = spectral;
                 return std::make_shared<RenderJob>(std::move(scene), s);
             }),
             py::arg("scene"), py::arg("spp"), py::arg("pass_spp") = 4, py::arg("max_depth") = 8,
             py::arg("rr_depth") = 5, py::arg("seed") = 0, py::arg("tile") = 16, py::arg("strategy") = 0,
             py::arg("spectral") = false)
        .def("run", &RenderJob::run, py::call_guard<py::gil_scoped_release>())
        .def("cancel", &RenderJob::cancel)
        .def_property_readonly("cancelled", &RenderJob::cancelled)
        .def_property_readonly("total", &RenderJob::total)
        .def_property_readonly("done", &RenderJob::done)
        .def_property_readonly("spp_done", &RenderJob::spp_done)
        .def_property_readonly("invalid_samples", &RenderJob::invalid_samples)
        .def(
            "image",
            [](const RenderJob &j) {
                std::size_t h = j.height(), w = j.width();
                py::array_t<double> mean({h, w, std::size_t(3)}), var({h, w, std::size_t(3)});
                j.image(mean.mutable_data(), var.mutable_data());
                return py::make_tuple(mean, var);
            },
            "(mean, variance of the mean), each (H, W, 3), over the completed passes")
        .def_property_readonly("passes", &RenderJob::passes)
        .def("pass_samples", &RenderJob::pass_samples, py::arg("pass_index"))
        .def(
            "render_window",
            [](const RenderJob &j, int x0, int y0, int x1, int y1, int pass) {
                const std::size_t h = std::size_t(std::max(0, y1 - y0)),
                                  w = std::size_t(std::max(0, x1 - x0));
                py::array_t<double> sum({h, w, std::size_t(3)}), sq({h, w, std::size_t(3)});
                double *ps = sum.mutable_data(), *pq = sq.mutable_data();
                std::size_t bad;
                {
                    py::gil_scoped_release release;
                    bad = j.render_window(x0, y0, x1, y1, pass, ps, pq);
                }
                return py::make_tuple(sum, sq, bad);
            },
            py::arg("x0"), py::arg("y0"), py::arg("x1"), py::arg("y1"), py::arg("pass_index"),
            "(sum, sum of squares, invalid samples) of one pass over a pixel window: a work unit "
            "of distributed rendering, equal to what run() computes for those pixels")
        .def_static(
            "finish_image",
            [](py::array_t<double, py::array::c_style | py::array::forcecast> sum,
               py::array_t<double, py::array::c_style | py::array::forcecast> sq, double n) {
                if (sum.size() != sq.size()) throw std::invalid_argument("sum and sq differ in size");
                std::vector<py::ssize_t> shape(sum.shape(), sum.shape() + sum.ndim());
                py::array_t<double> mean(shape), var(shape);
                RenderJob::finish_image(sum.data(), sq.data(), std::size_t(sum.size()), n,
                                        mean.mutable_data(), var.mutable_data());
                return py::make_tuple(mean, var);
            },
            py::arg("sum"), py::arg("sum_sq"), py::arg("n"),
            "(mean, variance of the mean) from accumulated sums over n samples, as image() computes them")
        .def(
            "radiance",
            [](const RenderJob &j, double px, double py, uint64_t seed) {
                double L[3];
                j.radiance(px, py, seed, L);
                return std::vector<double>{L[0], L[1], L[2]};
            },
            "one camera sample's radiance at film position (px, py): for tests")
        .def_property_readonly("rays_traced", &RenderJob::rays_traced)
        .def(
            "record_rays",
            [](const RenderJob &j, std::size_t max_rays) {
                std::vector<float> r;
                {
                    py::gil_scoped_release release;
                    r = j.record_rays(max_rays);
                }
                py::array_t<float> out({r.size() / 8, std::size_t(8)});
                std::copy(r.begin(), r.end(), out.mutable_data());
                return out;
            },
            py::arg("max_rays"), "(N, 8) rays of the first pass: origin, direction, tmax, shadow flag")
        .def(
            "aovs",
            [](const RenderJob &j, int samples) {
                if (samples < 1) throw std::invalid_argument("aovs: samples must be >= 1");
                std::size_t h = j.height(), w = j.width();
                py::array_t<double> albedo({h, w, std::size_t(3)}), normal({h, w, std::size_t(3)});
                py::array_t<int> mesh({h, w});
                double *a = albedo.mutable_data(), *n = normal.mutable_data();
                int *id = mesh.mutable_data();
                {
                    py::gil_scoped_release release;
                    j.aovs(samples, a, n, id);
                }
                return py::make_tuple(albedo, normal, mesh);
            },
            py::arg("samples") = 16, "(albedo, normal, mesh id) first-hit images for a denoiser and masks");
}
