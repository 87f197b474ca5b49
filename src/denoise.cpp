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
        || !detail::check_input(dst, radiance, opname, "radiance", roi, 3))
        return false;
    // The filter reads the quotient over roi and its halo, clipped to the
    // frame, whose edges its windows stop at: demodulate just that, and tell
    // the filter the frame (by default the radiance's data window), which
    // the quotient no longer shows.
    FilterOptions opt = options;
    if (!opt.frame.defined())
        opt.frame = radiance.roi();
    if (!detail::check_frame(dst, opname, roi, opt.frame))
        return false;
    ROI region    = detail::halo_region(roi, opt.frame, filter_halo(opt));
    region.chbegin = 0;
    region.chend   = radiance.nchannels();
    if (!detail::check_input(dst, radiance, opname, "radiance", region, 3)
        || !detail::check_input(dst, albedo, opname, "albedo", region, 3))
        return false;
    ImageBuf quotient, filtered;
    if (!demodulate(quotient, radiance, albedo, options.albedo_eps, region,
                    nthreads)) {
        dst.errorfmt("{}", quotient.geterror());
        return false;
    }
    if (!regression_filter(filtered, quotient, albedo, guides, opt, stats,
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
    return detail::returned_image("denoise", [&](ImageBuf& result) {
        return denoise(result, radiance, albedo, guides, options, stats, roi, nthreads);
    });
}

}  // namespace zdenoise
