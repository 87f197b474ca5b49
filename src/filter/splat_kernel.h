// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The splat kernel (docs/FILTER.md section 6; docs/PERFORMANCE.md "Vector
// kernels"): the splat weights and blended plane values of one row of a
// window, written with Google Highway, compiled for every instruction set
// src/simd_targets.cpp lists and dispatched at run time.
//
// A row is one call, a vector of pixels at a time: each lane takes the
// quadrant plane of its side of the centre (dx < 0 or dx >= 0), so a
// window of radius up to 7 is one AVX-512 vector a row. Every input plane
// and window cache has kPlanePadding floats after its last pixel and every
// output kPlanePadding floats after the row: the kernel reads and writes
// whole vectors, and the lanes past the row get weight 0.

#pragma once

#include "row_kernels.h"

namespace zdenoise {
namespace detail {

/// One row of a window's splat: pointers at its first output pixel.
struct SplatRow {
    const uint32_t* cls;
    const float* g;           ///< cached guide weights
    const float* spatial;     ///< e(dx)
    const float* fit_weight;  ///< cached; > 0 where `values` holds exp(-vt)
    const float* values;
    const float* zl;
    const float* inv_albedo[3];  ///< 1 / (La + eps) of the receivers
    int n;                    ///< pixels
    float dx0;                ///< dx of the first pixel
    float ey, inv_r, v;       ///< e(dy), 1/R, dy/R
    float mean, value_scale;  ///< for exp(-vt) where the fit did not keep it
    float power;              ///< quadrant_power
    /// The whole window's plane and the quadrant planes of the pixels left
    /// (dx < 0) and right (dx >= 0) of the centre (= whole where the
    /// quadrant has none).
    PlaneCoeffs whole, left, right;
    WindowRange range;  ///< A is clamped to it
    float* s;     ///< receives each point's weight (0: receives nothing)
    float* a[3];  ///< receives weight times the blended plane value A
    /// Null, or receive the terms of the hat diagonal (docs/SELECTION.md
    /// 2.5, 2.6): s H_l (1 - c (zl - A_l)), s c and s c A_l, with H_l the
    /// luminance of the blended fits' derivatives in the point's own value
    /// and c the value term's derivative.
    float* hat[3] = { nullptr, nullptr, nullptr };
};

/// The splat weights and blended plane values of section 6 for one row.
void
splat_row(const SplatRow& row);

/// Add a splat_row()'s output for n pixels to the output's sums (double,
/// interleaved as the splat's accumulators hold them): acc (3 a pixel) +=
/// a, wsum += s, and when hat is set hat_sums (kHatSums a pixel) += hat,
/// at the pixels with s > 0 only.
void
accumulate_row(const SplatRow& row, int n, double* acc, double* wsum,
               double* hat_sums);

}  // namespace detail
}  // namespace zdenoise
