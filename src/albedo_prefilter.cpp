// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// prefilter_albedo(): the renderer's noisy albedo AOV made clean before it
// demodulates and remodulates (docs/FILTER.md section 12): non-local means
// over its own patches, with the variance of each pixel from the
// anti-aliasing (coverage) noise of N samples.

#include <zdenoise/zdenoise.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imagebufalgo_util.h>

#include "albedo_prefilter_kernels.h"
#include "checks.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;

namespace {

/// Offsets searched: the (2 kSearch + 1)^2 around a pixel.
constexpr int kSearch = 3;
/// Half-size of the patches compared (3x3).
constexpr int kPatch = 1;
/// exp(-t) of a float is 0 for every t at least this (2^-150 rounds to 0).
constexpr float kNoWeight = 103.972084f;
/// Rows a thread filters at a time.
constexpr int kBandRows = 16;
/// Keeps 0 / 0 defined where neither pixel has noise (then any difference
/// is texture, and weighs 0).
constexpr float kVarianceFloor = 1e-10f;

/// The albedo's RGB over its data window `win`, and the variance of each
/// value; NaN marks a value that takes no part (not finite).
struct AlbedoPlanes {
    ROI win;
    std::vector<float> a, v;
    /// a and v again, a plane a channel, for the row kernels.
    std::vector<float> planar_a[3], planar_v[3];

    size_t index(int x, int y) const
    {
        return size_t(y - win.ybegin) * size_t(win.width())
               + size_t(x - win.xbegin);
    }
    bool inside(int x, int y) const
    {
        return x >= win.xbegin && x < win.xend && y >= win.ybegin
               && y < win.yend;
    }
    /// Whether the 3x3 around (x, y) is not flat (some neighbour differs
    /// in some channel): only such a pixel's footprint can mix albedos. A
    /// flat one is exact and stays as it is.
    bool mixes(int x, int y) const
    {
        const size_t i = 3 * index(x, y);
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                if (!inside(x + dx, y + dy))
                    continue;
                const size_t j = 3 * index(x + dx, y + dy);
                for (int c = 0; c < 3; ++c)
                    if (a[j + c] != a[i + c])
                        return true;
            }
        return false;
    }
};

/// Section 12: the variance of a pixel mean of N stratified samples of a
/// pixel whose footprint mixes the albedos lo and hi (the least and the
/// most of its 3x3) in the proportion t its value says:
/// (hi - lo)^2 t (1 - t) / N^(3/2).
void
coverage_variance(AlbedoPlanes& p, int samples, int nthreads)
{
    const ROI& w = p.win;
    p.v.assign(p.a.size(), 0.0f);
    // N^(3/2): renderers stratify a pixel's samples, and the variance of a
    // jittered estimate of an edge's coverage falls as N^(-3/2), not
    // N^(-1) (measured on the public set: 8x less from 4 to 16 and from
    // 16 to 64 spp).
    const float strata = std::pow(float(samples), 1.5f);
    parallel_for(int64_t(w.ybegin), int64_t(w.yend), [&](int64_t y) {
        for (int x = w.xbegin; x < w.xend; ++x)
            for (int c = 0; c < 3; ++c) {
                const size_t i = 3 * p.index(x, int(y)) + size_t(c);
                const float a  = p.a[i];
                if (!std::isfinite(a)) {
                    p.v[i] = std::numeric_limits<float>::quiet_NaN();
                    continue;
                }
                float lo = a, hi = a;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        if (!p.inside(x + dx, int(y) + dy))
                            continue;
                        const float b = p.a[3 * p.index(x + dx, int(y) + dy)
                                            + size_t(c)];
                        if (std::isfinite(b)) {
                            lo = std::min(lo, b);
                            hi = std::max(hi, b);
                        }
                    }
                p.v[i] = detail::albedo_mixture_variance(a, lo, hi) / strata;
            }
    }, detail::paropt_any_length(nthreads));
}


/// The variance the halves `a` and `b` show (the mean over the 3x3 of
/// (a - b)^2 / 4, finite values within the window), where it is above the
/// model's: the larger of two estimates, so that noise the model does not
/// know (texture finer than its 3x3) is not taken for texture.
bool
halves_variance(AlbedoPlanes& p, const ImageBuf& half_a,
                const ImageBuf& half_b, int nthreads)
{
    std::vector<float> a(p.a.size()), b(p.a.size());
    if (!half_a.get_pixels(p.win, TypeFloat, a.data())
        || !half_b.get_pixels(p.win, TypeFloat, b.data()))
        return false;
    for (size_t i = 0; i < a.size(); ++i) {
        const float d = a[i] - b[i];
        a[i] = std::isfinite(d) ? 0.25f * d * d
                                : std::numeric_limits<float>::quiet_NaN();
    }
    const ROI& w = p.win;
    parallel_for(int64_t(w.ybegin), int64_t(w.yend), [&](int64_t y) {
        for (int x = w.xbegin; x < w.xend; ++x)
            for (int c = 0; c < 3; ++c) {
                const size_t i = 3 * p.index(x, int(y)) + size_t(c);
                float sum = 0.0f;
                int n     = 0;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        if (!p.inside(x + dx, int(y) + dy))
                            continue;
                        const float h = a[3 * p.index(x + dx, int(y) + dy)
                                          + size_t(c)];
                        if (std::isfinite(h)) {
                            sum += h;
                            ++n;
                        }
                    }
                if (n && std::isfinite(p.v[i]))
                    p.v[i] = std::max(p.v[i], sum / float(n));
            }
    }, detail::paropt_any_length(nthreads));
    return true;
}


/// Rows of a band of the output `roi`: the weighted sums of section 12
/// over the 7x7 offsets, into acc and wsum (indexed as roi), and which
/// pixels are filtered (those whose 3x3 mixes albedos).
void
filter_rows(const AlbedoPlanes& p, const ROI& rows, const ROI& roi,
            std::vector<double>& acc, std::vector<double>& wsum,
            std::vector<uint8_t>& filtered)
{
    auto out_index = [&](int x, int y) {
        return size_t(y - roi.ybegin) * size_t(roi.width())
               + size_t(x - roi.xbegin);
    };
    bool any = false;
    for (int y = rows.ybegin; y < rows.yend; ++y)
        for (int x = rows.xbegin; x < rows.xend; ++x)
            if (p.mixes(x, y)) {
                filtered[out_index(x, y)] = 1;
                any                       = true;
            }
    if (!any)
        return;
    // The patch distances over the rows and their patch border, as sums of
    // the defined ones and their counts, then summed along rows.
    ROI near    = rows;
    near.xbegin = std::max(rows.xbegin - kPatch, p.win.xbegin);
    near.xend   = std::min(rows.xend + kPatch, p.win.xend);
    near.ybegin = std::max(rows.ybegin - kPatch, p.win.ybegin);
    near.yend   = std::min(rows.yend + kPatch, p.win.yend);
    const int nw = near.width();
    auto near_index = [&](int x, int y) {
        return size_t(y - near.ybegin) * size_t(nw) + size_t(x - near.xbegin);
    };
    const size_t nn = size_t(near.npixels());
    std::vector<float> d(nn), dn(nn), hs(nn), hn(nn);
    for (int oy = -kSearch; oy <= kSearch; ++oy)
        for (int ox = -kSearch; ox <= kSearch; ++ox) {
            // d(p) = mean_c ((A_p - A_q)^2 - (V_p + min(V_p, V_q)))
            //        / (V_p + V_q), q = p + offset; undefined (count 0)
            // where there is no such q or either is not finite.
            const int xa = std::max(near.xbegin, p.win.xbegin - ox);
            const int xb = std::min(near.xend, p.win.xend - ox);
            for (int y = near.ybegin; y < near.yend; ++y) {
                float* dr  = &d[near_index(near.xbegin, y)];
                float* dnr = &dn[near_index(near.xbegin, y)];
                std::fill(dr, dr + nw, 0.0f);
                std::fill(dnr, dnr + nw, 0.0f);
                if (y + oy < p.win.ybegin || y + oy >= p.win.yend)
                    continue;
                if (xb <= xa)
                    continue;
                const size_t i = p.index(xa, y), j = p.index(xa + ox, y + oy);
                const float* ap[3] = { &p.planar_a[0][i], &p.planar_a[1][i], &p.planar_a[2][i] };
                const float* vp[3] = { &p.planar_v[0][i], &p.planar_v[1][i], &p.planar_v[2][i] };
                const float* aq[3] = { &p.planar_a[0][j], &p.planar_a[1][j], &p.planar_a[2][j] };
                const float* vq[3] = { &p.planar_v[0][j], &p.planar_v[1][j], &p.planar_v[2][j] };
                detail::patch_distance_row(ap, vp, aq, vq, xb - xa, kVarianceFloor,
                                           &dr[xa - near.xbegin], &dnr[xa - near.xbegin]);
            }
            // Sums over x-1..x+1 within the band's columns.
            for (int y = near.ybegin; y < near.yend; ++y) {
                const size_t r = near_index(near.xbegin, y);
                detail::box3_row(&d[r], &dn[r], nw, &hs[r], &hn[r]);
            }
            // w(p, q) = exp(-max(0, mean of d over p's 3x3 patch))
            for (int y = rows.ybegin; y < rows.yend; ++y) {
                if (y + oy < p.win.ybegin || y + oy >= p.win.yend)
                    continue;
                const int y0 = std::max(y - kPatch, near.ybegin);
                const int y1 = std::min(y + kPatch, near.yend - 1);
                for (int x = std::max(rows.xbegin, xa);
                     x < std::min(rows.xend, xb); ++x) {
                    const size_t o = out_index(x, y);
                    if (!filtered[o] || dn[near_index(x, y)] == 0.0f)
                        continue;
                    float sum = 0.0f, n = 0.0f;
                    for (int yy = y0; yy <= y1; ++yy) {
                        sum += hs[near_index(x, yy)];
                        n += hn[near_index(x, yy)];
                    }
                    // Past kNoWeight expf is 0, reached through libm's
                    // slow underflow path: skip the call (most offsets
                    // in texture are that far).
                    const float t = std::max(sum / n, 0.0f);
                    if (!(t < kNoWeight))
                        continue;
                    const float w = std::exp(-t);
                    const size_t j = 3 * p.index(x + ox, y + oy);
                    for (int c = 0; c < 3; ++c)
                        acc[3 * o + c] += double(w) * double(p.a[j + c]);
                    wsum[o] += double(w);
                }
            }
        }
}

}  // namespace


int
albedo_prefilter_halo()
{
    // The search (3), the patch (1) and the variance's 3x3 (1).
    return kSearch + kPatch + 1;
}


namespace {

bool
prefilter(ImageBuf& dst, const ImageBuf& albedo, int samples,
          const ImageBuf* half_a, const ImageBuf* half_b, ROI roi,
          int nthreads)
{
    const char* opname = "prefilter_albedo";
    if (!detail::prepare_dst(dst, albedo, roi, opname)
        || !detail::check_input(dst, albedo, opname, "albedo", roi, 3))
        return false;
    if (half_a
        && (!detail::check_input(dst, *half_a, opname, "half_a",
                                 albedo.roi(), 3)
            || !detail::check_input(dst, *half_b, opname, "half_b",
                                    albedo.roi(), 3)))
        return false;
    if (samples < 1) {
        dst.errorfmt("{}: samples = {} is invalid: needs >= 1", opname,
                     samples);
        return false;
    }
    AlbedoPlanes p;
    p.win          = albedo.roi();
    p.win.chbegin  = 0;
    p.win.chend    = 3;
    p.a.resize(size_t(p.win.npixels()) * 3);
    if (!albedo.get_pixels(p.win, TypeFloat, p.a.data())) {
        dst.errorfmt("{}: {}", opname, albedo.geterror());
        return false;
    }
    for (float& a : p.a)
        if (!std::isfinite(a))
            a = std::numeric_limits<float>::quiet_NaN();
    coverage_variance(p, samples, nthreads);
    if (half_a && !halves_variance(p, *half_a, *half_b, nthreads)) {
        dst.errorfmt("{}: cannot read the halves' albedos", opname);
        return false;
    }
    for (int c = 0; c < 3; ++c) {
        p.planar_a[c].resize(p.a.size() / 3);
        p.planar_v[c].resize(p.a.size() / 3);
        for (size_t i = 0; i < p.planar_a[c].size(); ++i) {
            p.planar_a[c][i] = p.a[3 * i + size_t(c)];
            p.planar_v[c][i] = p.v[3 * i + size_t(c)];
        }
    }
    // In bands of rows, each on its own (all its offsets, then the next
    // band), so that a band's planes stay in cache; each pixel adds its
    // offsets in one fixed order, so the result does not depend on the
    // threads.
    const size_t npix = size_t(roi.width()) * size_t(roi.height());
    std::vector<double> acc(3 * npix, 0.0), wsum(npix, 0.0);
    std::vector<uint8_t> filtered(npix, 0);
    const int nbands = (roi.height() + kBandRows - 1) / kBandRows;
    parallel_for(0, nbands, [&](int band) {
        ROI rows   = roi;
        rows.ybegin = roi.ybegin + band * kBandRows;
        rows.yend   = std::min(rows.ybegin + kBandRows, roi.yend);
        filter_rows(p, rows, roi, acc, wsum, filtered);
    }, detail::paropt_any_length(nthreads));  // a task a band
    // RGB from the weighted means (the pixel itself always weighs 1); a
    // value that is not finite, and the other channels, as they were.
    ROI all    = roi;
    all.chbegin = 0;
    all.chend   = albedo.nchannels();
    const int nch = all.nchannels();
    std::vector<float> out(npix * size_t(nch));
    albedo.get_pixels(all, TypeFloat, out.data());
    for (size_t o = 0; o < npix; ++o)
        for (int c = 0; c < 3; ++c) {
            float& v = out[o * size_t(nch) + size_t(c)];
            if (filtered[o] && std::isfinite(v) && wsum[o] > 0.0)
                v = float(acc[3 * o + c] / wsum[o]);
        }
    if (!dst.set_pixels(all, TypeFloat, out.data())) {
        if (!dst.has_error())
            dst.errorfmt("{}: could not store the result", opname);
        return false;
    }
    return true;
}


}  // namespace


bool
prefilter_albedo(ImageBuf& dst, const ImageBuf& albedo, int samples, ROI roi,
                 int nthreads)
{
    return prefilter(dst, albedo, samples, nullptr, nullptr, roi, nthreads);
}


bool
prefilter_albedo(ImageBuf& dst, const ImageBuf& albedo, int samples,
                 const ImageBuf& half_a, const ImageBuf& half_b, ROI roi,
                 int nthreads)
{
    return prefilter(dst, albedo, samples, &half_a, &half_b, roi, nthreads);
}


ImageBuf
prefilter_albedo(const ImageBuf& albedo, int samples, ROI roi, int nthreads)
{
    return detail::returned_image("prefilter_albedo", [&](ImageBuf& result) {
        return prefilter_albedo(result, albedo, samples, roi, nthreads);
    });
}

}  // namespace zdenoise
