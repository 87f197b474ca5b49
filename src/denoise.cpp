// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// denoise(): demodulate, regression_filter, remodulate, bound_highlights.

#include <zdenoise/highlights.h>
#include <zdenoise/zdenoise.h>

#include "checks.h"
#include "denoise.h"
#include "internal.h"

namespace zdenoise {

bool
detail::denoise_through(ImageBuf& dst, const ImageBuf& radiance,
                        const ImageBuf& albedo, const ImageBuf* remodulation,
                        const FilterOptions& options, ROI roi, int nthreads,
                        int extra_halo, const QuotientFilter& filter)
{
    const char* opname = "denoise";
    const bool dst_was_given = dst.initialized();
    if (detail::cancel_requested(options))
        return detail::cancelled(dst, dst_was_given, roi, nthreads);
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
    ROI region    = detail::halo_region(roi, opt.frame,
                                        filter_halo(opt) + extra_halo);
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
    if (!filter(filtered, quotient, opt)) {
        if (detail::cancel_requested(options))
            return detail::cancelled(dst, dst_was_given, roi, nthreads);
        dst.errorfmt("{}", filtered.geterror());
        return false;
    }
    if (remodulation
        && !detail::check_input(dst, *remodulation, opname,
                                "remodulation albedo", roi, 3))
        return false;
    const bool remodulated
        = remodulation ? remodulate(dst, filtered, albedo, *remodulation,
                                    options.albedo_eps, roi, nthreads)
                       : remodulate(dst, filtered, albedo, options.albedo_eps,
                                    roi, nthreads);
    // A noisy albedo can remodulate the light around a pixel into a
    // highlight the input does not have (docs/FILTER.md section 1a).
    return remodulated
           && bound_highlights(dst, radiance, opt.frame, roi, nthreads);
}

namespace {

/// Both forms of denoise(): remodulated by `remodulation` when given, else
/// by `albedo`.
bool
denoise_(ImageBuf& dst, const ImageBuf& radiance, const ImageBuf& albedo,
         const ImageBuf* remodulation, const Guides& guides,
         const FilterOptions& options, FilterStats* stats, ROI roi,
         int nthreads)
{
    return detail::denoise_through(
        dst, radiance, albedo, remodulation, options, roi, nthreads, 0,
        [&](ImageBuf& filtered, const ImageBuf& quotient,
            const FilterOptions& opt) {
            return regression_filter(filtered, quotient, albedo, guides, opt,
                                     stats, roi, nthreads);
        });
}

}  // namespace


bool
denoise(ImageBuf& dst, const ImageBuf& radiance, const ImageBuf& albedo,
        const Guides& guides, const FilterOptions& options, FilterStats* stats,
        ROI roi, int nthreads)
{
    return denoise_(dst, radiance, albedo, nullptr, guides, options, stats,
                    roi, nthreads);
}


bool
denoise(ImageBuf& dst, const ImageBuf& radiance, const ImageBuf& albedo,
        const ImageBuf* remodulation_albedo, const Guides& guides,
        const FilterOptions& options, FilterStats* stats, ROI roi,
        int nthreads)
{
    return denoise_(dst, radiance, albedo, remodulation_albedo, guides,
                    options, stats, roi, nthreads);
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


ImageBuf
denoise(const ImageBuf& radiance, const ImageBuf& albedo,
        const ImageBuf* remodulation_albedo, const Guides& guides,
        const FilterOptions& options, FilterStats* stats, ROI roi,
        int nthreads)
{
    return detail::returned_image("denoise", [&](ImageBuf& result) {
        return denoise(result, radiance, albedo, remodulation_albedo, guides,
                       options, stats, roi, nthreads);
    });
}

}  // namespace zdenoise
