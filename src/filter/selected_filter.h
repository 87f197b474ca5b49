// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// regression_filter() with FilterOptions::select = 1: today's filter and the
// feature regression, chosen per pixel by their estimated error
// (docs/FILTER.md section 13; selected_filter.cpp).

#pragma once

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
bool filter_decoded(ImageBuf& dst, const ImageBuf& quotient,
                    const FilterInputs& in, const FilterOptions& opt, ROI roi,
                    const ROI& counted, int nthreads, FilterStats& totals,
                    ImageBuf* hat, std::vector<double>* spread_light = nullptr);

/// filter_halo() of options with select = 1, given the same options with
/// select = 0.
int selected_filter_halo(const FilterOptions& base);

/// regression_filter() with select = 1, after its argument checks: `options`
/// has its frame defined, `roi` lies in it, dst is prepared. Adds the
/// statistics of roi's windows (candidate 0's) and pixels to totals.
bool selected_regression_filter(ImageBuf& dst, const ImageBuf& quotient,
                                const ImageBuf& albedo, const Guides& guides,
                                const FilterOptions& options, ROI roi,
                                int nthreads, FilterStats& totals);

}  // namespace detail
}  // namespace zdenoise
