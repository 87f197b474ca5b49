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

/// The last stages of a filter whose light over `roi` is acc / wsum (3
/// doubles and 1 a pixel of roi): the outliers' light spread over it
/// (section 3a), then the output normalised, passed through where wsum is
/// 0 or a channel does not receive (section 7), into dst. Adds the pixel
/// statistics of `counted` to totals. The box core's end (box_core.cpp).
bool finish_filtered_light(ImageBuf& dst, const ImageBuf& quotient,
                           const FilterInputs& in, const FilterOptions& opt,
                           ROI roi, const ROI& counted, int nthreads,
                           FilterStats& totals, std::vector<double>&& acc,
                           std::vector<double>&& wsum);

}  // namespace detail
}  // namespace zdenoise
