// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Holes (docs/FILTER.md section 7): a receiver channel whose radiance is NaN
// or Inf and that no window reached takes the light of the fit points of
// its surface around it, so that remodulation puts its albedo back on it,
// instead of passing through as 0.

#pragma once

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// The fill radius: 2 r_max, as far as the filter's halo holds the inputs.
inline int
hole_fill_radius(const FilterOptions& opt)
{
    return 2 * opt.r_max;
}

/// The light at receiver (x, y), per RGB channel, from the fit points
/// within hole_fill_radius(): the plane fitted to their z with the weights
/// g(q; (x, y)) exp(-d^2 / r_max^2), at (x, y), within the range of those
/// z. False when no fit point of its surface is that near.
bool
hole_light(const FilterInputs& in, const FilterOptions& opt, int x, int y,
           float light[3]);

}  // namespace detail
}  // namespace zdenoise
