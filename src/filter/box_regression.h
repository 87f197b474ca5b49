// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The box core's candidates (docs/FILTER.md 15.1-15.2; box_regression.cpp):
// one radius's regressions over every window, from box sums, splatted.
// Radii up to 4 run on pixels; larger ones on cells of r / 4 pixels, so
// that every radius costs about the same.

#pragma once

#include <vector>

#include <zdenoise/zdenoise.h>

namespace zdenoise {
namespace detail {

struct FilterInputs;

/// One candidate over the risk region: its light (3 floats a pixel, NaN
/// where no window reaches) and hat diagonal.
struct BoxCandidate {
    int radius = 0;  ///< 0: the input
    std::vector<float> rgb, hat;
};

/// The cell side of radius r: 1 (pixels) up to radius 4, then r / 4.
int box_cell(int r);

/// The candidate of radius r over `rr` (the output and the risk's pool
/// around it), from inputs decoded over a region that holds rr and
/// box_candidate_reach(r) around it. No result once opt.cancel is set.
void box_candidate(const FilterInputs& in, const FilterOptions& opt,
                   const ROI& rr, int r, BoxCandidate& cand, int nthreads);

/// How far a pixel of radius r's candidate reads around it.
int box_candidate_reach(int r);

}  // namespace detail
}  // namespace zdenoise
