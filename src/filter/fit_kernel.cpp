// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The fit kernel (fit_kernel.h says how a window is laid out). Highway
// compiles this file once per target: foreach_target.h includes it again
// for each.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "filter/fit_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

#include "fit_kernel.h"
#include "row_kernels.h"

HWY_BEFORE_NAMESPACE();
namespace zdenoise {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<float>;
using V = hn::Vec<D>;
using M = hn::Mask<D>;
static_assert(HWY_LANES(float) <= kPlanePadding,
              "a vector must fit in the planes' padding");

void
FitColumnsImpl(const FitColumns& in)
{
    const D d;
    const size_t lanes = hn::Lanes(d);
    const V zero = hn::Zero(d), one = hn::Set(d, 1.0f);
    const V mean = hn::Set(d, in.mean), value_scale = hn::Set(d, in.value_scale);
    const V clamp = hn::Set(d, kValueClamp);
    for (size_t j = 0; j < size_t(in.columns); j += lanes) {
        const M in_window = hn::FirstN(d, size_t(in.columns) - j);
        const bool last = j + lanes >= size_t(in.columns);
        const V spatial = hn::LoadU(d, in.spatial + j);
        V sum[kColumnSums];
        for (V& s : sum)
            s = zero;
        for (int r = 0; r < in.rows; ++r) {
            const size_t p = size_t(r) * in.stride + j;
            const size_t c = size_t(r) * in.cache_stride + j;
            const V dy = hn::Set(d, in.dy0 + float(r));
            const V fw = hn::LoadU(d, in.fit_weight + c);
            const M use = hn::And(in_window, hn::Gt(fw, zero));
            // exp(-vt), clamped so that weights never underflow; NaN
            // compares false and gives exp(-0) = 1.
            const V t = hn::Mul(value_scale, hn::Abs(hn::Sub(hn::LoadU(d, in.zl + p), mean)));
            const V value = hn::Exp(d, hn::Neg(hn::IfThenElseZero(hn::Gt(t, zero), hn::Min(t, clamp))));
            // Past the last column the cache holds the next row's points.
            if (last)
                hn::BlendedStore(value, in_window, d, in.values + c);
            else
                hn::StoreU(value, d, in.values + c);
            const V w = hn::IfThenElseZero(
                use, hn::Mul(hn::Mul(fw, hn::Mul(spatial, hn::Set(d, in.ey[r]))), value));
            const V wy = hn::Mul(w, dy);
            sum[kColW] = hn::Add(sum[kColW], w);
            sum[kColWy] = hn::Add(sum[kColWy], wy);
            sum[kColWyy] = hn::MulAdd(wy, dy, sum[kColWyy]);
            for (int ch = 0; ch < 3; ++ch) {
                const V z = hn::LoadU(d, in.z[ch] + p);
                sum[kColZ0 + ch] = hn::MulAdd(w, z, sum[kColZ0 + ch]);
                sum[kColZ0y + ch] = hn::MulAdd(wy, z, sum[kColZ0y + ch]);
            }
            const V w2 = hn::Mul(w, w);
            const V w2v = hn::IfThenElseZero(use, hn::Mul(w2, hn::LoadU(d, in.vs + p)));
            const V ny = hn::Mul(w2v, dy);
            sum[kColN] = hn::Add(sum[kColN], w2v);
            sum[kColNy] = hn::Add(sum[kColNy], ny);
            sum[kColNyy] = hn::MulAdd(ny, dy, sum[kColNyy]);
            const V sigma = hn::IfThenElseZero(use, hn::LoadU(d, in.sigma + p));
            sum[kColS2] = hn::MulAdd(w2, hn::Mul(sigma, sigma), sum[kColS2]);
            sum[kColCount] = hn::Add(sum[kColCount], hn::IfThenElseZero(use, one));
        }
        for (int k = 0; k < kColumnSums; ++k)
            hn::StoreU(sum[k], d, in.sums + size_t(k) * in.sums_stride + j);
    }
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace zdenoise
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace zdenoise {
namespace detail {

HWY_EXPORT(FitColumnsImpl);

void
fit_columns(const FitColumns& in)
{
    HWY_DYNAMIC_DISPATCH(FitColumnsImpl)(in);
}

double
add_columns(const float* sums, size_t stride, int columns, float dx0, double R,
            const int cell_of_side[3], FitMoments cells[9])
{
    const double i1 = 1.0 / R, i2 = i1 * i1;
    double s2 = 0.0;
    for (int j = 0; j < columns; ++j) {
        auto sum = [&](int k) { return double(sums[size_t(k) * stride + size_t(j)]); };
        if (!(sum(kColCount) > 0.0))
            continue;
        const double dx = double(dx0 + float(j));
        FitMoments& m = cells[cell_of_side[dx < 0.0 ? 0 : (dx > 0.0 ? 2 : 1)]];
        const double u = dx * i1;
        // Moments in u = dx/R, v = dy/R: the column's sums in dy, times
        // its u and its powers.
        const double col[3] = { sum(kColW), sum(kColWy) * i1, sum(kColWyy) * i2 };
        const double noise[3] = { sum(kColN), sum(kColNy) * i1, sum(kColNyy) * i2 };
        m.s[0] += col[0];
        m.s[1] += u * col[0];
        m.s[2] += col[1];
        m.s[3] += u * u * col[0];
        m.s[4] += u * col[1];
        m.s[5] += col[2];
        m.n[0] += noise[0];
        m.n[1] += u * noise[0];
        m.n[2] += noise[1];
        m.n[3] += u * u * noise[0];
        m.n[4] += u * noise[1];
        m.n[5] += noise[2];
        for (int ch = 0; ch < 3; ++ch) {
            const double z = sum(kColZ0 + ch);
            m.t[ch][0] += z;
            m.t[ch][1] += u * z;
            m.t[ch][2] += sum(kColZ0y + ch) * i1;
        }
        m.count += int(sum(kColCount));
        s2 += sum(kColS2);
    }
    return s2;
}

}  // namespace detail
}  // namespace zdenoise
#endif
