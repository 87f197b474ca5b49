// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The noise estimate's 5x5 median (docs/FILTER.md section 3) as a Highway
// kernel, dispatched at run time as the filter's other kernels. It takes
// only minima and maxima of the 25 values, so every target returns the
// value the scalar median() (noise_estimate.h) returns: the 13th smallest.

#pragma once

namespace zdenoise {
namespace detail {

/// For n pixels x = 0..n-1: med[x] = the median of the 25 values
/// rows[dy][x + dx], dy, dx = 0..4 (the 5x5 box whose top-left is x), or
/// NaN where one of them is NaN (the caller takes those pixels one by
/// one, leaving the NaN out). rows[dy] must be readable at [0, n + 4).
void median5x5_row(const float* const rows[5], int n, float* med);

}  // namespace detail
}  // namespace zdenoise
