// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The fit kernel (docs/FILTER.md section 5; docs/PERFORMANCE.md "Vector
// kernels"): the weighted sums of a window's five-plane fit, written with
// Google Highway, compiled for every instruction set src/simd_targets.cpp
// lists and dispatched at run time.
//
// Layout. A call covers rows of the window that share the sign of dy (the
// cells of section 5 split there) and all its columns. It walks a vector
// of columns down the rows, so that each lane is one column and its sums
// stay in registers: the sums of a column are those of its points over the
// rows. Everything that is constant along a column (dx and its powers, the
// column's side of the centre) is applied once per column afterwards, by
// add_columns(), in double. dy is constant along a row, so a point needs
// the fit's sums without dx only: 14 instead of 23.
//
// Every plane and window cache has kPlanePadding floats after its last
// pixel: the kernel reads whole vectors and leaves the lanes past the last
// column out of every sum.

#pragma once

#include <cstddef>

#include "plane_fit.h"

namespace zdenoise {
namespace detail {

/// The sums of a column's points, in this order: w {1, dy, dy^2},
/// w z_c (3), w z_c dy (3), w^2 Vs {1, dy, dy^2}, w^2 sigma^2, count.
enum ColumnSum {
    kColW, kColWy, kColWyy,
    kColZ0, kColZ1, kColZ2,
    kColZ0y, kColZ1y, kColZ2y,
    kColN, kColNy, kColNyy,
    kColS2, kColCount,
    kColumnSums
};

/// Rows of a window that share the sign of dy, and its columns.
struct FitColumns {
    /// The fit's planes (zl, zfit, vs, sigma), at the first point of the
    /// first row, `stride` floats a row.
    const float* zl = nullptr;
    const float* z[3] = {};
    const float* vs = nullptr;
    const float* sigma = nullptr;
    size_t stride = 0;
    /// The window caches at the same point, `cache_stride` floats a row:
    /// the fit weight without the spatial and value terms (0: not a good
    /// point) and, written, each point's value factor exp(-vt).
    const float* fit_weight = nullptr;
    float* values = nullptr;
    size_t cache_stride = 0;
    const float* spatial = nullptr;  ///< e(dx) of each column
    const float* ey = nullptr;       ///< e(dy) of each row
    int columns = 0, rows = 0;
    float dy0 = 0.0f;  ///< dy of the first row (rows step by 1)
    float mean = 0.0f, value_scale = 0.0f;
    /// Receives kColumnSums planes of `columns` floats (and kPlanePadding),
    /// `sums_stride` floats apart.
    float* sums = nullptr;
    size_t sums_stride = 0;
};

/// The column sums of the rows and columns `in` describes.
void
fit_columns(const FitColumns& in);

/// Add the column sums of a row group to the nine cells of a fit, in
/// window coordinates of radius R: column j has offset dx0 + j and lies in
/// cell `left`, `centre` or `right` by the sign of its offset. Returns the
/// group's sum of w^2 sigma^2.
double
add_columns(const float* sums, size_t sums_stride, int columns, float dx0,
            double R, const int cell_of_side[3], FitMoments cells[9]);

}  // namespace detail
}  // namespace zdenoise
