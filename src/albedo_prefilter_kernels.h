// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The albedo prefilter's row kernels (docs/FILTER.md section 12), written
// with Google Highway and dispatched at run time as the filter's
// (src/filter/feature_regression_kernels.h). They use no fused multiply-add
// and keep the scalar code's order of operations, so every target computes
// the same floats as albedo_prefilter.cpp did point by point.

#pragma once

namespace zdenoise {
namespace detail {

/// For n points: d[x] = the mean over the three channels of
/// ((a_p - a_q)^2 - (v_p + min(v_p, v_q))) / (floor + v_p + v_q), and
/// dn[x] = 1, where that is a number, else both 0. ap, vp, aq, vq: the
/// albedo and its variance, planar, at p's and q's first point.
void patch_distance_row(const float* const ap[3], const float* const vp[3],
                        const float* const aq[3], const float* const vq[3],
                        int n, float variance_floor, float* d, float* dn);

/// s[k] = d[k] + d[k - 1] + d[k + 1] (in that order, the terms outside
/// 0..n-1 left out), likewise sn from dn.
void box3_row(const float* d, const float* dn, int n, float* s, float* sn);

}  // namespace detail
}  // namespace zdenoise
