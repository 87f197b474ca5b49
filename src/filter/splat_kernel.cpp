// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The splat kernel (splat_kernel.h says how a row is laid out). Highway
// compiles this file once per target: foreach_target.h includes it again
// for each.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "filter/splat_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

#include <limits>

#include "internal.h"
#include "splat_kernel.h"

HWY_BEFORE_NAMESPACE();
namespace zdenoise {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D  = hn::ScalableTag<float>;
using V  = hn::Vec<D>;
using M  = hn::Mask<D>;
using DU = hn::RebindToUnsigned<D>;
static_assert(HWY_LANES(float) <= kPlanePadding,
              "a vector must fit in the planes' padding");

/// 1 / x to about 23 bits: the hardware's estimate and a Newton step,
/// several times the throughput of a division.
HWY_INLINE V
reciprocal(V x)
{
    const D d;
    const V r = hn::ApproximateReciprocal(x);
    return hn::Mul(r, hn::NegMulAdd(x, r, hn::Set(d, 2.0f)));
}

/// A plane's coefficients as vectors: each lane takes `left` where `is_left`
/// holds, else `right`; c + b v is folded into c (v is the row's).
struct PlaneLanes {
    V c[3], a[3], hat[6];
    PlaneLanes(const PlaneCoeffs& left, const PlaneCoeffs& right, M is_left, float v)
    {
        const D d;
        auto pick = [&](float l, float r) {
            return hn::IfThenElse(is_left, hn::Set(d, l), hn::Set(d, r));
        };
        for (int ch = 0; ch < 3; ++ch) {
            c[ch] = pick(left.c[ch] + left.b[ch] * v, right.c[ch] + right.b[ch] * v);
            a[ch] = pick(left.a[ch], right.a[ch]);
        }
        for (int t = 0; t < 6; ++t)
            hat[t] = pick(left.hat[t], right.hat[t]);
    }
    /// e^T M^-1 e at (u, v): the hat diagonal's quadratic form.
    V form(V u, float v) const
    {
        const D d;
        const V vv = hn::Set(d, v);
        const V inner = hn::MulAdd(hat[3], u, hn::MulAdd(hat[4], vv, hat[1]));
        return hn::MulAdd(u, inner, hn::MulAdd(vv, hn::MulAdd(hat[5], vv, hat[2]), hat[0]));
    }
};

template <bool kPower8, bool kHat>
HWY_INLINE void
splat_lanes(const SplatRow& in)
{
    const D d;
    const DU du;
    const int lanes = int(hn::Lanes(d));
    const V zero = hn::Zero(d), one = hn::Set(d, 1.0f);
    const V eps = hn::Set(d, float(kEps)), max_wm = hn::Set(d, float(kMaxWm));
    const V mean = hn::Set(d, in.mean), value_scale = hn::Set(d, in.value_scale);
    const V clamp = hn::Set(d, kValueClamp), ey = hn::Set(d, in.ey);
    const V inv_r = hn::Set(d, in.inv_r), power = hn::Set(d, in.power);
    const V largest = hn::Set(d, std::numeric_limits<float>::max());
    V llo[3], lhi[3];
    for (int ch = 0; ch < 3; ++ch) {
        llo[ch] = hn::Set(d, in.range.llo[ch]);
        lhi[ch] = hn::Set(d, in.range.lhi[ch]);
    }
    const PlaneLanes whole(in.whole, in.whole, hn::FirstN(d, 0), in.v);
    for (int j = 0; j < in.n; j += lanes) {
        const V dx = hn::Add(hn::Iota(d, float(j)), hn::Set(d, in.dx0));
        const M is_left = hn::Lt(dx, zero);
        // A row crosses the centre once: most vectors lie on one side.
        const PlaneLanes quadrant(in.left, in.right, is_left, in.v);
        const hn::Vec<DU> cls = hn::LoadU(du, in.cls + j);
        const V g = hn::LoadU(d, in.g + j), fw = hn::LoadU(d, in.fit_weight + j);
        const V zl = hn::LoadU(d, in.zl + j);
        // Receiving implies a surface (section 2).
        const M use = hn::And(
            hn::And(hn::FirstN(d, size_t(in.n - j)), hn::Gt(g, zero)),
            hn::RebindMask(d, hn::Ne(hn::And(cls, hn::Set(du, kReceiveAny)),
                                     hn::Zero(du))));
        const M fit = hn::RebindMask(
            d, hn::Ne(hn::And(cls, hn::Set(du, kFitPoint)), hn::Zero(du)));
        const M kept = hn::Gt(fw, zero);
        // The fit kept exp(-vt) where the point took part; a fit point it
        // left out (no fit prior) needs its own.
        const V t = hn::Mul(value_scale, hn::Abs(hn::Sub(zl, mean)));
        V value = hn::IfThenElse(kept, hn::LoadU(d, in.values + j), one);
        const M fresh = hn::AndNot(kept, fit);
        if (!hn::AllFalse(d, fresh)) {
            // NaN compares false: exp(-0) = 1, as exp_neg() gives.
            const V tc = hn::IfThenElseZero(hn::Gt(t, zero), hn::Min(t, clamp));
            value = hn::IfThenElse(fresh, hn::Exp(d, hn::Neg(tc)), value);
        }
        const V base = hn::Mul(hn::Mul(hn::LoadU(d, in.spatial + j), ey), value);
        const V s = hn::IfThenElseZero(use, hn::Mul(g, base));
        const V u = hn::Mul(dx, inv_r);
        V h_whole = zero, h_quadrant = zero, H_l = zero, A_l = zero;
        if (kHat) {
            // The point's own fit weight times e^T M^-1 e of each plane.
            const V w = hn::IfThenElseZero(use, hn::Mul(fw, base));
            h_whole = hn::Mul(w, whole.form(u, in.v));
            h_quadrant = hn::Mul(w, quadrant.form(u, in.v));
        }
        for (int ch = 0; ch < 3; ++ch) {
            const V Z = hn::MulAdd(whole.a[ch], u, whole.c[ch]);
            const V Zm = hn::MulAdd(quadrant.a[ch], u, quadrant.c[ch]);
            // r = max(a/b, b/a) from the two reciprocals the hat needs too
            const V a = hn::Add(hn::Abs(Z), eps), b = hn::Add(hn::Abs(Zm), eps);
            const V inv_a = reciprocal(a), inv_b = reciprocal(b);
            const V r = hn::Mul(hn::Max(a, b), hn::Max(inv_a, inv_b));
            V wm;
            if (kPower8) {
                const V r2 = hn::Mul(r, r), r4 = hn::Mul(r2, r2);
                wm = hn::Mul(r4, r4);
            } else {
                wm = hn::Exp(d, hn::Mul(power, hn::Log(d, r)));
            }
            wm = hn::Min(wm, max_wm);
            const M opposite = hn::Or(hn::And(hn::Lt(Z, zero), hn::Gt(Zm, zero)),
                                      hn::And(hn::Gt(Z, zero), hn::Lt(Zm, zero)));
            wm = hn::IfThenElse(opposite, max_wm, wm);
            // Without a quadrant plane Q is the whole one: Zm = Z, wm = 1
            // and A = Z. Within the radiance the window saw, at this
            // pixel's albedo: a plane extrapolates, and a mixed pixel's z
            // (an emitter's anti-aliased edge) is no one side's light.
            const V inv_1wm = reciprocal(hn::Add(one, wm));
            const V A = hn::Mul(hn::MulAdd(wm, Zm, Z), inv_1wm);
            const V ia = hn::LoadU(d, in.inv_albedo[ch] + j);
            // The bounds saturate at the largest float, both ways: a pixel
            // of albedo near 0 in a bright window has a bound past it (in
            // a window of radiance -1e30 alone, hi = -Inf), and a plane
            // fitted to huge quotients can reach Inf there (NaN: taken as
            // 0, then bounded).
            const V lo = hn::Min(hn::Max(hn::Mul(llo[ch], ia), hn::Neg(largest)), largest);
            const V hi = hn::Max(hn::Min(hn::Mul(lhi[ch], ia), largest), hn::Neg(largest));
            const V Al = hn::Min(hn::Max(hn::IfThenElseZero(hn::Eq(A, A), A), lo), hi);
            hn::StoreU(hn::Mul(s, Al), d, in.a[ch] + j);
            if (kHat) {
                // The blend's weight follows the point too: w_m = r^p with
                // ln r = |ln a - ln b|, so dw_m = p w_m d ln r (none where
                // w_m is at its bound), and
                // dA = (h + w_m h_m + (Zm - Z) dw_m / (1 + w_m)) / (1 + w_m).
                // A clamped channel does not follow its own value.
                const V da = hn::Mul(hn::IfThenElse(hn::Lt(Z, zero), hn::Neg(h_whole), h_whole), inv_a);
                const V db = hn::Mul(hn::IfThenElse(hn::Lt(Zm, zero), hn::Neg(h_quadrant), h_quadrant), inv_b);
                const V dln = hn::IfThenElse(hn::Ge(a, b), hn::Sub(da, db), hn::Sub(db, da));
                const V p = kPower8 ? hn::Set(d, 8.0f) : power;
                const V dwm = hn::IfThenElseZero(hn::Lt(wm, max_wm), hn::Mul(hn::Mul(p, wm), dln));
                const V H = hn::Mul(hn::MulAdd(hn::Mul(hn::Sub(Zm, Z), dwm), inv_1wm,
                                               hn::MulAdd(wm, h_quadrant, h_whole)),
                                    inv_1wm);
                const V luma = hn::Set(d, kLumaWeights[ch]);
                H_l = hn::MulAdd(luma, hn::IfThenElseZero(hn::Eq(Al, A), H), H_l);
                A_l = hn::MulAdd(luma, Al, A_l);
            }
        }
        hn::StoreU(s, d, in.s + j);
        if (kHat) {
            // d ln(weight) / d zl of a fit point's value term (where the
            // clamp of exp(-vt) does not hold it).
            const V sign = hn::IfThenElse(hn::Gt(zl, mean), value_scale,
                                          hn::IfThenElseZero(hn::Lt(zl, mean), hn::Neg(value_scale)));
            const V c = hn::IfThenElseZero(hn::And(fit, hn::Lt(t, clamp)), sign);
            const V sc = hn::Mul(s, c);
            hn::StoreU(hn::Mul(hn::Mul(s, H_l), hn::NegMulAdd(c, hn::Sub(zl, A_l), one)), d,
                       in.hat[0] + j);
            hn::StoreU(sc, d, in.hat[1] + j);
            hn::StoreU(hn::Mul(sc, A_l), d, in.hat[2] + j);
        }
    }
}

void
SplatRowImpl(const SplatRow& in)
{
    // r^8 by multiplication (the default quadrant_power) and the hat
    // diagonal (the selection's risk) are the cases worth their own code.
    if (in.hat[0])
        in.power == 8.0f ? splat_lanes<true, true>(in) : splat_lanes<false, true>(in);
    else
        in.power == 8.0f ? splat_lanes<true, false>(in) : splat_lanes<false, false>(in);
}

void
AccumulateRowImpl(const SplatRow& in, int n, double* HWY_RESTRICT acc,
                  double* HWY_RESTRICT wsum, double* HWY_RESTRICT hat_sums)
{
    // As many floats as a vector holds doubles: each is promoted exactly.
    const hn::ScalableTag<double> dd;
    const hn::Rebind<float, decltype(dd)> df;
    using VD = hn::Vec<decltype(dd)>;
    const int lanes = int(hn::Lanes(dd));
    const VD zero = hn::Zero(dd);
    int q = 0;
    // Whole vectors only: the sums past the row are other pixels', which
    // another window may be adding to.
    for (; q + lanes <= n; q += lanes) {
        const VD s = hn::PromoteTo(dd, hn::LoadU(df, in.s + q));
        const auto take = hn::Gt(s, zero);
        // Adding 0 where a pixel does not receive leaves its sums as they
        // were (skipping it would too).
        auto add3 = [&](float* const src[3], double* sums) {
            VD a0, a1, a2;
            hn::LoadInterleaved3(dd, sums + 3 * q, a0, a1, a2);
            a0 = hn::Add(a0, hn::IfThenElseZero(take, hn::PromoteTo(dd, hn::LoadU(df, src[0] + q))));
            a1 = hn::Add(a1, hn::IfThenElseZero(take, hn::PromoteTo(dd, hn::LoadU(df, src[1] + q))));
            a2 = hn::Add(a2, hn::IfThenElseZero(take, hn::PromoteTo(dd, hn::LoadU(df, src[2] + q))));
            hn::StoreInterleaved3(a0, a1, a2, dd, sums + 3 * q);
        };
        add3(in.a, acc);
        hn::StoreU(hn::Add(hn::LoadU(dd, wsum + q), hn::IfThenElseZero(take, s)), dd, wsum + q);
        if (hat_sums)
            add3(in.hat, hat_sums);
    }
    for (; q < n; ++q) {
        const float s = in.s[q];
        if (!(s > 0.0f))
            continue;
        for (int ch = 0; ch < 3; ++ch)
            acc[3 * q + ch] += double(in.a[ch][q]);
        wsum[q] += double(s);
        if (hat_sums)
            for (int t = 0; t < 3; ++t)
                hat_sums[3 * q + t] += double(in.hat[t][q]);
    }
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace zdenoise
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace zdenoise {
namespace detail {

HWY_EXPORT(SplatRowImpl);
HWY_EXPORT(AccumulateRowImpl);

void
splat_row(const SplatRow& row)
{
    HWY_DYNAMIC_DISPATCH(SplatRowImpl)(row);
}

void
accumulate_row(const SplatRow& row, int n, double* acc, double* wsum,
               double* hat_sums)
{
    HWY_DYNAMIC_DISPATCH(AccumulateRowImpl)(row, n, acc, wsum, hat_sums);
}

}  // namespace detail
}  // namespace zdenoise
#endif
