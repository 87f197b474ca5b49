// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Strips: the band of rows a job holds at a time. A strip is its own rows
// (`core`) and the rows around them they depend on (`held`), and turns a
// role's channels of the files' held rows into an image (a float copy, or
// the rows themselves). The height of strips is the memory plan's
// (memory_plan.h).

#pragma once

#include <algorithm>

#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "input_files.h"
#include "pixel_moves.h"

namespace zdenoise {
namespace job {

/// Whether a role's channels can be handed to the library as the file's
/// rows themselves: next to each other, of one type, where that type may
/// be read.
bool
wraps(const RowReader& rows, const Selection& s,
      const std::vector<ChannelRun>& runs);


/// The rows the current strip holds: the strip's own rows (`core`) and the
/// rows around them that they depend on (`held`: the filter's halo, and
/// the residual layer mask's reach), x over the noisy input's columns.
struct Strip {
    OIIO::ROI core, held;
    InputFiles* files = nullptr;
    int threads       = 0;

    /// Strip `index` of the frame `noisy` cut in strips of `rows` rows,
    /// holding `around` rows above and below (within the frame).
    void place(const OIIO::ROI& noisy, int index, int rows, int around);

    /// The strip's rows and `rows` more above and below (at most `around`),
    /// within the frame.
    OIIO::ROI widened(int rows) const
    {
        OIIO::ROI r = core;
        r.ybegin    = std::max(core.ybegin - rows, held.ybegin);
        r.yend      = std::min(core.yend + rows, held.yend);
        return r;
    }

    /// A role's channels over the held rows: a float image of its own, or
    /// for an image only read (`read_only`) and whose channels lie next to
    /// each other in the file in one pixel type, the file's rows themselves
    /// (no copy; the operations take any pixel type and convert exactly as
    /// the copy would). Valid until the rows move on.
    OIIO::ImageBuf image(const Selection& s, bool read_only = false) const;

    /// The sum of the images of `terms`, a float image of its own unless
    /// only read (`read_only`).
    OIIO::ImageBuf sum(const std::vector<Selection>& terms,
                       bool read_only = true) const;
};

}  // namespace job
}  // namespace zdenoise
