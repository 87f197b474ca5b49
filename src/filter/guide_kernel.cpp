// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The guide kernels (guide_kernel.h says how the planes are laid out).
// Highway compiles this file once per target: foreach_target.h includes it
// again for each.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "filter/guide_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "internal.h"
#include "guide_kernel.h"

HWY_BEFORE_NAMESPACE();
namespace zdenoise {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D  = hn::ScalableTag<float>;
using V  = hn::Vec<D>;
using M  = hn::Mask<D>;
using DU = hn::RebindToUnsigned<D>;
using VU = hn::Vec<DU>;
static_assert(HWY_LANES(float) <= kPlanePadding,
              "a vector must fit in the planes' padding");

/// The lanes of `cls` with `bit` set.
HWY_INLINE M
has_class(VU cls, uint32_t bit)
{
    const DU du;
    return hn::RebindMask(D(), hn::Ne(hn::And(cls, hn::Set(du, bit)), hn::Zero(du)));
}

/// Store the first n of v's lanes at p: the window caches hold other rows'
/// pixels after a segment.
HWY_INLINE void
store_first(V v, int n, float* p)
{
    const D d;
    if (n >= int(hn::Lanes(d)))
        hn::StoreU(v, d, p);
    else
        hn::BlendedStore(v, hn::FirstN(d, size_t(n)), d, p);
}

/// g of section 4 for the lanes at pixel j of the row. Each operation is
/// the scalar code's, in its order (no contraction: src/CMakeLists.txt).
template <bool kNormal, bool kDepth, bool kPlainId>
HWY_INLINE V
guide_lanes(const GuideRow& in, int j, bool none0)
{
    const D d;
    const DU du;
    const V zero = hn::Zero(d), one = hn::Set(d, 1.0f);
    V w = one;  // no normal guide: neither pixel has one, d = 1
    if (kNormal) {
        const V nx = hn::LoadU(d, in.normal[0] + j), ny = hn::LoadU(d, in.normal[1] + j),
                nz = hn::LoadU(d, in.normal[2] + j);
        const M none = hn::Eq(hn::Add(hn::Add(hn::Mul(nx, nx), hn::Mul(ny, ny)), hn::Mul(nz, nz)),
                              zero);
        // Unit vectors, but rounding can put the cosine a hair above 1,
        // which a large normal_power turns into Inf.
        const V cosine = hn::Min(
            one, hn::Add(hn::Add(hn::Mul(nx, hn::Set(d, in.n0[0])), hn::Mul(ny, hn::Set(d, in.n0[1]))),
                         hn::Mul(nz, hn::Set(d, in.n0[2]))));
        const V with_normal = hn::IfThenElseZero(hn::Gt(cosine, hn::Set(d, in.normal_cut)), cosine);
        w = none0 ? hn::IfThenElseZero(none, one) : hn::IfThenZeroElse(none, with_normal);
    }
    if (kDepth) {
        const V dx = hn::Add(hn::Set(d, in.dx0), hn::Iota(d, float(j)));
        const V zhat = hn::Add(hn::Add(hn::Set(d, in.zeta0), hn::Mul(hn::Set(d, in.gx), dx)),
                               hn::Mul(hn::Set(d, in.gy), hn::Set(d, in.dy)));
        const V gap = hn::Abs(hn::Sub(hn::LoadU(d, in.invdepth + j), zhat));
        const M near = hn::And(hn::Gt(zhat, zero),
                               hn::Le(gap, hn::Mul(hn::Set(d, in.depth_tolerance), zhat)));
        w = hn::IfThenElseZero(near, w);
    }
    if (kPlainId) {
        const VU id = hn::LoadU(du, reinterpret_cast<const uint32_t*>(
                                        in.ids[0].data() + in.first + size_t(j)));
        w = hn::IfThenElseZero(hn::RebindMask(d, hn::Eq(id, hn::Set(du, in.id0))), w);
    }
    return hn::IfThenElseZero(has_class(hn::LoadU(du, in.cls + j), kSurface), w);
}

/// The Cryptomatte overlap of the lanes at pixel j with the centre: the sum
/// over equal ids of the smaller normalised coverage, at most 1 (1 where
/// neither has coverage, 0 where one has none). Coverages are >= 0, so a
/// rank without coverage adds min(c, 0) = 0 and needs no test.
HWY_INLINE V
overlap_lanes(const GuideRow& in, int j, float cover0)
{
    const D d;
    const DU du;
    const V zero = hn::Zero(d), one = hn::Set(d, 1.0f);
    const size_t at = in.first + size_t(j);
    V overlap = zero, cover = zero;
    for (int a = 0; a < in.id_pairs; ++a) {
        const VU ida = hn::LoadU(
            du, reinterpret_cast<const uint32_t*>(in.ids[size_t(2 * a)].data() + at));
        const V ca = hn::LoadU(d, in.ids[size_t(2 * a + 1)].data() + at);
        cover = hn::Add(cover, ca);
        for (int b = 0; b < in.id_pairs; ++b) {
            uint32_t id0;
            std::memcpy(&id0, &in.pairs0[2 * b], sizeof id0);
            const M same = hn::RebindMask(d, hn::Eq(ida, hn::Set(du, id0)));
            overlap = hn::Add(overlap,
                              hn::IfThenElseZero(same, hn::Min(ca, hn::Set(d, in.pairs0[2 * b + 1]))));
        }
    }
    const M bare = hn::Eq(cover, zero);
    overlap = cover0 == 0.0f ? hn::IfThenElseZero(bare, one) : hn::IfThenZeroElse(bare, overlap);
    return hn::Min(overlap, one);
}

template <bool kNormal, bool kDepth, bool kPlainId>
HWY_INLINE void
guide_row_lanes(const GuideRow& in)
{
    const D d;
    const int lanes = int(hn::Lanes(d));
    const bool none0 = in.n0[0] * in.n0[0] + in.n0[1] * in.n0[1] + in.n0[2] * in.n0[2] == 0.0f;
    float cover0 = 0.0f;
    for (int b = 0; b < in.id_pairs; ++b)
        cover0 += in.pairs0[2 * b + 1];
    for (int j = 0; j < in.n; j += lanes) {
        V g = guide_lanes<kNormal, kDepth, kPlainId>(in, j, none0);
        if (in.normal_power == 4.0f) {
            const V d2 = hn::Mul(g, g);
            g = hn::Mul(d2, d2);
        } else {
            // Other powers are rare options: libm's pow, lane by lane.
            HWY_ALIGN float t[HWY_LANES(float)];
            hn::Store(g, d, t);
            for (int l = 0; l < lanes; ++l)
                t[l] = t[l] > 0.0f ? std::pow(t[l], in.normal_power) : t[l];
            g = hn::Load(d, t);
        }
        if (in.id_pairs > 0)
            g = hn::Mul(g, overlap_lanes(in, j, cover0));
        store_first(g, in.n - j, in.g + j);
    }
}

void
GuideRowImpl(const GuideRow& in)
{
    const bool normal = in.normal[0] != nullptr, depth = in.invdepth != nullptr;
    const bool plain = in.id_pairs == -1;
    // One instantiation per set of guides given: the tests of absent
    // guides cost nothing.
    if (normal) {
        if (depth)
            plain ? guide_row_lanes<true, true, true>(in) : guide_row_lanes<true, true, false>(in);
        else
            plain ? guide_row_lanes<true, false, true>(in) : guide_row_lanes<true, false, false>(in);
    } else {
        if (depth)
            plain ? guide_row_lanes<false, true, true>(in) : guide_row_lanes<false, true, false>(in);
        else
            plain ? guide_row_lanes<false, false, true>(in) : guide_row_lanes<false, false, false>(in);
    }
}

void
GrowRingImpl(GrowRing& in)
{
    const D d;
    const DU du;
    const int lanes = int(hn::Lanes(d));
    const V zero = hn::Zero(d);
    const V inf = hn::Set(d, std::numeric_limits<float>::infinity());
    V llo[3], lhi[3];
    for (int ch = 0; ch < 3; ++ch) {
        llo[ch] = hn::Set(d, in.range.llo[ch]);
        lhi[ch] = hn::Set(d, in.range.lhi[ch]);
    }
    size_t zcount = 0;
    double zsum = in.zsum;
    for (int k = 0; k < in.count; ++k) {
        const GrowSegment& seg = in.segments[k];
        const size_t i = seg.pixel, c = seg.cache;
        V zrow = zero;
        for (int j = 0; j < seg.n; j += lanes) {
            const V g = hn::LoadU(d, in.g + c + j);
            const M take = hn::And(hn::And(hn::FirstN(d, size_t(seg.n - j)), hn::Gt(g, zero)),
                                   has_class(hn::LoadU(du, in.cls + i + j), kFitPoint));
            zrow = hn::Add(zrow, hn::IfThenElseZero(take, hn::LoadU(d, in.zl + i + j)));
            zcount += hn::CountTrue(d, take);
            const V fw = hn::IfThenElseZero(take, hn::Mul(g, hn::LoadU(d, in.fit_prior + i + j)));
            store_first(fw, seg.n - j, in.fit_weight + c + j);
            const M good = hn::Gt(fw, zero);
            for (int ch = 0; ch < 3; ++ch) {
                const V l = hn::LoadU(d, in.lfit[ch] + i + j);
                llo[ch] = hn::Min(llo[ch], hn::IfThenElse(good, l, inf));
                lhi[ch] = hn::Max(lhi[ch], hn::IfThenElse(good, l, hn::Neg(inf)));
            }
        }
        // A segment is at most a window's side: its float sum is exact to
        // about 1e-7, then kept in double, segment by segment in order.
        zsum += double(hn::GetLane(hn::SumOfLanes(d, zrow)));
    }
    in.zsum = zsum;
    in.zcount += int(zcount);
    for (int ch = 0; ch < 3; ++ch) {
        in.range.llo[ch] = hn::GetLane(hn::MinOfLanes(d, llo[ch]));
        in.range.lhi[ch] = hn::GetLane(hn::MaxOfLanes(d, lhi[ch]));
    }
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace zdenoise
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace zdenoise {
namespace detail {

HWY_EXPORT(GuideRowImpl);
HWY_EXPORT(GrowRingImpl);

void
guide_row(const GuideRow& row)
{
    HWY_DYNAMIC_DISPATCH(GuideRowImpl)(row);
}

void
grow_ring(GrowRing& ring)
{
    HWY_DYNAMIC_DISPATCH(GrowRingImpl)(ring);
}

}  // namespace detail
}  // namespace zdenoise
#endif
