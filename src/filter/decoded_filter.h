// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Today's filter over inputs already decoded (decoded_filter.cpp): the
// inside of regression_filter(), which the selection runs as its
// candidate 0.

#pragma once

#include <vector>

#include <zdenoise/zdenoise.h>

namespace zdenoise {
namespace detail {

struct FilterInputs;

/// Today's filter (sections 2-7) over `roi` from inputs already decoded
/// over a region that holds roi and filter_halo(opt) around it (clipped to
/// opt.frame): the same pixels as regression_filter() (section 8), which
/// decodes tile by tile; the selection decodes once for its own stages and
/// candidate 0. dst must be prepared; `hat` (or null) receives the hat
/// diagonal, opt.diagnostics the maps, `spread_light` (or null) the
/// outliers' spread light over roi (3 doubles a pixel, spread_outliers()).
/// Adds the statistics of the windows and pixels in `counted` to totals.
/// Returns false with no message, dst not written, when opt.cancel is set.
bool filter_decoded(ImageBuf& dst, const ImageBuf& quotient,
                    const FilterInputs& in, const FilterOptions& opt, ROI roi,
                    const ROI& counted, int nthreads, FilterStats& totals,
                    ImageBuf* hat, std::vector<double>* spread_light = nullptr);

}  // namespace detail
}  // namespace zdenoise
