// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The filter's row kernels: the inner loops over one row segment of a
// window for the fit sums (docs/FILTER.md section 5), the splat (section 6)
// and the guide weights (section 4). They are the only code built twice
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

/// The sums of one cell of a window's fit (section 5), kLanes partial sums
/// each, in pixel offsets dx, dy from the centre (window coordinates u =
/// dx/R, v = dy/R are applied once, in double, by FitMoments::add).
struct CellLanes {
    enum Sum {
        W, Wx, Wy, Wxx, Wxy, Wyy,  ///< w {1, dx, dy, dx^2, dx dy, dy^2}
        Z0, Z0x, Z0y, Z1, Z1x, Z1y, Z2, Z2x, Z2y,  ///< w z_c {1, dx, dy}
        N, Nx, Ny, Nxx, Nxy, Nyy,  ///< w^2 Vs {1, dx, dy, ...}
        S2,                        ///< w^2 sigma^2
        Count,                     ///< good points
        kSums
    };
    float lane[kSums][kLanes];
};

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
};

/// One row segment of a window for the fit: pointers at its first point.
struct FitRow {
    int n;              ///< points in the segment
    float dx0, dy;      ///< offset of the first point
    float ey;           ///< e(dy)
    float mean;         ///< <z>
    float value_scale;  ///< value_k / max(|<z>|, eps)
};


/// Add the points of one row segment to a cell, kLanes at a time; store
/// each point's value factor exp(-vt) in `values` (whole blocks: the
/// buffers are padded, and a store past the segment lands where a later
/// segment writes or nobody reads).
void
fit_row(const float* __restrict fit_weight, const float* __restrict spatial,
        const float* __restrict zl, const float* __restrict z0,
        const float* __restrict z1, const float* __restrict z2,
        const float* __restrict l0, const float* __restrict l1,
        const float* __restrict l2, const float* __restrict vs,
        const float* __restrict sigma, float* __restrict values,
        CellLanes* __restrict cell, RangeLanes* __restrict range,
        const FitRow& in);

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

/// One row segment of a window's splat, all of it in one quadrant:
/// pointers at its first point.
struct SplatRow {
    const uint32_t* cls;
    const float* g;           ///< cached guide weights
    const float* spatial;     ///< e(dx)
    const float* fit_weight;  ///< cached; > 0 where `values` holds exp(-vt)
    const float* values;
    const float* zl;
    int n;
    float dx0, ey, inv_r, v;  ///< dx of the first point, e(dy), 1/R, dy/R
    float mean, value_scale;  ///< for exp(-vt) where the fit did not keep it
    PlaneCoeffs whole, quadrant;  ///< quadrant = whole where it has none
    const float* inv_albedo[3];  ///< 1 / (La + eps) of the receivers
    WindowRange range;           ///< A is clamped to it
    float* s;     ///< receives each point's weight (0: receives nothing)
    float* a[3];  ///< receives weight times the blended plane value A
    /// Null, or receive the terms of the hat diagonal (docs/SELECTION.md
    /// 2.5, 2.6): s H_l (1 - c (zl - A_l)), s c and s c A_l, with H_l the
    /// luminance of the blended fits' derivatives in the point's own value
    /// and c the value term's derivative.
    float* hat[3] = { nullptr, nullptr, nullptr };
};


/// The splat weights and blended plane values of section 6 for one row
/// segment, by the kernel that fits quadrant_power.
void
splat_row(const SplatRow& in, float power);

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
