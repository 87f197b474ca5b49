// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The filter's row kernels: the value factors and radiance range of a
// window fitted on the pyramid (docs/FILTER.md 5.1); the fit's, the
// splat's and the guide weights' are fit_kernel.cpp, splat_kernel.cpp and
// guide_kernel.cpp. They are built twice
// (baseline x86-64 and AVX2, picked at run time: ZDENOISE_ROW_KERNEL) and
// the only file compiled without FMA contraction and trapping math
// (src/CMakeLists.txt), so that every build computes the same floats and
// the selects in their lanes vectorise (section 8).

#pragma once

#include <cstdint>

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// The largest value term exp_neg() takes: weights never underflow.
constexpr float kValueClamp = 30.0f;
/// The largest quadrant blending weight w_m (section 6).
constexpr double kMaxWm = 1e6;

/// The range of the radiance of a window's fit points (those of weight >
/// 0), per channel, in kLanes partial minima and maxima: no fit of the
/// window predicts radiance outside it (section 6).
struct RangeLanes {
    float llo[3][kLanes], lhi[3][kLanes];
    void clear();
};

/// The whole range of a window, per channel (llo > lhi when no point).
struct WindowRange {
    float llo[3], lhi[3];
    explicit WindowRange(const RangeLanes& lanes);
    WindowRange() = default;
    /// No point yet: llo = +inf, lhi = -inf.
    static WindowRange empty();
    /// Whether a point was added (not empty()).
    bool has_points() const { return llo[0] <= lhi[0]; }
    /// Extend the range by one point's radiance.
    void add(float l0, float l1, float l2)
    {
        const float l[3] = { l0, l1, l2 };
        for (int ch = 0; ch < 3; ++ch) {
            llo[ch] = l[ch] < llo[ch] ? l[ch] : llo[ch];
            lhi[ch] = l[ch] > lhi[ch] ? l[ch] : lhi[ch];
        }
    }
};

/// For a window fitted on the pyramid (docs/FILTER.md 5.1), what fit_row
/// leaves at full resolution for the splat: each point's value factor
/// exp(-vt) into `values` and the radiance range of the points with
/// fit_weight > 0 into `range`, for one row segment of n points.
void
value_row(const float* __restrict fit_weight, const float* __restrict zl,
          const float* __restrict l0, const float* __restrict l1,
          const float* __restrict l2, float* __restrict values,
          RangeLanes* __restrict range, int n, float mean, float value_scale);

/// A solved plane's coefficients as floats, for the splat kernel.
struct PlaneCoeffs {
    float c[3] = {}, a[3] = {}, b[3] = {};
    float hat[6] = {};  ///< Plane::hat
};

}  // namespace detail
}  // namespace zdenoise
