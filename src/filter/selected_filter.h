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

/// filter_halo() of options with select = 1, given the same options with
/// select = 0.
int selected_filter_halo(const FilterOptions& base);

/// regression_filter() with select = 1, after its argument checks: `options`
/// has its frame defined, `roi` lies in it, dst is prepared. Adds the
/// statistics of the windows (candidate 0's) and pixels in `counted` to
/// totals.
bool selected_regression_filter(ImageBuf& dst, const ImageBuf& quotient,
                                const ImageBuf& albedo, const Guides& guides,
                                const FilterOptions& options, ROI roi,
                                const ROI& counted, int nthreads,
                                FilterStats& totals);

}  // namespace detail
}  // namespace zdenoise
