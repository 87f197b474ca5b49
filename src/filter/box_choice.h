// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The box core's choice (docs/FILTER.md 15.3; box_choice.cpp): each
// candidate's risk against the radius-1 candidate, pooled over the pixels
// around that show the same light, and the candidates blended by it.

#pragma once

#include <vector>

#include "box_regression.h"

namespace zdenoise {
namespace detail {

struct FilterInputs;

/// How far the choice reads the candidates around an output pixel.
constexpr int kChoiceReach = 7;

/// The light of every pixel of `roi` into acc (3 a pixel) and 1 into wsum
/// (0 where no candidate reaches: passed through), and the blend's mean
/// radius into `radius` (1 a pixel). `cands` cover `rr` = roi and
/// kChoiceReach around it (clipped to the frame): candidate 0 the input,
/// candidate 1 radius 1, candidate `guide` the radius whose light guides
/// the pooling (8).
void blend_candidates(const FilterInputs& in,
                      const std::vector<BoxCandidate>& cands, int guide,
                      const ROI& rr, const ROI& roi, std::vector<double>& acc,
                      std::vector<double>& wsum, std::vector<float>& radius,
                      int nthreads);

}  // namespace detail
}  // namespace zdenoise
