// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The operations' argument checks and result preparation (checks.cpp):
// thin checks up front, as OIIO's ImageBufAlgo makes them.

#pragma once

#include <string>
#include <vector>

#include <zdenoise/zdenoise.h>

namespace zdenoise {
namespace detail {

/// Check that `img` is a usable input of operation `opname`: initialized,
/// not deep, 2D, at least `minchannels` channels, and its data window holds
/// `roi` (all but the channel range). On failure the message names the
/// operation and the input (`what`) and goes to dst.
bool
check_input(ImageBuf& dst, const ImageBuf& img, const char* opname,
            const char* what, const ROI& roi, int minchannels);

/// check_input() for every guide given (normal and halves 3 channels, the
/// others 1), named as in the messages of regression_filter().
bool
check_guides(ImageBuf& dst, const Guides& guides, const char* opname,
             const ROI& roi);

/// Check that the output pixels `roi` lie in `frame` (FilterOptions::frame).
bool
check_frame(ImageBuf& dst, const char* opname, const ROI& roi,
            const ROI& frame);

/// Make dst ready as the float result of an op whose first input is `src`
/// and set roi (default: src's data window) to the pixels to compute.
bool
prepare_dst(ImageBuf& dst, const ImageBuf& src, ROI& roi, const char* opname);

/// The spec of a float result over roi (its data window) in the image
/// `frame` (its display window), with nch channels of default names.
OIIO::ImageSpec
result_spec(const ROI& roi, const ROI& frame, int nch);

/// Make `img` ready as a float result of `nch` channels over roi: allocated
/// (result_spec(), with `names` when given) when uninitialised, else
/// checked to hold roi and the channels (the error, naming the image as
/// `what`, goes to err).
bool
prepare_result(ImageBuf& err, ImageBuf& img, const ROI& roi, const ROI& frame,
               int nch, const char* opname, const char* what,
               const std::vector<std::string>* names = nullptr);

/// Make `maps` ready for FilterOptions::diagnostics over roi: allocated
/// (float, diagnostic_channels(), data window roi, display window frame)
/// when uninitialised, else checked to hold roi and the channels (the
/// error goes to dst).
bool
prepare_diagnostics(ImageBuf& dst, ImageBuf& maps, const ROI& roi,
                    const ROI& frame, const char* opname);

/// End an operation that saw its cancel flag set (FilterOptions::cancel):
/// what a stage left in dst's error is dropped for "zdenoise: cancelled",
/// and dst holds no result: reset when the call allocated it
/// (`dst_was_given` false), else the pixels of roi (undefined: all), every
/// channel, set to 0. Returns false.
bool
cancelled(ImageBuf& dst, bool dst_was_given, ROI roi, int nthreads);

}  // namespace detail
}  // namespace zdenoise
