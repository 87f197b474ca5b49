// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// denoise(): demodulate, regression_filter, remodulate.

#include <zdenoise/zdenoise.h>

#include "internal.h"

namespace zdenoise {

bool
denoise(ImageBuf& dst, const ImageBuf& radiance, const ImageBuf& albedo,
        const Guides& guides, const FilterOptions& options, FilterStats* stats,
        ROI roi, int nthreads)
{
    const char* opname = "denoise";
    if (!detail::prepare_dst(dst, radiance, roi, opname)
        || !detail::check_input(dst, radiance, opname, "radiance", roi, 3)
        || !detail::check_input(dst, albedo, opname, "albedo", radiance.roi(),
                                3))
        return false;
    // The whole data window is demodulated: the filter clips its windows at
    // the image's edges, so it must see the real ones.
    ImageBuf quotient, filtered;
    if (!demodulate(quotient, radiance, albedo, options.albedo_eps,
                    radiance.roi(), nthreads)) {
        dst.errorfmt("{}", quotient.geterror());
        return false;
    }
    if (!regression_filter(filtered, quotient, albedo, guides, options, stats,
                           roi, nthreads)) {
        dst.errorfmt("{}", filtered.geterror());
        return false;
    }
    if (!remodulate(dst, filtered, albedo, options.albedo_eps, roi,
                    nthreads))
        return false;
    return true;
}


ImageBuf
denoise(const ImageBuf& radiance, const ImageBuf& albedo, const Guides& guides,
        const FilterOptions& options, FilterStats* stats, ROI roi,
        int nthreads)
{
    ImageBuf result;
    if (!denoise(result, radiance, albedo, guides, options, stats, roi,
                 nthreads)
        && !result.has_error())
        result.errorfmt("denoise error");
    return result;
}

}  // namespace zdenoise
