// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The feature regression's per-window kernels (feature_regression_kernels.h
// says what each computes and how a window is laid out). Highway compiles
// this file once per target: foreach_target.h includes it again for each.

#include <limits>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "filter/feature_regression_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

#include "internal.h"
#include "feature_regression_kernels.h"

HWY_BEFORE_NAMESPACE();
namespace zdenoise {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<float>;
using V = hn::Vec<D>;
static_assert(HWY_LANES(float) <= kFeaturePlanePadding,
              "a vector must fit in the planes' padding");
using M = hn::Mask<D>;
using DU = hn::RebindToUnsigned<D>;

/// One vector of a window row: its points' features and weight. The lanes
/// past the row's last point read the pixels after it, which are finite.
struct Points {
    V x[kWindowFeatures];
};

/// The features of the points at plane index j (window column u, row dy).
HWY_INLINE Points
load_features(const FeaturePlanes& p, const WindowExtent& e, size_t j, V dx, V dy)
{
    const D d;
    Points pt;
    const V inv_r = hn::Set(d, 1.0f / float(e.radius));
    pt.x[0] = hn::Set(d, 1.0f);
    pt.x[1] = hn::Mul(dx, inv_r);
    pt.x[2] = hn::Mul(dy, inv_r);
    for (int c = 0; c < 3; ++c)
        pt.x[3 + c] = p.normal[c]
                          ? hn::Sub(hn::LoadU(d, p.normal[c] + j),
                                    hn::Set(d, p.normal[c][e.centre]))
                          : hn::Zero(d);
    if (p.invdepth) {
        const float c = p.invdepth[e.centre];
        pt.x[6] = hn::Mul(hn::Sub(hn::LoadU(d, p.invdepth + j), hn::Set(d, c)),
                          hn::Set(d, 1.0f / c));
    } else {
        pt.x[6] = hn::Zero(d);
    }
    return pt;
}

/// Calls f(j, k, dx, dy, lanes_left, x, y) for each vector of the window's
/// rows: j the plane index of its first point (x, y), k its index in the
/// window buffers.
template <class F>
HWY_INLINE void
for_each_vector(const FeaturePlanes& p, const WindowExtent& e, F&& f)
{
    const D d;
    const int lanes = int(hn::Lanes(d));
    const int n = e.xhi - e.xlo + 1;
    for (int y = e.ylo; y <= e.yhi; ++y) {
        const size_t row = size_t(y) * size_t(p.width);
        const size_t krow = size_t(y - e.ylo) * size_t(e.row_stride);
        const V dy = hn::Set(d, float(y - e.y0));
        for (int u = 0; u < n; u += lanes) {
            const V dx = hn::Add(hn::Iota(d, 0.0f), hn::Set(d, float(e.xlo + u - e.x0)));
            f(row + size_t(e.xlo + u), krow + size_t(u), dx, dy, n - u, e.xlo + u, y);
        }
    }
}

void
WindowWeights(const FeaturePlanes& p, const WindowExtent& e,
              const CentrePatch& centre, float patch_k, float* weight)
{
    const D d;
    const DU du;
    const V zero = hn::Zero(d), one = hn::Set(d, 1.0f);
    const V k2 = hn::Set(d, patch_k * patch_k);
    const V floor_scale = hn::Set(d, 1e-4f), tiny = hn::Set(d, 1e-30f);
    const V inv_r2 = hn::Set(d, 1.0f / float(e.radius * e.radius));
    const int pr = (p.pilot_width - p.width) / 2;
    const uint32_t id0 = p.id ? p.id[e.centre] : 0u;
    for_each_vector(p, e, [&](size_t j, size_t k, V dx, V dy, int left, int x, int y) {
        // The pilot index of the point: the pilot planes have pr more
        // columns on each side and pr more rows above.
        const size_t pj = size_t(y + pr) * size_t(p.pilot_width) + size_t(x + pr);
        V dist = zero, terms = zero;
        for (int t = 0; t < centre.count; ++t) {
            const size_t at = size_t(ptrdiff_t(pj) + centre.shift[t]);
            const V la = hn::Set(d, centre.l[t]), va = hn::Set(d, centre.v[t]);
            const V lb = hn::LoadU(d, p.pilot_l + at), vb = hn::LoadU(d, p.pilot_v + at);
            const M inside = hn::Gt(hn::LoadU(d, p.pilot_in + at), zero);
            const V diff = hn::Sub(la, lb);
            // A 1 % difference is always tolerated: the pilot's own bias.
            const V floor = hn::MulAdd(floor_scale, hn::MulAdd(la, la, hn::Mul(lb, lb)), tiny);
            const V num = hn::Sub(hn::Mul(diff, diff), hn::Add(va, hn::Min(va, vb)));
            const V den = hn::MulAdd(k2, hn::Add(va, vb), floor);
            dist = hn::Add(dist, hn::IfThenElseZero(inside, hn::Div(num, den)));
            terms = hn::Add(terms, hn::IfThenElseZero(inside, one));
        }
        // d2 <= 0 or not a number: the patch weight is 1 (std::max(0, d2)).
        const V d2 = hn::Div(dist, hn::Max(terms, one));
        const V d2pos = hn::IfThenElseZero(hn::Gt(d2, zero), d2);
        const V sp = hn::Mul(hn::MulAdd(dx, dx, hn::Mul(dy, dy)), inv_r2);
        const V w = hn::Exp(d, hn::Neg(hn::Add(sp, d2pos)));
        M take = hn::And(hn::FirstN(d, size_t(left)),
                         hn::Gt(hn::LoadU(d, p.valid + j), zero));
        if (p.id)
            take = hn::And(take, hn::RebindMask(d, hn::Eq(hn::LoadU(du, p.id + j),
                                                          hn::Set(du, id0))));
        hn::StoreU(hn::IfThenElseZero(hn::And(take, hn::Gt(w, zero)), w), d, weight + k);
    });
}

/// Rows A0 .. A1 - 1 of the normal equations: m[a][0..a] and b[a][0..2].
template <int A0, int A1>
HWY_INLINE void
sums_rows(const FeaturePlanes& p, const WindowExtent& e, const float* weight,
          WindowSums& s)
{
    const D d;
    constexpr int kM = (A1 * (A1 + 1) - A0 * (A0 + 1)) / 2;
    V m[kM], b[A1 - A0][3];
    for (V& v : m)
        v = hn::Zero(d);
    for (auto& row : b)
        for (V& v : row)
            v = hn::Zero(d);
    for_each_vector(p, e, [&](size_t j, size_t k, V dx, V dy, int, int, int) {
        const Points pt = load_features(p, e, j, dx, dy);
        const V w = hn::LoadU(d, weight + k);
        V z[3];
        for (int c = 0; c < 3; ++c)
            z[c] = hn::LoadU(d, p.z[c] + j);
        int i = 0;
        for (int a = A0; a < A1; ++a) {
            const V wa = hn::Mul(w, pt.x[a]);
            for (int bb = 0; bb <= a; ++bb, ++i)
                m[i] = hn::MulAdd(wa, pt.x[bb], m[i]);
            for (int c = 0; c < 3; ++c)
                b[a - A0][c] = hn::MulAdd(wa, z[c], b[a - A0][c]);
        }
    });
    int i = 0;
    for (int a = A0; a < A1; ++a) {
        for (int bb = 0; bb <= a; ++bb, ++i)
            s.m[a][bb] = double(hn::GetLane(hn::SumOfLanes(d, m[i])));
        for (int c = 0; c < 3; ++c)
            s.b[a][c] = double(hn::GetLane(hn::SumOfLanes(d, b[a - A0][c])));
    }
}

void
WindowSums_(const FeaturePlanes& p, const WindowExtent& e, const float* weight,
            WindowSums& s)
{
    // Three passes keep each pass's accumulators (22, 17, 10) in registers.
    static_assert(kWindowFeatures == 7, "the passes below cover rows 0..6");
    sums_rows<0, 4>(p, e, weight, s);
    sums_rows<4, 6>(p, e, weight, s);
    sums_rows<6, 7>(p, e, weight, s);
    const D d;
    const V zero = hn::Zero(d);
    const V inf = hn::Set(d, std::numeric_limits<float>::infinity());
    V lo[3], hi[3];
    for (int c = 0; c < 3; ++c)
        lo[c] = hn::Set(d, s.lo[c]), hi[c] = hn::Set(d, s.hi[c]);
    for_each_vector(p, e, [&](size_t j, size_t k, V, V, int, int, int) {
        const M used = hn::Gt(hn::LoadU(d, weight + k), zero);
        for (int c = 0; c < 3; ++c) {
            const V l = hn::LoadU(d, p.radiance[c] + j);
            lo[c] = hn::Min(lo[c], hn::IfThenElse(used, l, inf));
            hi[c] = hn::Max(hi[c], hn::IfThenElse(used, l, hn::Neg(inf)));
        }
    });
    for (int c = 0; c < 3; ++c) {
        s.lo[c] = hn::GetLane(hn::MinOfLanes(d, lo[c]));
        s.hi[c] = hn::GetLane(hn::MaxOfLanes(d, hi[c]));
    }
}

void
WindowSplat(const FeaturePlanes& p, const WindowExtent& e, const float* weight,
            const WindowSolution& fit, float* const splat[kSplatPlanes])
{
    constexpr int F = kWindowFeatures;
    const D d;
    const V zero = hn::Zero(d);
    const V largest = hn::Set(d, std::numeric_limits<float>::max());
    for_each_vector(p, e, [&](size_t j, size_t k, V dx, V dy, int, int, int) {
        const Points pt = load_features(p, e, j, dx, dy);
        // x^T M^-1 x over the lower triangle (off-diagonal entries doubled).
        V q = zero;
        for (int a = 0; a < F; ++a) {
            V row = hn::Set(d, fit.inverse[a][0]);
            for (int b = 1; b <= a; ++b)
                row = hn::MulAdd(hn::Set(d, fit.inverse[a][b]), pt.x[b], row);
            q = hn::MulAdd(row, pt.x[a], q);
        }
        const V w = hn::LoadU(d, weight + k);
        V hat = zero;
        for (int c = 0; c < 3; ++c) {
            V v = hn::Set(d, fit.beta[0][c]);
            for (int a = 1; a < F; ++a)
                v = hn::MulAdd(pt.x[a], hn::Set(d, fit.beta[a][c]), v);
            // The bounds saturate at the largest float, a fit's Inf or NaN
            // (huge quotients) is bounded too (splat_kernel.cpp says why).
            const V inv = hn::LoadU(d, p.inv_scale[c] + j);
            const V lo = hn::Min(hn::Max(hn::Mul(hn::Set(d, fit.lo[c]), inv), hn::Neg(largest)), largest);
            const V hi = hn::Max(hn::Min(hn::Mul(hn::Set(d, fit.hi[c]), inv), largest), hn::Neg(largest));
            const V clamped = hn::Min(hn::Max(hn::IfThenElseZero(hn::Eq(v, v), v), lo), hi);
            // Where clamped the value no longer moves with z (up to the
            // point attaining the bound): no hat term.
            hat = hn::Add(hat, hn::IfThenElseZero(hn::Eq(clamped, v),
                                                  hn::Set(d, kLumaWeights[c])));
            hn::StoreU(hn::Mul(w, clamped), d, splat[kSplatR + c] + k);
        }
        hn::StoreU(w, d, splat[kSplatWeight] + k);
        hn::StoreU(hn::Mul(hn::Mul(hn::Mul(w, w), q), hat), d, splat[kSplatHat] + k);
    });
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace zdenoise
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace zdenoise {
namespace detail {

HWY_EXPORT(WindowWeights);
HWY_EXPORT(WindowSums_);
HWY_EXPORT(WindowSplat);

void
window_weights(const FeaturePlanes& p, const WindowExtent& e,
               const CentrePatch& centre, float patch_k, float* weight)
{
    HWY_DYNAMIC_DISPATCH(WindowWeights)(p, e, centre, patch_k, weight);
}

void
window_sums(const FeaturePlanes& p, const WindowExtent& e, const float* weight,
            WindowSums& sums)
{
    HWY_DYNAMIC_DISPATCH(WindowSums_)(p, e, weight, sums);
}

void
window_splat(const FeaturePlanes& p, const WindowExtent& e, const float* weight,
             const WindowSolution& fit, float* const splat[kSplatPlanes])
{
    HWY_DYNAMIC_DISPATCH(WindowSplat)(p, e, weight, fit, splat);
}

}  // namespace detail
}  // namespace zdenoise
#endif
