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


namespace {

/// g of section 4 for n pixels, before the normal power and Cryptomatte
/// coverage: d (the normals' cosine, 1 where neither has one) where every
/// test passes, else 0. Each test is its own select: GCC 12 vectorises
/// these, not a conjunction of them.
template<bool kDepth, bool kPlainId>
[[gnu::always_inline]] inline void
guide_lanes(const uint32_t* __restrict cls, const float* __restrict normal,
            const float* __restrict invdepth, const float* __restrict ids,
            float* __restrict g, int n, const GuideCentre& c)
{
    // A decoded normal is a unit vector or all zero (none).
    const bool none0 = c.n0[0] * c.n0[0] + c.n0[1] * c.n0[1]
                           + c.n0[2] * c.n0[2]
                       == 0.0f;
    for (int q = 0; q < n; ++q) {
        const float nx = normal[3 * q], ny = normal[3 * q + 1],
                    nz = normal[3 * q + 2];
        const bool none = nx * nx + ny * ny + nz * nz == 0.0f;
        // Unit vectors, but rounding can put d a hair above 1, which a
        // large normal_power turns into Inf.
        const float d = std::min(1.0f, nx * c.n0[0] + ny * c.n0[1]
                                           + nz * c.n0[2]);
        const float with_normal = d > c.normal_cut ? d : 0.0f;
        float w = none0 ? (none ? 1.0f : 0.0f) : (none ? 0.0f : with_normal);
        if (kDepth) {
            const float zhat = c.zeta0 + c.gx * (c.dx0 + float(q))
                               + c.gy * c.dy;
            w = zhat > 0.0f ? w : 0.0f;
            w = std::fabs(invdepth[q] - zhat) <= c.depth_tolerance * zhat
                    ? w
                    : 0.0f;
        }
        if (kPlainId) {
            uint32_t id;
            std::memcpy(&id, &ids[q], sizeof id);
            w = id == c.id0 ? w : 0.0f;
        }
        g[q] = (cls[q] & kSurface) ? w : 0.0f;
    }
}

}  // namespace


ZDENOISE_ROW_KERNEL void
guide_row(const uint32_t* __restrict cls, const float* __restrict normal,
          const float* __restrict invdepth, const float* __restrict ids,
          float* __restrict g, int n, const GuideCentre& c, bool depth,
          bool plain_id)
{
    if (depth && plain_id)
        guide_lanes<true, true>(cls, normal, invdepth, ids, g, n, c);
    else if (depth)
        guide_lanes<true, false>(cls, normal, invdepth, ids, g, n, c);
    else if (plain_id)
        guide_lanes<false, true>(cls, normal, invdepth, ids, g, n, c);
    else
        guide_lanes<false, false>(cls, normal, invdepth, ids, g, n, c);
}

/// Multiply g by the Cryptomatte overlap of each pixel with the centre p0:
/// the sum over equal ids of the smaller normalised coverage, at most 1 (1
/// where neither has coverage, 0 where one has none). Coverages are >= 0,
/// so a rank without coverage adds min(c, 0) = 0 and needs no test. K > 0
/// is k known when compiling (its loops unroll and the pixels vectorise).

namespace {

template<int K>
[[gnu::always_inline]] inline void
coverage_lanes(const float* __restrict ids, const float* __restrict p0,
               float* __restrict g, int n, int k)
{
    static_assert(K <= 4, "the centre's ranks are held in registers");
    const int kk = K > 0 ? K : k;
    uint32_t id0[4] = {};
    float c0[4]     = {};
    float cover0    = 0.0f;
    for (int b = 0; b < kk; ++b) {
        if (K > 0) {
            std::memcpy(&id0[b], &p0[2 * b], sizeof(uint32_t));
            c0[b] = p0[2 * b + 1];
        }
        cover0 += p0[2 * b + 1];
    }
    // The centre's rank b (from p0 itself when k is not known).
    auto centre_id = [&](int b) {
        uint32_t id = id0[K > 0 ? b : 0];
        if (K == 0)
            std::memcpy(&id, &p0[2 * b], sizeof id);
        return id;
    };
    auto centre_cover = [&](int b) {
        return K > 0 ? c0[b] : p0[2 * b + 1];
    };
    for (int q = 0; q < n; ++q) {
        const float* p = &ids[size_t(2 * kk) * size_t(q)];
        float overlap = 0.0f, cover = 0.0f;
        for (int a = 0; a < kk; ++a) {
            const float ca = p[2 * a + 1];
            uint32_t ida;
            std::memcpy(&ida, &p[2 * a], sizeof ida);
            cover += ca;
            for (int b = 0; b < kk; ++b)
                overlap += ida == centre_id(b) ? std::min(ca, centre_cover(b))
                                               : 0.0f;
        }
        const float none = cover == 0.0f ? 1.0f : 0.0f;
        overlap = cover0 == 0.0f ? none : (cover == 0.0f ? 0.0f : overlap);
        g[q] *= std::min(overlap, 1.0f);
    }
}

}  // namespace


ZDENOISE_ROW_KERNEL void
coverage_row(const float* __restrict ids, const float* __restrict p0,
             float* __restrict g, int n, int k)
{
    switch (k) {
    case 1: coverage_lanes<1>(ids, p0, g, n, k); break;
    case 2: coverage_lanes<2>(ids, p0, g, n, k); break;
    case 3: coverage_lanes<3>(ids, p0, g, n, k); break;
    default: coverage_lanes<0>(ids, p0, g, n, k); break;
    }
}

}  // namespace detail
}  // namespace zdenoise
