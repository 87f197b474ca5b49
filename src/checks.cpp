// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Argument checking shared by the operations.

#include "checks.h"
#include "internal.h"

#include <zdenoise/zdenoise.h>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imagebufalgo_util.h>

namespace zdenoise {
namespace detail {

bool
check_input(ImageBuf& dst, const ImageBuf& img, const char* opname,
            const char* what, const ROI& roi, int minchannels)
{
    if (!img.initialized()) {
        dst.errorfmt("{}: {} image is not initialized", opname, what);
        return false;
    }
    if (img.has_error()) {
        dst.errorfmt("{}: {} image: {}", opname, what, img.geterror(false));
        return false;
    }
    const OIIO::ImageSpec& spec = img.spec();
    if (spec.deep) {
        dst.errorfmt("{}: {} image is deep; deep images are not supported",
                     opname, what);
        return false;
    }
    if (spec.depth > 1) {
        dst.errorfmt("{}: {} image is a volume; only 2D images are supported",
                     opname, what);
        return false;
    }
    if (spec.nchannels < minchannels) {
        dst.errorfmt("{}: {} image has {} channel(s), needs at least {}",
                     opname, what, spec.nchannels, minchannels);
        return false;
    }
    ROI need(roi.xbegin, roi.xend, roi.ybegin, roi.yend);
    ROI have = img.roi();
    have.chbegin = need.chbegin;
    have.chend   = need.chend;
    if (OIIO::roi_intersection(need, have) != need) {
        dst.errorfmt("{}: {} image's data window {}x{}{:+d}{:+d} does not "
                     "cover the pixels {}x{}{:+d}{:+d} being computed",
                     opname, what, have.width(), have.height(), have.xbegin,
                     have.ybegin, need.width(), need.height(), need.xbegin,
                     need.ybegin);
        return false;
    }
    return true;
}


bool
check_guides(ImageBuf& dst, const Guides& guides, const char* opname,
             const ROI& roi)
{
    struct NamedGuide {
        const ImageBuf* buf;
        const char* name;
        int minchannels;
    } named[] = { { guides.normal, "normal guide", 3 },
                  { guides.depth, "depth guide", 1 },
                  { guides.object_id, "object id guide", 1 },
                  { guides.variance, "variance guide", 1 },
                  { guides.half_a, "half buffer A", 3 },
                  { guides.half_b, "half buffer B", 3 } };
    for (const NamedGuide& g : named)
        if (g.buf && !check_input(dst, *g.buf, opname, g.name, roi, g.minchannels))
            return false;
    return true;
}


bool
check_frame(ImageBuf& dst, const char* opname, const ROI& roi,
            const ROI& frame)
{
    if (roi.xbegin >= frame.xbegin && roi.xend <= frame.xend
        && roi.ybegin >= frame.ybegin && roi.yend <= frame.yend)
        return true;
    dst.errorfmt("{}: the pixels being computed {}x{}{:+d}{:+d} are not all "
                 "in the frame {}x{}{:+d}{:+d}",
                 opname, roi.width(), roi.height(), roi.xbegin, roi.ybegin,
                 frame.width(), frame.height(), frame.xbegin, frame.ybegin);
    return false;
}


bool
prepare_dst(ImageBuf& dst, const ImageBuf& src, ROI& roi, const char* opname)
{
    if (!src.initialized()) {
        dst.errorfmt("{}: input image is not initialized", opname);
        return false;
    }
    if (!OIIO::ImageBufAlgo::IBAprep(roi, &dst, &src,
                                     OIIO::ImageBufAlgo::IBAprep_DST_FLOAT_PIXELS
                                         | OIIO::ImageBufAlgo::IBAprep_NO_SUPPORT_VOLUME))
        return false;
    if (dst.nchannels() != src.nchannels()) {
        dst.errorfmt("{}: destination has {} channels, input has {}", opname,
                     dst.nchannels(), src.nchannels());
        return false;
    }
    return true;
}


OIIO::ImageSpec
result_spec(const ROI& roi, const ROI& frame, int nch)
{
    ROI data    = roi;
    data.chbegin = 0;
    data.chend   = nch;
    OIIO::ImageSpec spec(data, OIIO::TypeFloat);
    spec.full_x      = frame.xbegin;
    spec.full_y      = frame.ybegin;
    spec.full_width  = frame.width();
    spec.full_height = frame.height();
    return spec;
}


bool
prepare_result(ImageBuf& err, ImageBuf& img, const ROI& roi, const ROI& frame,
               int nch, const char* opname, const char* what,
               const std::vector<std::string>* names)
{
    if (!img.initialized()) {
        OIIO::ImageSpec spec = result_spec(roi, frame, nch);
        if (names)
            spec.channelnames = *names;
        img.reset(spec);
        return true;
    }
    if (img.nchannels() < nch || !img.roi().contains(roi.xbegin, roi.ybegin)
        || !img.roi().contains(roi.xend - 1, roi.yend - 1)) {
        err.errorfmt("{}: {} needs {} channel{} over the output's pixels",
                     opname, what, nch, nch == 1 ? "" : "s");
        return false;
    }
    return true;
}


bool
prepare_diagnostics(ImageBuf& dst, ImageBuf& maps, const ROI& roi,
                    const ROI& frame, const char* opname)
{
    const std::vector<std::string>& names = diagnostic_channels();
    return prepare_result(dst, maps, roi, frame, int(names.size()), opname,
                          "the diagnostics image", &names);
}

bool
cancelled(ImageBuf& dst, bool dst_was_given, ROI roi, int nthreads)
{
    dst.geterror();  // clears it
    if (!dst_was_given) {
        dst.reset();
    } else if (dst.initialized()) {
        roi = roi.defined() ? OIIO::roi_intersection(roi, dst.roi())
                            : dst.roi();
        roi.chbegin = 0;
        roi.chend   = dst.nchannels();
        OIIO::ImageBufAlgo::zero(dst, roi, nthreads);
    }
    dst.errorfmt("zdenoise: cancelled");
    return false;
}

}  // namespace detail


const std::vector<std::string>&
diagnostic_channels()
{
    static const std::vector<std::string> names = { "radius", "stop", "noise",
                                                    "error" };
    return names;
}

}  // namespace zdenoise
