// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// bound_highlights() (docs/FILTER.md section 1a): the largest input value of
// each channel over the 9x9 around a pixel, by rows then columns, bounds the
// denoised value from above.

#include <zdenoise/highlights.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "checks.h"
#include "filter/filter_inputs.h"
#include "internal.h"

namespace zdenoise {

namespace {

constexpr float kNoValue = -std::numeric_limits<float>::infinity();

/// The largest finite value of each channel of `rgb` (3 floats a pixel over
/// `area`) within kHighlightRadius along x, at each pixel of the x range
/// [xbegin, xend) on every row of `area`; kNoValue where there is none.
std::vector<float>
row_maxima(const std::vector<float>& rgb, const ROI& area, int xbegin,
           int xend, int nthreads)
{
    const size_t aw = size_t(area.width()), ow = size_t(xend - xbegin);
    std::vector<float> out(3 * ow * size_t(area.height()), kNoValue);
    detail::for_rows(area, nthreads, [&](int y) {
        const size_t row = size_t(y - area.ybegin);
        for (int x = xbegin; x < xend; ++x) {
            const int u0 = std::max(x - kHighlightRadius, area.xbegin);
            const int u1 = std::min(x + kHighlightRadius + 1, area.xend);
            float* o     = &out[3 * (row * ow + size_t(x - xbegin))];
            for (int u = u0; u < u1; ++u)
                for (int c = 0; c < 3; ++c) {
                    const float v = rgb[3 * (row * aw + size_t(u - area.xbegin)) + size_t(c)];
                    if (std::isfinite(v))
                        o[c] = std::max(o[c], v);
                }
        }
    });
    return out;
}

}  // namespace


bool
bound_highlights(ImageBuf& dst, const ImageBuf& radiance, ROI frame, ROI roi,
                 int nthreads)
{
    const char* opname = "bound_highlights";
    if (!dst.initialized()) {
        dst.errorfmt("{}: dst is not initialized", opname);
        return false;
    }
    if (!roi.defined())
        roi = dst.roi();
    if (!frame.defined())
        frame = radiance.initialized() ? radiance.roi() : roi;
    if (!detail::check_input(dst, dst, opname, "dst", roi, 3)
        || !detail::check_frame(dst, opname, roi, frame))
        return false;
    const ROI around = detail::halo_region(roi, frame, kHighlightRadius);
    if (!detail::check_input(dst, radiance, opname, "radiance", around, 3))
        return false;
    const std::vector<float> in = detail::read_channels(radiance, around, 0, 3);
    const std::vector<float> rows
        = row_maxima(in, around, roi.xbegin, roi.xend, nthreads);
    std::vector<float> out = detail::read_channels(dst, roi, 0, 3);
    const size_t w = size_t(roi.width());
    detail::for_rows(roi, nthreads, [&](int y) {
        const int v0 = std::max(y - kHighlightRadius, around.ybegin);
        const int v1 = std::min(y + kHighlightRadius + 1, around.yend);
        for (size_t x = 0; x < w; ++x) {
            float bound[3] = { kNoValue, kNoValue, kNoValue };
            for (int v = v0; v < v1; ++v)
                for (int c = 0; c < 3; ++c)
                    bound[c] = std::max(bound[c],
                                        rows[3 * (size_t(v - around.ybegin) * w + x) + size_t(c)]);
            float* o = &out[3 * (size_t(y - roi.ybegin) * w + x)];
            for (int c = 0; c < 3; ++c)
                if (bound[c] != kNoValue && std::isfinite(o[c]) && o[c] > bound[c])
                    o[c] = bound[c];
        }
    });
    const ROI rgb(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1, 0, 3);
    if (!dst.set_pixels(rgb, OIIO::TypeFloat, out.data())) {
        dst.errorfmt("{}: cannot write dst: {}", opname, dst.geterror());
        return false;
    }
    return true;
}

}  // namespace zdenoise
