// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "strips.h"

#include <algorithm>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include "internal.h"
#include "failure.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

bool
wraps(const RowReader& rows, const Selection& s,
      const std::vector<ChannelRun>& runs)
{
    return runs.size() == 1 && rows.aligned(s.indices[0]);
}


void
Strip::place(const ROI& noisy, int index, int rows, int around)
{
    core        = noisy;
    core.ybegin = noisy.ybegin + index * rows;
    core.yend   = std::min(core.ybegin + rows, noisy.yend);
    held        = core;
    held.ybegin = std::max(core.ybegin - around, noisy.ybegin);
    held.yend   = std::min(core.yend + around, noisy.yend);
}


ImageBuf
Strip::image(const Selection& s, bool read_only) const
{
    const RowReader& rows = files->rows(s.path);
    const int nch         = int(s.indices.size());
    const std::vector<ChannelRun> runs = channel_runs(rows, s.indices);
    const int c0    = s.indices[0];
    const bool wrap = read_only && wraps(rows, s, runs);
    ImageSpec spec(held.width(), held.height(), nch,
                   wrap ? rows.format(c0) : TypeFloat);
    spec.x = spec.full_x = held.xbegin;
    spec.y = spec.full_y = held.ybegin;
    spec.channelnames    = s.names;
    spec.alpha_channel   = -1;
    for (int c = 0; c < nch; ++c)
        if (Strutil::iequals(s.names[size_t(c)], "A")
            || Strutil::iequals(s.names[size_t(c)], "alpha"))
            spec.alpha_channel = c;
    if (wrap)
        return ImageBuf(spec,
                        const_cast<unsigned char*>(
                            rows.at(c0, held.xbegin, held.ybegin)),
                        rows.stride(c0), rows.row_stride(c0));
    ImageBuf img(spec, InitializePixels::No);
    auto* px = static_cast<unsigned char*>(img.localpixels());
    const stride_t pixel = stride_t(nch) * 4;
    parallel_for(int64_t(held.ybegin), int64_t(held.yend), [&](int64_t y) {
        unsigned char* dst = px
                             + size_t(y - held.ybegin) * size_t(pixel)
                                   * size_t(held.width());
        for (const ChannelRun& r : runs) {
            const int c = s.indices[size_t(r.first)];
            move_channels(rows.at(c, held.xbegin, int(y)), rows.format(c),
                          rows.stride(c), dst + 4 * r.first, TypeFloat,
                          pixel, r.count, held.width());
        }
    }, detail::paropt_any_length(threads));
    return img;
}


ImageBuf
Strip::sum(const std::vector<Selection>& terms, bool read_only) const
{
    ImageBuf total;
    for (const Selection& t : terms) {
        ImageBuf img = image(t, total.initialized()
                                    || (read_only && terms.size() == 1));
        if (!total.initialized())
            total = std::move(img);
        else if (!ImageBufAlgo::add(total, total, img, {}, threads))
            fail(format("'{}': {}", t.path, one_line(total.geterror())));
    }
    return total;
}

}  // namespace job
}  // namespace zdenoise
