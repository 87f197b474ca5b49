// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The low-frequency energy correction of docs/FILTER.md section 7b: the
// filtered light scaled, where its blur differs from the input's by more
// than the input's noise at that scale explains, towards the input's.

#pragma once

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// How many pixels beyond an output pixel the correction of radius
/// `radius` reads: three box passes of `radius` and the noise estimate's
/// one neighbour.
inline int
energy_reach(int radius)
{
    return radius > 0 ? 3 * radius + 1 : 0;
}

/// Section 7b over roi: dst's channels 0-2 set to `filtered`'s (the
/// filter's result over `area`: roi widened by energy_reach(), clipped to
/// the frame), scaled by the correction read from it and from `quotient`
/// and `albedo` over `area`. Pixels the filter left as they were are
/// neither read nor changed.
void
correct_energy(ImageBuf& dst, const ImageBuf& filtered, const ImageBuf& quotient,
               const ImageBuf& albedo, float albedo_eps, int radius, ROI roi,
               ROI area, int nthreads);

}  // namespace detail
}  // namespace zdenoise
