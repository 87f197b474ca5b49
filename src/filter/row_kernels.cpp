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

/// Add the points of one row segment to a cell, kLanes at a time; store
/// each point's value factor exp(-vt) in `values` (whole blocks: the
/// buffers are padded, and a store past the segment lands where a later
/// segment writes or nobody reads).
ZDENOISE_ROW_KERNEL void
fit_row(const float* __restrict fit_weight, const float* __restrict spatial,
        const float* __restrict zl, const float* __restrict z0,
        const float* __restrict z1, const float* __restrict z2,
        const float* __restrict l0, const float* __restrict l1,
        const float* __restrict l2, const float* __restrict vs,
        const float* __restrict sigma, float* __restrict values,
        CellLanes* __restrict cell, RangeLanes* __restrict range,
        const FitRow& in)
{
    using S = CellLanes;
    const float dy = in.dy, ey = in.ey, mean = in.mean;
    const float value_scale = in.value_scale;
    const int n = in.n;
    for (int j = 0; j < n; j += kLanes) {
        for (int l = 0; l < kLanes; ++l) {
            // Every load unconditional, selects instead of branches: the
            // lanes vectorise.
            const int q       = j + l;
            const float fw    = fit_weight[q];
            const float sp    = spatial[q];
            const float vsq   = vs[q];
            const float sgq   = sigma[q];
            const float value = exp_neg(value_scale * std::fabs(zl[q] - mean));
            values[q]         = value;
            const bool use    = q < n && fw > 0.0f;
            const float w   = use ? fw * sp * ey * value : 0.0f;
            const float w2v = w * w * (use ? vsq : 0.0f);
            const float sg  = use ? sgq : 0.0f;
            const float dx  = in.dx0 + float(q);
            const float wx = w * dx, wy = w * dy;
            S& c = *cell;
            c.lane[S::W][l] += w;
            c.lane[S::Wx][l] += wx;
            c.lane[S::Wy][l] += wy;
            c.lane[S::Wxx][l] += wx * dx;
            c.lane[S::Wxy][l] += wx * dy;
            c.lane[S::Wyy][l] += wy * dy;
            const float zc[3] = { z0[q], z1[q], z2[q] };
            const float lc[3] = { l0[q], l1[q], l2[q] };
#pragma GCC unroll 3
            for (int ch = 0; ch < 3; ++ch) {
                c.lane[S::Z0 + 3 * ch][l] += w * zc[ch];
                c.lane[S::Z0x + 3 * ch][l] += wx * zc[ch];
                c.lane[S::Z0y + 3 * ch][l] += wy * zc[ch];
                float& llo = range->llo[ch][l];
                float& lhi = range->lhi[ch][l];
                llo = use && lc[ch] < llo ? lc[ch] : llo;
                lhi = use && lc[ch] > lhi ? lc[ch] : lhi;
            }
            const float nx = w2v * dx, ny = w2v * dy;
            c.lane[S::N][l] += w2v;
            c.lane[S::Nx][l] += nx;
            c.lane[S::Ny][l] += ny;
            c.lane[S::Nxx][l] += nx * dx;
            c.lane[S::Nxy][l] += nx * dy;
            c.lane[S::Nyy][l] += ny * dy;
            c.lane[S::S2][l] += w * w * sg * sg;
            c.lane[S::Count][l] += use ? 1.0f : 0.0f;
        }
    }
}

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

namespace {

/// The splat weights and values of section 7 for one segment; kPower8 when
/// quadrant_power is 8 (the default: r^8 by multiplication vectorises,
/// std::pow does not).
// The pointers of a SplatRow again, as __restrict parameters: GCC gives up
// vectorising when it must check at run time that more than ten of them do
// not overlap, and only parameters carry restrict reliably.
#define ZDENOISE_SPLAT_POINTERS                                               \
    const uint32_t *__restrict cls, const float *__restrict gw,                \
        const float *__restrict fitw, const float *__restrict values,          \
        const float *__restrict spat, const float *__restrict zl,              \
        const float *__restrict ia0, const float *__restrict ia1,              \
        const float *__restrict ia2, float *__restrict out_s,                  \
        float *__restrict a0, float *__restrict a1, float *__restrict a2,      \
        float *__restrict h, float *__restrict hc, float *__restrict hca
#define ZDENOISE_SPLAT_ARGS(in)                                                \
    in.cls, in.g, in.fit_weight, in.values, in.spatial, in.zl,                 \
        in.inv_albedo[0], in.inv_albedo[1], in.inv_albedo[2], in.s, in.a[0],   \
        in.a[1], in.a[2], in.hat[0], in.hat[1], in.hat[2]

template<bool kPower8, bool kHat>
[[gnu::always_inline]] inline void
splat_lanes(ZDENOISE_SPLAT_POINTERS, const SplatRow& in, float power)
{
    float* const out_a[3] = { a0, a1, a2 };
    const float* const inv_albedo[3] = { ia0, ia1, ia2 };
    const PlaneCoeffs P = in.whole, Q = in.quadrant;
    const WindowRange range = in.range;
    const float ey = in.ey, inv_r = in.inv_r, v = in.v, dx0 = in.dx0;
    const float mean = in.mean, value_scale = in.value_scale;
    const int n = in.n;
    // Whole blocks of kLanes points (the inputs and outputs are padded):
    // segments are short, and a plain loop would spend most of its time in
    // its scalar remainder. No sums across points, so any vector width
    // computes every point alike.
    for (int j = 0; j < n; j += kLanes) {
        for (int l = 0; l < kLanes; ++l) {
            const int q       = j + l;
            const uint32_t cl = cls[q];
            const float g    = gw[q];
            const float fw   = fitw[q];
            const float kept = values[q];
            const float sp   = spat[q];
            // Receiving implies a surface (section 2). One bit test per
            // condition: GCC 12 vectorises no bitwise and of two of them.
            const bool use = (cl & kReceiveAny) && g > 0.0f;
            const bool fit = (cl & kFitPoint) != 0;
            const float fresh = exp_neg(value_scale * std::fabs(zl[q] - mean));
            const float value = fit ? (fw > 0.0f ? kept : fresh) : 1.0f;
            const float s = use ? g * sp * ey * value : 0.0f;
            const float u = (dx0 + float(q)) * inv_r;
            // The hat diagonal's terms: the point's own fit weight times
            // e^T M^-1 e of the whole and the quadrant plane.
            float h_whole = 0.0f, h_quadrant = 0.0f, H_l = 0.0f, A_l = 0.0f;
            if (kHat) {
                const float w = use ? fw * sp * ey * value : 0.0f;
                auto form = [u, v](const float* k) {
                    return k[0] + u * (k[1] + k[3] * u + k[4] * v)
                           + v * (k[2] + k[5] * v);
                };
                h_whole    = w * form(P.hat);
                h_quadrant = w * form(Q.hat);
            }
#pragma GCC unroll 3
            for (int ch = 0; ch < 3; ++ch) {
                const float Z  = P.c[ch] + P.a[ch] * u + P.b[ch] * v;
                const float Zm = Q.c[ch] + Q.a[ch] * u + Q.b[ch] * v;
                // r = max(a/b, b/a) with one division
                const float a = std::fabs(Z) + float(kEps);
                const float b = std::fabs(Zm) + float(kEps);
                const float r = std::max(a, b) / std::min(a, b);
                float wm;
                if (kPower8) {
                    const float r2 = r * r, r4 = r2 * r2;
                    wm = r4 * r4;
                } else {
                    wm = std::pow(r, power);
                }
                wm = std::min(wm, float(kMaxWm));
                const bool opposite = (Z < 0.0f && Zm > 0.0f)
                                      || (Z > 0.0f && Zm < 0.0f);
                wm = opposite ? float(kMaxWm) : wm;
                // Without a quadrant plane Q is the whole one: Zm = Z, wm = 1
                // and A = (Z + Z) / 2 = Z exactly.
                // Within the radiance the window saw, at this pixel's
                // albedo: a plane extrapolates, and a mixed pixel's z (an
                // emitter's anti-aliased edge) is no one side's light.
                const float A  = (Z + wm * Zm) / (1.0f + wm);
                const float ia = inv_albedo[ch][q];
                const float Al = std::min(std::max(A, range.llo[ch] * ia),
                                          range.lhi[ch] * ia);
                out_a[ch][q] = s * Al;
                if (kHat) {
                    // The blend's weight follows the point too: w_m = r^p
                    // with ln r = |ln a - ln b|, so dw_m = p w_m d ln r
                    // (none where w_m is at its bound), and
                    // dA = (h + w_m h_m + (Zm - Z) dw_m / (1 + w_m)) / (1 + w_m).
                    // A clamped channel does not follow its own value.
                    const float da  = (Z < 0.0f ? -h_whole : h_whole) / a;
                    const float db  = (Zm < 0.0f ? -h_quadrant : h_quadrant) / b;
                    const float dln = a >= b ? da - db : db - da;
                    const float dwm = wm < float(kMaxWm)
                                          ? (kPower8 ? 8.0f : power) * wm * dln
                                          : 0.0f;
                    const float H = (h_whole + wm * h_quadrant
                                     + (Zm - Z) * dwm / (1.0f + wm))
                                    / (1.0f + wm);
                    H_l += kLumaWeights[ch] * (Al == A ? H : 0.0f);
                    A_l += kLumaWeights[ch] * Al;
                }
            }
            out_s[q] = s;
            if (kHat) {
                // d ln(weight) / d zl of a fit point's value term (where
                // exp_neg does not clamp it).
                const float t = value_scale * std::fabs(zl[q] - mean);
                const float c = fit && t < kValueClamp
                                    ? (zl[q] > mean   ? value_scale
                                       : zl[q] < mean ? -value_scale
                                                      : 0.0f)
                                    : 0.0f;
                h[q]   = s * H_l * (1.0f - c * (zl[q] - A_l));
                hc[q]  = s * c;
                hca[q] = s * c * A_l;
            }
        }
    }
}

#define ZDENOISE_SPLAT_NAMES                                                   \
    cls, gw, fitw, values, spat, zl, ia0, ia1, ia2, out_s, a0, a1, a2, h, hc, hca

ZDENOISE_ROW_KERNEL void
splat_row_power8(ZDENOISE_SPLAT_POINTERS, const SplatRow& in)
{
    splat_lanes<true, false>(ZDENOISE_SPLAT_NAMES, in, 8.0f);
}

void
splat_row(ZDENOISE_SPLAT_POINTERS, const SplatRow& in, float power)
{
    splat_lanes<false, false>(ZDENOISE_SPLAT_NAMES, in, power);
}

// With the hat diagonal (selection's risk only): not the default's cost.
ZDENOISE_ROW_KERNEL void
splat_row_power8_hat(ZDENOISE_SPLAT_POINTERS, const SplatRow& in)
{
    splat_lanes<true, true>(ZDENOISE_SPLAT_NAMES, in, 8.0f);
}

void
splat_row_hat(ZDENOISE_SPLAT_POINTERS, const SplatRow& in, float power)
{
    splat_lanes<false, true>(ZDENOISE_SPLAT_NAMES, in, power);
}
#undef ZDENOISE_SPLAT_NAMES

}  // namespace

void
RangeLanes::clear()
{
    for (int ch = 0; ch < 3; ++ch)
        for (int l = 0; l < kLanes; ++l) {
            llo[ch][l] = std::numeric_limits<float>::infinity();
            lhi[ch][l] = -std::numeric_limits<float>::infinity();
        }
}


WindowRange::WindowRange(const RangeLanes& r)
{
    for (int ch = 0; ch < 3; ++ch) {
        llo[ch] = *std::min_element(r.llo[ch], r.llo[ch] + kLanes);
        lhi[ch] = *std::max_element(r.lhi[ch], r.lhi[ch] + kLanes);
    }
}


/// The splat of one row segment, by the kernel that fits quadrant_power.
void
splat_row(const SplatRow& in, float power)
{
    if (in.hat[0]) {
        if (power == 8.0f)
            splat_row_power8_hat(ZDENOISE_SPLAT_ARGS(in), in);
        else
            splat_row_hat(ZDENOISE_SPLAT_ARGS(in), in, power);
    } else if (power == 8.0f)
        splat_row_power8(ZDENOISE_SPLAT_ARGS(in), in);
    else
        splat_row(ZDENOISE_SPLAT_ARGS(in), in, power);
}
#undef ZDENOISE_SPLAT_POINTERS
#undef ZDENOISE_SPLAT_ARGS


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
