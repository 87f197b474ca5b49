// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The beauty's alpha (docs/ALPHA.md): denoised with the render's guides
// where it is fractional (motion blur, depth of field, transparent film),
// unless --no-alpha.

#pragma once

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/zdenoise.h>

#include "input_files.h"
#include "job_types.h"
#include "strips.h"

namespace zdenoise {
namespace job {

/// The --in file's channel of the alpha that job `j` denoises: the
/// radiance's fourth (R,G,B,A), unless --no-alpha; -1: none.
int
denoised_alpha_channel(const Job& j, const Selection& radiance);

/// The alpha of a strip's radiance image (its channel 3, over the held
/// rows) as one float channel, read before any other frame is combined
/// with the radiance.
OIIO::ImageBuf
strip_alpha(const Job& j, const OIIO::ImageBuf& radiance);

/// Strip `strip`'s alpha `held` (strip_alpha(); of the image `frame`)
/// denoised over the strip's rows into `alpha` (one float channel; `held`
/// as it is where the held rows have no fractional or non-finite alpha).
/// The colour is denoised as with --no-alpha.
void
denoise_strip_alpha(const Job& j, const Strip& strip, const OIIO::ROI& frame,
                    const OIIO::ImageBuf& held, const Guides& guides,
                    OIIO::ImageBuf& alpha);

}  // namespace job
}  // namespace zdenoise
