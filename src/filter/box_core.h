// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The box core (docs/FILTER.md section 15, FilterOptions::core = 1): local
// linear regressions of the light on the pixel's position, normal and
// depth over square windows of radii 1, 2, 4, ... box_radius, each from
// box sums whose cost per pixel does not depend on the radius
// (box_sums.h), splatted by a second box pass, and per pixel a blend of
// the input and the radii by their estimated risks (box_choice.cpp).
// box_core.cpp.

#pragma once

#include <vector>

#include <zdenoise/zdenoise.h>

namespace zdenoise {
namespace detail {

struct FilterInputs;

/// The candidate radii of the box core: 1, 2, 4, ... up to
/// opt.box_radius (its last, also when not a power of 2).
std::vector<int> box_radii(const FilterOptions& opt);

/// What an output pixel of the box core depends on around it: the
/// largest radius's reach (box_candidate_reach()), the choice's and the
/// noise estimate's footprint.
int box_core_halo(const FilterOptions& opt);

/// The box core over `roi` from inputs decoded over a region holding roi
/// and box_core_halo() around it (clipped to opt.frame), into dst's RGB
/// (its other channels from the quotient, as filter_decoded()). With
/// opt.diagnostics, map 0 is the blend's mean radius (0: the input). Adds the
/// pixel statistics of `counted` to totals. Returns false with no
/// message when opt.cancel is set.
bool box_filter_decoded(ImageBuf& dst, const ImageBuf& quotient,
                        const FilterInputs& in, const FilterOptions& opt,
                        ROI roi, const ROI& counted, int nthreads,
                        FilterStats& totals);

}  // namespace detail
}  // namespace zdenoise
