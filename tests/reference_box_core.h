// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The plain reference of the box core (docs/FILTER.md section 15): every
// window's sums added point by point, every splat window by window, every
// pooled risk pixel by pixel. reference_filter.cpp runs it between its
// sections 2-3 (classes, noise, outliers) and 3a/7 (spread, output).

#pragma once

#include <vector>

#include <zdenoise/zdenoise.h>

namespace zdenoise_ref {

/// What the box core reads per pixel (w x h, row-major).
struct BoxInputs {
    int w = 0, h = 0;
    std::vector<char> fit;           ///< a fit point
    std::vector<double> z;           ///< the quotient, outliers capped, 3 a pixel
    std::vector<double> zl, vs;      ///< its luminance and smoothed variance
    std::vector<double> normal;      ///< unit normal, 3 a pixel, 0 where none
    std::vector<double> invdepth;    ///< 1 / depth, 0 where none or no depth
    std::vector<double> albedo;      ///< La + eps where demodulated, else 0; 3 a pixel
};

/// The box core's light: `acc` (3 a pixel) and `wsum` (1 where a
/// candidate reaches the pixel, else 0), as the C++ core hands them to the
/// outliers' spread and the output.
void box_core_light(const BoxInputs& in, const zdenoise::FilterOptions& opt,
                    std::vector<double>& acc, std::vector<double>& wsum);

}  // namespace zdenoise_ref
