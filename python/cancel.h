// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// zdenoise.Cancel and zdenoise.Cancelled (docs/PYTHON.md, "Cancelling"):
// a flag another Python thread sets while denoise() or denoise_file() runs
// with the GIL released, and the error the stopped call raises.

#pragma once

#include <algorithm>
#include <atomic>
#include <stdexcept>

#include <pybind11/pybind11.h>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/zdenoise.h>

namespace zdenoise_python {

/// The flag of zdenoise::FilterOptions::cancel.
struct Cancel {
    std::atomic<bool> flag { false };
};

/// zdenoise.Cancelled: the call's Cancel was set.
struct CancelledError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// zdenoise::prefilter_albedo() of the whole of `albedo` into `dst`, in
/// bands of rows with `cancel` polled between them (about 35 ms a band on
/// a 1080p frame, where the whole takes 0.6 s): each band's pixels are the
/// whole image's (any ROI is exact). Cancelled: false, dst holding no
/// result and the error "zdenoise: cancelled", as the library's.
inline bool
prefilter_albedo_in_bands(OIIO::ImageBuf& dst, const OIIO::ImageBuf& albedo,
                          int samples, int nthreads,
                          const std::atomic<bool>* cancel)
{
    constexpr int kBandRows = 64;
    dst.reset(OIIO::ImageSpec(albedo.roi(), OIIO::TypeFloat));
    for (int y = albedo.ybegin(); y < albedo.yend(); y += kBandRows) {
        if (cancel && cancel->load()) {
            dst.reset();
            dst.errorfmt("zdenoise: cancelled");
            return false;
        }
        OIIO::ROI band = albedo.roi();
        band.ybegin    = y;
        band.yend      = std::min(y + kBandRows, albedo.yend());
        if (!zdenoise::prefilter_albedo(dst, albedo, samples, band, nthreads))
            return false;
    }
    return true;
}

/// Add Cancel and Cancelled (a subclass of `error`, zdenoise.Error) to `m`.
inline void
add_cancel(pybind11::module_& m, pybind11::handle error)
{
    namespace py = pybind11;
    py::register_exception<CancelledError>(m, "Cancelled", error);
    m.attr("Cancelled").attr("__doc__")
        = "The call's zdenoise.Cancel was set: it stopped, with no output.";
    py::class_<Cancel>(m, "Cancel", "A flag that stops a running denoise() "
                                    "or denoise_file() given it as cancel=.")
        .def(py::init<>())
        .def("cancel", [](Cancel& c) { c.flag = true; },
             "Stop the calls given this flag; safe from any thread.")
        .def_property_readonly("cancelled",
                               [](const Cancel& c) { return c.flag.load(); });
}

}  // namespace zdenoise_python
