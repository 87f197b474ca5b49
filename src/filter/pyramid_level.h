// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The pyramid's first level (docs/FILTER.md 5.1): the fit points averaged
// over blocks of 2x2 pixels, what large windows fit on (a quarter of the
// points) before splatting at full resolution.

#pragma once

#include <vector>

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// Floor of v / 2 for any sign: the block of pixel offset v (from the
/// frame's origin). Blocks are anchored at the frame's origin, not at a
/// region's corner, so that every strip, tile and data window origin sees
/// the same blocks.
inline int
block_of(int v)
{
    return v >= 0 ? v / 2 : -((1 - v) / 2);
}

/// Level 1 of the pyramid over the blocks of a fine level's region: a
/// FilterInputs whose pixel (bx, by) stands for the fine pixels
/// x0 + 2bx .. x0 + 2bx + 1, y0 + 2by .. y0 + 2by + 1, with (x0, y0) the
/// fine level's frame origin (fine.image's begin), so that the guide weight
/// and the fit's row kernel read it as they read the fine level.
///
/// A block is a fit point (kSurface | kFitPoint) only when its four pixels
/// lie in the fine region, are surface, carry the same object id bits and
/// an inverse depth within depth_tolerance of their mean, and one of them
/// is a good fit point: a block that straddles an edge takes no part.
/// Then, with p_i the fine fit priors (exp(-sigma), 0 at points that are
/// not good) and P their sum:
///   fit_prior = P (the block weighs what its points would),
///   zl, zfit, lfit = sum p_i x_i / P,
///   vs = sum p_i^2 vs_i / P^2 and sigma = sqrt(sum p_i^2 sigma_i^2) / P
///   (the noise of that mean: a fit's sums of w^2 vs and w^2 sigma^2 come
///   out as the fine points' would),
///   normal = the normalised mean, invdepth = the mean, ids = the first
///   pixel's.
/// zl_sum and fit_points hold the sum of zl over the block's fit points
/// and their number, for the window mean <z>.
struct PyramidLevel {
    FilterInputs in;
    std::vector<float> zl_sum;
    std::vector<float> fit_points;
};

/// Build level 1 over the blocks that touch fine.region.
void
build_pyramid_level(PyramidLevel& level, const FilterInputs& fine,
                    const FilterOptions& opt, int nthreads);

}  // namespace detail
}  // namespace zdenoise
