// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The filter's row kernels: the value factors and radiance range of a
// window fitted on the pyramid (docs/FILTER.md 5.1) and the guide weights
// (section 4); the fit's and the splat's are fit_kernel.cpp and
// splat_kernel.cpp. They are built twice
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

/// What the guide weight of a row needs of its centre.
struct GuideCentre {
    float n0[3];           ///< the centre's normal (0: none)
    float zeta0, gx, gy;   ///< its inverse depth and the plane's slopes
    float depth_tolerance;
    float normal_cut;
    uint32_t id0;          ///< its plain id's bits
    float dx0, dy;         ///< offset of the row's first pixel
};

/// g of section 4 for the n pixels of one row, before the normal power and
/// the Cryptomatte coverage: the normals' cosine d (1 where neither has
/// one) where every test passes, else 0.
void
guide_row(const uint32_t* __restrict cls, const float* __restrict normal,
          const float* __restrict invdepth, const float* __restrict ids,
          float* __restrict g, int n, const GuideCentre& c, bool depth,
          bool plain_id);

/// Multiply g by the Cryptomatte overlap of each of n pixels with the
/// centre p0 (k (id, coverage) pairs a pixel).
void
coverage_row(const float* __restrict ids, const float* __restrict p0,
             float* __restrict g, int n, int k);

}  // namespace detail
}  // namespace zdenoise
