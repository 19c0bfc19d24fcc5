// Helpers shared by the binding files: numpy <-> core conversions.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <stdexcept>
#include <string>
#include "bsdflab/vector.h"

namespace bsdflab::py_helpers {

namespace py = pybind11;
using Darr = py::array_t<double, py::array::c_style | py::array::forcecast>;

// The Python layer validates shapes with friendly messages; this is the last guard.
inline void require_rows3(const Darr &a, const char *name) {
    if (a.ndim() != 2 || a.shape(1) != 3)
        throw std::invalid_argument(std::string(name) + " must have shape (N, 3)");
}

inline Vec3 row(const double *p, std::size_t i) { return {p[3 * i], p[3 * i + 1], p[3 * i + 2]}; }

// Below this many rows a loop is not worth spreading over threads.
constexpr std::size_t kGrain = 2048;

} // namespace bsdflab::py_helpers
