// Vectorised thin-film responses over N rows (Python validates and broadcasts first).
// thin_film and film_stack return (r_s, r_p, t_s, t_p, R_s, R_p, T_s, T_p), four complex and
// four real arrays; thin_film_reflectance returns (R_s, R_p).
#include <algorithm>
#include <complex>
#include "arrays.h"
#include "bsdflab/parallel.h"
#include "bsdflab/thin_film.h"

namespace py = pybind11;
using namespace bsdflab;
using namespace bsdflab::py_helpers;
using Carr = py::array_t<std::complex<double>, py::array::c_style | py::array::forcecast>;

namespace {

// Output columns, filled row by row from FilmResponse.
struct Outputs {
    py::array_t<cplx> r_s, r_p, t_s, t_p;
    py::array_t<double> R_s, R_p, T_s, T_p;
    cplx *prs, *prp, *pts, *ptp;
    double *pRs, *pRp, *pTs, *pTp;

    explicit Outputs(std::size_t n)
        : r_s(n), r_p(n), t_s(n), t_p(n), R_s(n), R_p(n), T_s(n), T_p(n), prs(r_s.mutable_data()),
          prp(r_p.mutable_data()), pts(t_s.mutable_data()), ptp(t_p.mutable_data()), pRs(R_s.mutable_data()),
          pRp(R_p.mutable_data()), pTs(T_s.mutable_data()), pTp(T_p.mutable_data()) {}

    void store(std::size_t i, const FilmResponse &f) const {
        prs[i] = f.r_s;
        prp[i] = f.r_p;
        pts[i] = f.t_s;
        ptp[i] = f.t_p;
        pRs[i] = f.R_s;
        pRp[i] = f.R_p;
        pTs[i] = f.T_s;
        pTp[i] = f.T_p;
    }

    py::tuple to_tuple() const { return py::make_tuple(r_s, r_p, t_s, t_p, R_s, R_p, T_s, T_p); }
};

// Each argument of thin_film has length N or 1; a length-1 argument applies to every row
// (step 0), so Python need not copy a constant index N times.
template <typename T> struct Column {
    const T *data;
    std::size_t step;
    const T &operator[](std::size_t i) const { return data[i * step]; }
};

template <typename A> std::size_t rows_of(const A &a, const char *name) {
    if (a.ndim() != 1 || a.shape(0) < 1)
        throw std::invalid_argument(std::string(name) + " must have shape (N,) or (1,)");
    return static_cast<std::size_t>(a.shape(0));
}

template <typename T, typename A> Column<T> column(const A &a, std::size_t n, const char *name) {
    std::size_t len = rows_of(a, name);
    if (len != n && len != 1) throw std::invalid_argument(std::string(name) + " must have length N or 1");
    return {a.data(), len == 1 ? 0u : 1u};
}

void require_length(const py::array &a, std::size_t n, const char *name) {
    if (a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n)
        throw std::invalid_argument(std::string(name) + " must have shape (N,)");
}

// The six arguments of one film per row.
struct FilmColumns {
    std::size_t rows;
    Column<cplx> n0, n1, n2;
    Column<double> d, cos0, wl;
};

FilmColumns film_columns(const Carr &n0, const Carr &n1, const Carr &n2, const Darr &d_nm, const Darr &cos0,
                         const Darr &wavelength_nm) {
    std::size_t n = std::max({rows_of(n0, "n0"), rows_of(n1, "n1"), rows_of(n2, "n2"), rows_of(d_nm, "d_nm"),
                              rows_of(cos0, "cos0"), rows_of(wavelength_nm, "wavelength_nm")});
    return {n,
            column<cplx>(n0, n, "n0"),
            column<cplx>(n1, n, "n1"),
            column<cplx>(n2, n, "n2"),
            column<double>(d_nm, n, "d_nm"),
            column<double>(cos0, n, "cos0"),
            column<double>(wavelength_nm, n, "wavelength_nm")};
}

py::tuple thin_film_many(const Carr &n0, const Carr &n1, const Carr &n2, const Darr &d_nm, const Darr &cos0,
                         const Darr &wavelength_nm) {
    const FilmColumns c = film_columns(n0, n1, n2, d_nm, cos0, wavelength_nm);
    Outputs out(c.rows);
    {
        py::gil_scoped_release nogil;
        parallel_for(c.rows, kGrain, [&](std::size_t s, std::size_t e) {
            for (std::size_t i = s; i < e; ++i)
                out.store(i, thin_film(c.n0[i], c.n1[i], c.n2[i], c.d[i], c.cos0[i], c.wl[i]));
        });
    }
    return out.to_tuple();
}

py::tuple thin_film_reflectance_many(const Carr &n0, const Carr &n1, const Carr &n2, const Darr &d_nm,
                                     const Darr &cos0, const Darr &wavelength_nm) {
    const FilmColumns c = film_columns(n0, n1, n2, d_nm, cos0, wavelength_nm);
    py::array_t<double> R_s(c.rows), R_p(c.rows);
    double *ps = R_s.mutable_data(), *pp = R_p.mutable_data();
    {
        py::gil_scoped_release nogil;
        parallel_for(c.rows, kGrain, [&](std::size_t s, std::size_t e) {
            for (std::size_t i = s; i < e; ++i) {
                FilmReflectance f =
                    thin_film_reflectance(c.n0[i], c.n1[i], c.n2[i], c.d[i], c.cos0[i], c.wl[i]);
                ps[i] = f.R_s;
                pp[i] = f.R_p;
            }
        });
    }
    return py::make_tuple(R_s, R_p);
}

py::tuple film_stack_many(const Carr &indices, const Darr &d_nm, const Darr &cos0,
                          const Darr &wavelength_nm) {
    if (indices.ndim() != 2 || indices.shape(1) < 2)
        throw std::invalid_argument("indices must have shape (N, layers + 2)");
    std::size_t n = indices.shape(0), media = indices.shape(1), layers = media - 2;
    if (d_nm.ndim() != 2 || static_cast<std::size_t>(d_nm.shape(0)) != n ||
        static_cast<std::size_t>(d_nm.shape(1)) != layers)
        throw std::invalid_argument("d_nm must have shape (N, layers)");
    require_length(cos0, n, "cos0");
    require_length(wavelength_nm, n, "wavelength_nm");
    Outputs out(n);
    const cplx *ni = indices.data();
    const double *d = d_nm.data(), *ct = cos0.data(), *wl = wavelength_nm.data();
    {
        py::gil_scoped_release nogil;
        parallel_for(n, kGrain, [&](std::size_t s, std::size_t e) {
            for (std::size_t i = s; i < e; ++i)
                out.store(i, film_stack(ni + i * media, d + i * layers, layers, ct[i], wl[i]));
        });
    }
    return out.to_tuple();
}

} // namespace

void bind_thin_film(py::module_ &m) {
    m.def("thin_film", &thin_film_many, py::arg("n0"), py::arg("n1"), py::arg("n2"), py::arg("d_nm"),
          py::arg("cos0"), py::arg("wavelength_nm"),
          "One film (Airy) per row; every argument 1-D of length N, or 1 for all rows.\n"
          "Returns (r_s, r_p, t_s, t_p, R_s, R_p, T_s, T_p).");
    m.def("thin_film_reflectance", &thin_film_reflectance_many, py::arg("n0"), py::arg("n1"), py::arg("n2"),
          py::arg("d_nm"), py::arg("cos0"), py::arg("wavelength_nm"),
          "As thin_film, returning only (R_s, R_p).");
    m.def("film_stack", &film_stack_many, py::arg("indices"), py::arg("d_nm"), py::arg("cos0"),
          py::arg("wavelength_nm"),
          "A stack per row: indices (N, L + 2) incident..exit, d_nm (N, L), cos0 and\n"
          "wavelength_nm (N,). Returns (r_s, r_p, t_s, t_p, R_s, R_p, T_s, T_p).");
}
