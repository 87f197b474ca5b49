// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The guide kernels (docs/FILTER.md section 4; docs/PERFORMANCE.md "Vector
// kernels"): the guide weights of a row of pixels around a centre, and what
// a window's growth keeps of them (fit weights, <z>'s sums, the radiance
// range), written with Google Highway, compiled for every instruction set
// src/simd_targets.cpp lists and dispatched at run time.
//
// The guides are planar (FilterInputs): a vector of pixels reads each
// plane with one load. Every plane has kPlanePadding floats after its last
// pixel, so the kernels read whole vectors; they write only the n pixels
// asked for (a window's cache holds the rows around them). Built without
// FMA contraction: every target computes the floats of the scalar code,
// so a window stops at the same radius whatever the CPU.

#pragma once

#include <cstdint>
#include <vector>

#include "row_kernels.h"

namespace zdenoise {
namespace detail {

/// The guide weights g(q; p0) of n pixels of one row: pointers at the
/// row's first pixel, and what they need of the centre p0.
struct GuideRow {
    const uint32_t* cls;
    const float* normal[3] = { nullptr, nullptr, nullptr };  ///< null: none
    const float* invdepth  = nullptr;                        ///< null: none
    /// The id planes (FilterInputs::ids.data()) and the row's first pixel
    /// in them.
    const std::vector<float>* ids = nullptr;
    size_t first                  = 0;
    int id_pairs                  = 0;  ///< as FilterInputs::id_pairs
    int n                         = 0;

    float n0[3] = {};  ///< the centre's normal (0: none)
    float zeta0 = 0, gx = 0, gy = 0;  ///< its inverse depth and the slopes
    float depth_tolerance = 0, normal_cut = 0;
    uint32_t id0        = 0;        ///< its plain id's bits
    const float* pairs0 = nullptr;  ///< its (id, coverage) pairs
    float dx0 = 0, dy = 0;          ///< offset of the row's first pixel
    float normal_power = 4.0f;  ///< w_n = d^normal_power

    float* g;  ///< receives g(q; p0), 0 for pixels that are no surface
};

/// g(q; p0) of section 4 for one row: the normal, depth and plain id tests,
/// the normal power, and the Cryptomatte overlap.
void
guide_row(const GuideRow& row);

/// A row segment of a window's growth: n pixels from plane index `pixel`,
/// at index `cache` of the window's caches.
struct GrowSegment {
    size_t pixel, cache;
    int n;
};

/// What a window's growth keeps of the guide weights g of its new row
/// segments: a point takes part where g > 0 and it is a fit point.
struct GrowRing {
    const uint32_t* cls;  ///< planes at pixel index 0
    const float* zl;
    const float* fit_prior;
    const float* lfit[3];
    const float* g;     ///< the window's caches at index 0
    float* fit_weight;  ///< receives g fit_prior where a point takes part, else 0
    const GrowSegment* segments;
    int count;
    /// Add each taking-part point's zl and its count (the window's <z>).
    double zsum = 0.0;
    int zcount  = 0;
    /// Extended by the radiance of the points of fit weight > 0.
    WindowRange range;
};

/// Fill ring.fit_weight over its segments and add them to zsum, zcount
/// and range.
void
grow_ring(GrowRing& ring);

}  // namespace detail
}  // namespace zdenoise
