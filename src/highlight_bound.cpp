// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// bound_highlights() (docs/FILTER.md section 1a): the largest input value of
// each channel over the 9x9 around a pixel (sliding extrema by rows, then
// columns) bounds the denoised value from above.

#include <zdenoise/highlights.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "checks.h"
#include "filter/filter_inputs.h"
#include "filter/sliding_extrema.h"
#include "internal.h"

namespace zdenoise {

namespace {

constexpr float kNoValue = -std::numeric_limits<float>::infinity();

/// The largest finite value of each channel of `rgb` (3 floats a pixel over
/// `area`) within kHighlightRadius, at each pixel of `roi` (inside area):
/// by rows, then columns (sliding_extrema.h); kNoValue where there is none.
std::vector<float>
input_maxima(const std::vector<float>& rgb, const ROI& area, const ROI& roi,
             int nthreads)
{
    const size_t aw = size_t(area.width()), ah = size_t(area.height());
    const size_t w = size_t(roi.width());
    // Per channel, the rows' maxima over roi's columns: ah rows of w.
    std::vector<float> rows(3 * ah * w);
    detail::for_rows(area, nthreads, [&](int y) {
        const size_t row = size_t(y - area.ybegin);
        std::vector<float> value(aw), most(aw);
        detail::SlidingExtrema ext;
        for (size_t c = 0; c < 3; ++c) {
            for (size_t u = 0; u < aw; ++u) {
                const float v = rgb[3 * (row * aw + u) + c];
                value[u]      = std::isfinite(v) ? v : kNoValue;
            }
            ext.run_most(value.data(), int(aw), 1, kHighlightRadius, most.data());
            std::copy_n(&most[size_t(roi.xbegin - area.xbegin)], w, &rows[(c * ah + row) * w]);
        }
    });
    std::vector<float> out(3 * roi.npixels());
    OIIO::parallel_for(int64_t(0), int64_t(3 * w), [&](int64_t col) {
        const size_t c = size_t(col) / w, x = size_t(col) % w;
        std::vector<float> most(ah);
        detail::SlidingExtrema ext;
        ext.run_most(&rows[c * ah * w + x], int(ah), w, kHighlightRadius, most.data());
        for (int y = roi.ybegin; y < roi.yend; ++y)
            out[3 * (size_t(y - roi.ybegin) * w + x) + c] = most[size_t(y - area.ybegin)];
    }, detail::paropt_any_length(nthreads));
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
    const std::vector<float> bound = input_maxima(
        detail::read_channels(radiance, around, 0, 3), around, roi, nthreads);
    std::vector<float> out = detail::read_channels(dst, roi, 0, 3);
    for (size_t i = 0; i < out.size(); ++i)
        if (bound[i] != kNoValue && std::isfinite(out[i]) && out[i] > bound[i])
            out[i] = bound[i];
    const ROI rgb(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1, 0, 3);
    if (!dst.set_pixels(rgb, OIIO::TypeFloat, out.data())) {
        dst.errorfmt("{}: cannot write dst: {}", opname, dst.geterror());
        return false;
    }
    return true;
}

}  // namespace zdenoise
