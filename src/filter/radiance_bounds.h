// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The bounds the selection puts on the feature regressions' output: the
// radiance of the fit points around each pixel (docs/FILTER.md section
// 13.2; radiance_bounds.cpp).

#pragma once

#include <atomic>
#include <vector>

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// The bounds of the feature regressions' output at each pixel of `out`
/// (docs/FILTER.md section 13.2): per channel, the least and the most
/// radiance of the fit points within r_max (the largest window of today's
/// filter; a Chebyshev square, min and max by rows then columns), and the
/// pixel's 1 / (La + albedo_eps) (0 where not demodulated). A window of
/// the wider feature regression reaches 2 x 15 pixels, and its linear model
/// in the normal extrapolates across facets: without these bounds it put
/// light 1.2x brighter than any within 16 pixels on zigzag_steps. Once
/// `cancel` is set (FilterOptions::cancel) the remaining rows and columns
/// are skipped: the bounds are then no result.
void
radiance_bounds(const FilterInputs& in, const ROI& out, int r_max,
                std::vector<float>& lo, std::vector<float>& hi,
                std::vector<float>& inv_albedo, int nthreads,
                const std::atomic<bool>* cancel);

}  // namespace detail
}  // namespace zdenoise
