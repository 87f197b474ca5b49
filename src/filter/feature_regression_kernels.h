// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The feature regression's per-window kernels (docs/FILTER.md section
// 13.2; docs/PERFORMANCE.md "Vector kernels"), written with Google Highway,
// compiled for every instruction set src/simd_targets.cpp lists and
// dispatched at run time:
//   window_weights()  patch distances on the pilot and each point's weight
//   window_sums()     the normal equations X^T W X, X^T W z and the range
//   window_splat()    each point's prediction, clamped, and its hat term
// feature_regression.cpp decodes the planes once, solves each window's
// normal equations in double and adds its splat to the output sums.
//
// A window is walked row by row over the planes of the whole region, a
// vector of points at a time; the lanes past a row's last point get weight
// 0 and so add nothing. Every plane is finite and 0 where the pixel takes
// no part, and has kFeaturePlanePadding floats after its last pixel.

#pragma once

#include <cstddef>
#include <cstdint>

namespace zdenoise {
namespace detail {

/// The features of a point, in this order: 1, dx / r, dy / r, its normal
/// minus the centre's (3), its inverse depth relative to the centre's.
/// Features without a guide are 0: the kernels' loops have one size, and
/// the solve leaves those features out.
constexpr int kWindowFeatures = 7;

/// Floats past the end of every plane and every window row: the widest
/// target's vector (AVX-512, 16 floats).
constexpr int kFeaturePlanePadding = 16;

/// The region's planes, row-major with `width` pixels a row.
struct FeaturePlanes {
    int width = 0;
    const float* valid = nullptr;  ///< 1 where the pixel takes part, else 0
    const uint32_t* id = nullptr;  ///< object id bits (null: none)
    const float* z[3] = {};        ///< the quotient (0 where not valid)
    const float* radiance[3] = {}; ///< z (albedo + eps) (likewise)
    const float* inv_scale[3] = {}; ///< 1 / (albedo + eps) (likewise)
    const float* normal[3] = {};   ///< unit normal (null: no guide)
    const float* invdepth = nullptr; ///< 1 / depth (null: no guide)
    /// The pilot's luminance and variance, and 1 inside the region, on the
    /// region grown by the patch radius (0 outside it), pilot_width a row.
    const float* pilot_l = nullptr;
    const float* pilot_v = nullptr;
    const float* pilot_in = nullptr;
    int pilot_width = 0;
};

/// One window clipped to the region: its centre, radius and rows.
struct WindowExtent {
    int x0 = 0, y0 = 0, radius = 0;
    int xlo = 0, xhi = 0, ylo = 0, yhi = 0;  ///< inclusive, region coordinates from 0
    size_t centre = 0;                       ///< the centre's plane index
    /// Floats a row of the window buffers (weight, splat): the clipped
    /// width rounded up to whole vectors, plus kFeaturePlanePadding.
    int row_stride = 0;
};

/// The centre's patch: for each patch offset whose pixel lies in the
/// region, its shift in the pilot planes and the pilot there.
struct CentrePatch {
    static constexpr int kMaxOffsets = 17 * 17;  ///< patch radius 8
    int count = 0;
    ptrdiff_t shift[kMaxOffsets];
    float l[kMaxOffsets], v[kMaxOffsets];
};

/// One window's normal equations, summed in float lanes whose sum is then
/// kept in double for the solve: m[a][b] = sum w x_a x_b (b <= a), b[a][c] = sum w x_a z_c.
struct WindowSums {
    double m[kWindowFeatures][kWindowFeatures];
    double b[kWindowFeatures][3];
    float lo[3], hi[3];  ///< radiance range of the points of weight > 0
};

/// A window's solution for window_splat(), in float: M^-1 as the lower
/// triangle of the quadratic form x^T M^-1 x (off-diagonal entries
/// doubled; 0 for the features left out), the coefficients, the range.
struct WindowSolution {
    float inverse[kWindowFeatures][kWindowFeatures];
    float beta[kWindowFeatures][3];
    float lo[3], hi[3];
};

/// The contributions window_splat() writes for each point.
enum SplatPlane { kSplatR, kSplatG, kSplatB, kSplatWeight, kSplatHat, kSplatPlanes };

/// weight (rows of e.row_stride) = [valid, same id] exp(-(dx^2 + dy^2) / r^2
/// - max(0, d2)), d2 the mean over the centre's patch offsets of the
/// variance-cancelled squared difference of the pilot's luminance
/// (FILTER.md 13.2), treated as 0 where it is not a number.
void window_weights(const FeaturePlanes& p, const WindowExtent& e,
                    const CentrePatch& centre, float patch_k, float* weight);

/// The sums over the points of weight > 0; sums.lo, hi start from the
/// caller's values.
void window_sums(const FeaturePlanes& p, const WindowExtent& e,
                 const float* weight, WindowSums& sums);

/// splat[c] = w clamp(x^T beta_c, lo_c / a_c, hi_c / a_c), splat[weight] =
/// w, splat[hat] = w^2 x^T M^-1 x times the luminance weights of the
/// channels not clamped; each plane e.row_stride a row.
void window_splat(const FeaturePlanes& p, const WindowExtent& e,
                  const float* weight, const WindowSolution& fit,
                  float* const splat[kSplatPlanes]);

}  // namespace detail
}  // namespace zdenoise
