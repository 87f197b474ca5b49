// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The filter's row kernels (row_kernels.h says why they are a file of
// their own).

#include "row_kernels.h"

#include "internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace zdenoise {
namespace detail {

namespace {

/// exp(-t) for t in [0, kValueClamp] (NaN gives 1), branch-free so that it
/// vectorises: Cephes' expf reduction and polynomial, relative error within
/// 2e-7 like libm's expf.
[[gnu::always_inline]] inline float
exp_neg(float t)
{
    t              = t > 0.0f ? (t < kValueClamp ? t : kValueClamp) : 0.0f;
    const float x  = -t;
    // round(x log2(e)) by the 1.5 * 2^23 trick (no SSE4.1 round needed)
    const float fn = (x * 1.44269504088896341f + 12582912.0f) - 12582912.0f;
    const float r  = (x - fn * 0.693359375f) - fn * -2.12194440e-4f;
    float p        = 1.9875691500e-4f;
    p              = p * r + 1.3981999507e-3f;
    p              = p * r + 8.3334519073e-3f;
    p              = p * r + 4.1665795894e-2f;
    p              = p * r + 1.6666665459e-1f;
    p              = p * r + 5.0000001201e-1f;
    const float e  = p * (r * r) + r + 1.0f;
    const uint32_t bits = uint32_t(int(fn) + 127) << 23;  // 2^fn, fn in [-44, 0]
    float scale;
    std::memcpy(&scale, &bits, sizeof scale);
    return e * scale;
}

}  // namespace

ZDENOISE_ROW_KERNEL void
value_row(const float* __restrict fit_weight, const float* __restrict zl,
          const float* __restrict l0, const float* __restrict l1,
          const float* __restrict l2, float* __restrict values,
          RangeLanes* __restrict range, int n, float mean, float value_scale)
{
    for (int j = 0; j < n; j += kLanes) {
        for (int l = 0; l < kLanes; ++l) {
            const int q    = j + l;
            const bool use = q < n && fit_weight[q] > 0.0f;
            values[q] = exp_neg(value_scale * std::fabs(zl[q] - mean));
            const float lc[3] = { l0[q], l1[q], l2[q] };
#pragma GCC unroll 3
            for (int ch = 0; ch < 3; ++ch) {
                float& llo = range->llo[ch][l];
                float& lhi = range->lhi[ch][l];
                llo = use && lc[ch] < llo ? lc[ch] : llo;
                lhi = use && lc[ch] > lhi ? lc[ch] : lhi;
            }
        }
    }
}

void
RangeLanes::clear()
{
    for (int ch = 0; ch < 3; ++ch)
        for (int l = 0; l < kLanes; ++l) {
            llo[ch][l] = std::numeric_limits<float>::infinity();
            lhi[ch][l] = -std::numeric_limits<float>::infinity();
        }
}


WindowRange
WindowRange::empty()
{
    RangeLanes lanes;
    lanes.clear();
    return WindowRange(lanes);
}


WindowRange::WindowRange(const RangeLanes& r)
{
    for (int ch = 0; ch < 3; ++ch) {
        llo[ch] = *std::min_element(r.llo[ch], r.llo[ch] + kLanes);
        lhi[ch] = *std::max_element(r.lhi[ch], r.lhi[ch] + kLanes);
    }
}


}  // namespace detail
}  // namespace zdenoise
