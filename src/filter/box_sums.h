// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Box sums whose cost per pixel does not depend on the radius, and whose
// every sum is added in an order fixed by the frame, not by the region
// held (box_sums.cpp): the box core's (docs/FILTER.md section 15) normal
// equations, splats and the choice's noise all go through box_sum_planes().

#pragma once

#include <vector>

#include "internal.h"

namespace zdenoise {
namespace detail {

/// floor(a / b) for b > 0: the block or cell, anchored at the frame's
/// origin, that frame coordinate a lies in.
inline int
floor_div(int a, int b)
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/// Planes of T over one region, plane after plane, `width` x `height`
/// each, row-major.
template<class T>
struct Planes {
    int width = 0, height = 0, count = 0;
    std::vector<T> data;

    Planes() = default;
    Planes(int w, int h, int n)
        : width(w), height(h), count(n), data(size_t(w) * size_t(h) * size_t(n), T(0))
    {
    }
    size_t plane_size() const { return size_t(width) * size_t(height); }
    T* plane(int k) { return data.data() + size_t(k) * plane_size(); }
    const T* plane(int k) const { return data.data() + size_t(k) * plane_size(); }
};

/// The sums over the (2r+1)^2 box around every pixel of each plane of
/// `in` into `out` (shaped like it; `out` may be `in`). `x0`, `y0` are the frame coordinates
/// of the planes' first pixel, relative to the frame's origin; values
/// beyond the planes count as 0, which is exact at the frame's edges.
/// A sum is exact where its box lies within the planes or beyond them only
/// outside the frame; elsewhere (within r of a region edge inside the
/// frame) it is no result. Each sum is the 1-D van Herk / Gil-Werman
/// split: a suffix and a prefix within blocks of 2r+1 anchored at the
/// frame's origin, in x then in y, so a pixel's sum is added in the same
/// order whatever region holds it: bit-identical for any tile, strip, ROI
/// and thread count, at three additions a pixel a pass for any r.
template<class T>
void box_sum_planes(const Planes<T>& in, Planes<T>& out, int x0, int y0,
                    int r, int nthreads);

}  // namespace detail
}  // namespace zdenoise
