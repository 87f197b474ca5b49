// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// read_channels(): an image's channels over a region as floats, as every
// stage of the filter reads its inputs.

#include "filter_inputs.h"

#include <cmath>


namespace zdenoise {
namespace detail {

using namespace OIIO;

std::vector<float>
read_channels(const ImageBuf& img, ROI region, int chbegin, int chend)
{
    region.chbegin = chbegin;
    region.chend   = chend;
    std::vector<float> px(region.npixels() * size_t(chend - chbegin));
    img.get_pixels(region, TypeFloat, px.data());
    return px;
}


}  // namespace detail
}  // namespace zdenoise
