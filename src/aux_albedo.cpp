// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// pool_aux_albedo(): an auxiliary albedo checked against the render's own,
// pixel by pixel, and pooled with it (docs/AUX.md, "Wrong auxiliary
// pixels"). An auxiliary render that misses the world, an emitter or a
// holdout, or shows another frame, would otherwise put a wrong albedo
// into remodulation, which no filter can undo.

#include <zdenoise/zdenoise.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <OpenImageIO/imagebufalgo_util.h>

#include "checks.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;

namespace {

/// Standard deviations of the difference beyond which the two albedos are
/// not estimates of one pixel: under noise alone fewer than 1 channel in
/// 15,000 passes 4 (one-sided, normal), and the mixture variance below
/// overstates the noise of stratified samples.
constexpr float kDisagreement = 4.0f;

/// The neighbourhood whose pixels bound the values a pixel's samples take
/// (the 5x5): pixel means are narrower than the samples they average, and
/// a 3x3 of texture about 2 pixels wide holds no pixel of one albedo
/// alone.
constexpr int kReach = 2;

/// One albedo's RGB over its data window; NaN marks a value not finite.
struct Planes {
    ROI win;
    std::vector<float> a;

    bool load(const ImageBuf& img)
    {
        win         = img.roi();
        win.chbegin = 0;
        win.chend   = 3;
        a.resize(size_t(win.npixels()) * 3);
        if (!img.get_pixels(win, TypeFloat, a.data()))
            return false;
        for (float& v : a)
            if (!std::isfinite(v))
                v = std::numeric_limits<float>::quiet_NaN();
        return true;
    }
    const float* at(int x, int y) const
    {
        return &a[3 * (size_t(y - win.ybegin) * size_t(win.width())
                       + size_t(x - win.xbegin))];
    }
    /// Widen [lo, hi] to the finite values of channel c in the 5x5 around
    /// (x, y) (within the window).
    void widen(int x, int y, int c, float& lo, float& hi) const
    {
        for (int dy = -kReach; dy <= kReach; ++dy)
            for (int dx = -kReach; dx <= kReach; ++dx) {
                const int qx = x + dx, qy = y + dy;
                if (qx < win.xbegin || qx >= win.xend || qy < win.ybegin
                    || qy >= win.yend)
                    continue;
                const float b = at(qx, qy)[c];
                if (std::isfinite(b)) {
                    lo = std::min(lo, b);
                    hi = std::max(hi, b);
                }
            }
    }
};

}  // namespace


int
aux_albedo_halo()
{
    return kReach;
}


bool
pool_aux_albedo(ImageBuf& dst, const ImageBuf& aux, const ImageBuf& render,
                const AuxAlbedoOptions& options, AuxAlbedoStats* stats,
                ROI roi, int nthreads)
{
    const char* opname = "pool_aux_albedo";
    if (!detail::prepare_dst(dst, aux, roi, opname)
        || !detail::check_input(dst, aux, opname, "aux albedo", roi, 3)
        || !detail::check_input(dst, render, opname, "render albedo", roi, 3))
        return false;
    if (options.render_samples < 1 || options.aux_samples < 0
        || !(options.precision >= 0.0f)) {
        dst.errorfmt("{}: render_samples = {}, aux_samples = {}, precision = "
                     "{} are invalid: need >= 1, >= 0 (0: exact), >= 0",
                     opname, options.render_samples, options.aux_samples,
                     options.precision);
        return false;
    }
    Planes a, r;
    if (!a.load(aux) || !r.load(render)) {
        dst.errorfmt("{}: {}{}", opname, aux.geterror(), render.geterror());
        return false;
    }
    // The test takes the samples as independent (variance / N, more than
    // a stratified sampler leaves), so that noise is not taken for a wrong
    // pixel; the pooling weighs each by the inverse of its stratified
    // variance, N^(3/2), as the prefilter models it.
    const float nr = float(options.render_samples);
    const float na = float(options.aux_samples);
    const bool exact = options.aux_samples == 0;
    const float wr = exact ? 0.0f : std::pow(nr, 1.5f);
    const float wa = exact ? 1.0f : std::pow(na, 1.5f);

    ROI all    = roi;
    all.chbegin = 0;
    all.chend   = aux.nchannels();
    const int nch     = all.nchannels();
    const size_t npix = size_t(roi.npixels());
    std::vector<float> out(npix * size_t(nch));
    if (!aux.get_pixels(all, TypeFloat, out.data())) {
        dst.errorfmt("{}: {}", opname, aux.geterror());
        return false;
    }
    std::vector<uint8_t> rejected(npix, 0);
    parallel_for(int64_t(roi.ybegin), int64_t(roi.yend), [&](int64_t yy) {
        const int y = int(yy);
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t o = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            const float* av = a.at(x, y);
            const float* rv = r.at(x, y);
            bool disagree = false, render_finite = true;
            for (int c = 0; c < 3; ++c) {
                if (!std::isfinite(rv[c])) {
                    render_finite = false;
                    continue;
                }
                if (!std::isfinite(av[c])) {
                    disagree = true;
                    continue;
                }
                // The values a sample near here can take: both albedos'
                // 5x5 (each one's pixels are means, narrower than its
                // samples; the other's widen them where it differs).
                float lo = rv[c], hi = rv[c];
                r.widen(x, y, c, lo, hi);
                a.widen(x, y, c, lo, hi);
                // Both estimate one mean if they agree: the variance is
                // that of the pooled mean (at an extreme of the range a
                // pixel's own value would claim none).
                const float mean = exact ? av[c]
                                         : (wr * rv[c] + wa * av[c]) / (wr + wa);
                const float spread = detail::albedo_mixture_variance(mean, lo,
                                                                     hi);
                const float var = spread / nr + (exact ? 0.0f : spread / na);
                const float bound = kDisagreement * std::sqrt(var)
                                    + options.precision
                                          * (std::abs(rv[c]) + std::abs(av[c]));
                if (std::abs(rv[c] - av[c]) > bound)
                    disagree = true;
            }
            float* ov = &out[o * size_t(nch)];
            if (disagree && render_finite) {
                rejected[o] = 1;
                for (int c = 0; c < 3; ++c)
                    ov[c] = rv[c];
            } else if (!exact && render_finite) {
                for (int c = 0; c < 3; ++c)
                    ov[c] = (wr * rv[c] + wa * av[c]) / (wr + wa);
            }
        }
    }, detail::paropt_any_length(nthreads));
    if (stats) {
        const ROI counted = options.counted.defined()
                                ? roi_intersection(options.counted, roi)
                                : roi;
        *stats = {};
        for (int y = counted.ybegin; y < counted.yend; ++y)
            for (int x = counted.xbegin; x < counted.xend; ++x) {
                stats->pixels += 1;
                stats->rejected += rejected[size_t(y - roi.ybegin)
                                                * size_t(roi.width())
                                            + size_t(x - roi.xbegin)];
            }
    }
    if (!dst.set_pixels(all, TypeFloat, out.data())) {
        if (!dst.has_error())
            dst.errorfmt("{}: could not store the result", opname);
        return false;
    }
    return true;
}

}  // namespace zdenoise
