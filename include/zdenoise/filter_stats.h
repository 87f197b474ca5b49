// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// What the filter did (zdenoise.h includes this): the statistics of a run
// and the names of its per-pixel diagnostic maps.

#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <zdenoise/export.h>

namespace zdenoise {

/// What the filter did, for verbose output and reports.
struct FilterStats {
    int64_t pixels = 0;              ///< output pixels (in roi)
    int64_t windows = 0;             ///< windows fitted (centres in roi)
    int64_t stop_quality = 0;        ///< windows stopped by eta_target
    int64_t stop_size = 0;           ///< windows stopped by r_max
    int64_t stop_edge = 0;           ///< windows stopped by strong variation
    double mean_radius = 0.0;        ///< mean final half-size of the windows
    int64_t radius_sum = 0;          ///< sum of the final half-sizes (exact)
    int64_t passthrough_pixels = 0;  ///< pixels with >= 1 RGB channel passed through
    int64_t nonfinite_pixels = 0;    ///< pixels with a non-finite RGB value in
                                     ///< the input (repaired or set to 0)
    int64_t kept_pixels = 0;         ///< pixels of a direct layer where
                                     ///< keep_structure() took the
                                     ///< significance filter

    /// Add the statistics of other pixels (another tile, strip or layer):
    /// counts add, and mean_radius is radius_sum / windows again, so the
    /// totals do not depend on how the work was split.
    FilterStats& merge(const FilterStats& other)
    {
        pixels += other.pixels;
        windows += other.windows;
        stop_quality += other.stop_quality;
        stop_size += other.stop_size;
        stop_edge += other.stop_edge;
        radius_sum += other.radius_sum;
        passthrough_pixels += other.passthrough_pixels;
        nonfinite_pixels += other.nonfinite_pixels;
        kept_pixels += other.kept_pixels;
        mean_radius = windows ? double(radius_sum) / double(windows) : 0.0;
        return *this;
    }
};


/// The channels of FilterOptions::diagnostics, in order:
///  - "radius": the final half-size of the windows that reached the pixel,
///    their mean weighted by what each splatted there (0: none did); with
///    FilterOptions::core 1, the blend's mean radius (0: the input);
///  - "stop": why the window that splatted most there stopped growing, a
///    StopCode (0: no window reached the pixel; it passed through);
///  - "noise": the estimated relative noise of the input's light at the
///    pixel, sigma = sqrt(Var) / |z| (docs/FILTER.md section 3), 0 where
///    the pixel is no fit point;
///  - "error": the estimated remaining relative error of the output there:
///    the predicted relative standard deviation of the filtered light
///    (eta of the windows that reached it, weighted as "radius"). It is
///    what more samples would reduce: where it is high, the frame needs
///    them. 0 where no window reached the pixel.
ZDENOISE_API const std::vector<std::string>& diagnostic_channels();

/// The values of the "stop" diagnostic channel.
enum class StopCode : int { None = 0, Quality = 1, Size = 2, Edge = 3 };

}  // namespace zdenoise
