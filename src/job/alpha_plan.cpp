// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "alpha_plan.h"

#include <cmath>
#include <vector>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <zdenoise/alpha.h>

#include "failure.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// Does the image's channel 0 hold a value other than exactly 0 or 1?
bool
fractional(const ImageBuf& alpha)
{
    std::vector<float> a(alpha.roi().npixels());
    ROI one    = alpha.roi();
    one.chbegin = 0;
    one.chend   = 1;
    alpha.get_pixels(one, TypeFloat, a.data());
    for (float v : a)
        if (v != 0.0f && v != 1.0f)
            return true;  // NaN included
    return false;
}

}  // namespace


int
denoised_alpha_channel(const Job& j, const Selection& radiance)
{
    return !j.no_alpha && radiance.indices.size() == 4 ? radiance.indices[3]
                                                       : -1;
}


ImageBuf
strip_alpha(const Job& j, const ImageBuf& radiance)
{
    ImageBuf held;
    if (!ImageBufAlgo::channels(held, radiance, 1, { 3 }))
        fail(format("the alpha of '{}': {}", j.in.path,
                    one_line(held.geterror())));
    return held;
}


void
denoise_strip_alpha(const Job& j, const Strip& strip, const ROI& frame,
                    const ImageBuf& held, const Guides& guides, ImageBuf& alpha)
{
    if (!fractional(held)) {
        // Solid wherever the filter would look: denoise_alpha() keeps it.
        alpha = ImageBuf();
        if (!ImageBufAlgo::copy(alpha, held, TypeFloat, strip.core, j.threads))
            fail(format("the alpha of '{}': {}", j.in.path,
                        one_line(alpha.geterror())));
        return;
    }
    FilterOptions options = j.filter;
    options.frame         = frame;
    if (!denoise_alpha(alpha, held, guides, options, strip.core, j.threads))
        fail(format("denoising the alpha of '{}' failed: {}", j.in.path,
                    one_line(alpha.geterror())));
}

}  // namespace job
}  // namespace zdenoise
