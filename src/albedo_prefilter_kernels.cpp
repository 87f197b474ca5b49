// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The albedo prefilter's row kernels (albedo_prefilter_kernels.h). Highway
// compiles this file once per target; each kernel runs whole vectors, then
// the remainder one lane at a time with the same operations.

#include <utility>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "albedo_prefilter_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "albedo_prefilter_kernels.h"

HWY_BEFORE_NAMESPACE();
namespace zdenoise {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// patch_distance_row() for points [x, end) of D's width.
template<class D>
HWY_INLINE int
distance_points(D d, const float* const ap[3], const float* const vp[3],
                const float* const aq[3], const float* const vq[3], int x,
                int end, float variance_floor, float* dist, float* count)
{
    using V = hn::Vec<D>;
    const int lanes = int(hn::Lanes(d));
    const V floor = hn::Set(d, variance_floor), third = hn::Set(d, 3.0f);
    const V zero = hn::Zero(d), one = hn::Set(d, 1.0f);
    for (; x + lanes <= end; x += lanes) {
        V sum = zero;
        for (int c = 0; c < 3; ++c) {
            const V diff = hn::Sub(hn::LoadU(d, ap[c] + x), hn::LoadU(d, aq[c] + x));
            const V a = hn::LoadU(d, vp[c] + x), b = hn::LoadU(d, vq[c] + x);
            // (a + min(a, b)) and (floor + a) + b: the scalar code's order.
            sum = hn::Add(sum, hn::Div(hn::Sub(hn::Mul(diff, diff), hn::Add(a, hn::Min(a, b))),
                                       hn::Add(hn::Add(floor, a), b)));
        }
        const auto defined = hn::Eq(sum, sum);
        hn::StoreU(hn::IfThenElseZero(defined, hn::Div(sum, third)), d, dist + x);
        hn::StoreU(hn::IfThenElseZero(defined, one), d, count + x);
    }
    return x;
}

void
PatchDistanceRow(const float* const ap[3], const float* const vp[3],
                 const float* const aq[3], const float* const vq[3], int n,
                 float variance_floor, float* d, float* dn)
{
    const int x = distance_points(hn::ScalableTag<float>(), ap, vp, aq, vq, 0, n,
                                  variance_floor, d, dn);
    distance_points(hn::CappedTag<float, 1>(), ap, vp, aq, vq, x, n, variance_floor, d, dn);
}

/// box3_row() for k in [k, end) of D's width, 1 <= k, end <= n - 1.
template<class D>
HWY_INLINE int
box3_points(D d, const float* in, int k, int end, float* out)
{
    const int lanes = int(hn::Lanes(d));
    for (; k + lanes <= end; k += lanes)
        hn::StoreU(hn::Add(hn::Add(hn::LoadU(d, in + k), hn::LoadU(d, in + k - 1)),
                           hn::LoadU(d, in + k + 1)),
                   d, out + k);
    return k;
}

void
Box3Row(const float* d, const float* dn, int n, float* s, float* sn)
{
    if (n <= 2) {
        for (int k = 0; k < n; ++k) {
            s[k] = d[k], sn[k] = dn[k];
            if (k > 0)
                s[k] += d[k - 1], sn[k] += dn[k - 1];
            if (k + 1 < n)
                s[k] += d[k + 1], sn[k] += dn[k + 1];
        }
        return;
    }
    s[0] = d[0] + d[1], sn[0] = dn[0] + dn[1];
    for (const auto& [in, out] : { std::pair<const float*, float*>(d, s), { dn, sn } }) {
        const int k = box3_points(hn::ScalableTag<float>(), in, 1, n - 1, out);
        box3_points(hn::CappedTag<float, 1>(), in, k, n - 1, out);
    }
    s[n - 1] = d[n - 1] + d[n - 2], sn[n - 1] = dn[n - 1] + dn[n - 2];
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace zdenoise
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace zdenoise {
namespace detail {

HWY_EXPORT(PatchDistanceRow);
HWY_EXPORT(Box3Row);

void
patch_distance_row(const float* const ap[3], const float* const vp[3],
                   const float* const aq[3], const float* const vq[3], int n,
                   float variance_floor, float* d, float* dn)
{
    HWY_DYNAMIC_DISPATCH(PatchDistanceRow)(ap, vp, aq, vq, n, variance_floor, d, dn);
}

void
box3_row(const float* d, const float* dn, int n, float* s, float* sn)
{
    HWY_DYNAMIC_DISPATCH(Box3Row)(d, dn, n, s, sn);
}

}  // namespace detail
}  // namespace zdenoise
#endif
