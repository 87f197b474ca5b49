// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Helpers shared by the operations of libzdenoise (not installed).

#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/parallel.h>

#include <zdenoise/zdenoise.h>

namespace zdenoise {
namespace detail {

using OIIO::ImageBuf;
using OIIO::ROI;

/// regression_filter() works tile by tile, each at most this many pixels a
/// side, so that its working memory follows the tile, not the image (the
/// result is the whole image's: docs/FILTER.md section 8). Today's filter
/// alone keeps about 100 bytes a pixel of a tile and its halo; the
/// selection (select 1) about 250 over a halo twice as wide, so its tiles
/// are larger (fewer pixels filtered twice) but as wide as a 2K frame.
constexpr int kFilterTile    = 1024;
constexpr int kSelectionTile = 2048;
/// The box core's tiles (box_core.cpp): its radii up to 4 hold 50 planes
/// of doubles over the tile and its pool and windows around it.
constexpr int kBoxTile = 384;

/// Parallel options that split a range of any length over the threads
/// (nthreads 0: all). OIIO's default paropt runs a range of fewer than
/// 16384 items on the calling thread alone, which left every loop over the
/// rows of a strip (or over a few thousand outliers) serial. Each item of
/// such a loop writes its own outputs, so the result does not depend on the
/// split.
inline OIIO::paropt
paropt_any_length(int nthreads)
{
    return OIIO::paropt(nthreads, OIIO::paropt::SplitDir::Y, 1);
}

/// Run `body(begin, end)` over disjoint ranges covering [0, n), in
/// parallel: for per-pixel loops whose every index writes only its own
/// outputs (the result does not depend on the split).
template<class F>
void
for_ranges(size_t n, int nthreads, F&& body)
{
    OIIO::parallel_for_range(int64_t(0), int64_t(n),
                             [&](int64_t b, int64_t e) {
                                 body(size_t(b), size_t(e));
                             },
                             paropt_any_length(nthreads));
}

/// Has the caller asked the running operation to stop
/// (FilterOptions::cancel)? A relaxed load: the flag orders no data, it
/// only ends loops early, and costs nothing beside a block or a row.
inline bool
cancel_requested(const std::atomic<bool>* cancel)
{
    return cancel && cancel->load(std::memory_order_relaxed);
}

inline bool
cancel_requested(const FilterOptions& options)
{
    return cancel_requested(options.cancel);
}

/// Rec.709 luminance weights: the scalar view of an RGB quotient.
constexpr float kLumaWeights[3] = { 0.2126f, 0.7152f, 0.0722f };

/// The luminance of an RGB triple, in float (the same rounding everywhere).
inline float
luminance(const float* rgb)
{
    return kLumaWeights[0] * rgb[0] + kLumaWeights[1] * rgb[1]
           + kLumaWeights[2] * rgb[2];
}

/// Is an albedo channel value demodulated (docs/FILTER.md section 1)?
/// The single definition used by demodulate, the filter and remodulate, so
/// that the three agree pixel for pixel. An albedo above 1/albedo_eps is
/// no reflectance but a broken pass: remodulating by it would turn the
/// neighbours' filtered value into a firefly of that size.
inline bool
albedo_demodulated(float albedo, float albedo_eps)
{
    return std::isfinite(albedo) && albedo >= albedo_eps
           && albedo * albedo_eps <= 1.0f;
}

/// The variance of one sample of an albedo that a pixel's footprint mixes
/// from lo and hi (the least and the most of its 3x3) in the proportion
/// its mean `a` says: (hi - lo)^2 t (1 - t), t = (a - lo) / (hi - lo)
/// (docs/FILTER.md section 12). Divided by the samples' count (N, or
/// N^(3/2) for stratified samples) it is the pixel mean's.
inline float
albedo_mixture_variance(float a, float lo, float hi)
{
    const float range = hi - lo;
    const float t     = range > 1e-6f ? (a - lo) / range : 0.0f;
    return range * range * t * (1.0f - t);
}

/// Largest quotient magnitude taking part in fits (docs/FILTER.md section
/// 2): the filter squares values in float, and a larger one (overflowed
/// shading, not light) would swamp every window around it.
constexpr float kLargestFitQuotient = 1e18f;

/// A filtered value (a double sum) as a float saturated at the largest
/// float (docs/FILTER.md section 7): splats bounded at the largest float
/// can still average, with an outlier's spread light added, a hair past
/// it, which would round to Inf.
inline float
saturated_float(double v)
{
    constexpr double largest = std::numeric_limits<float>::max();
    return float(std::min(std::max(v, -largest), largest));
}

/// The pixels of `frame` the output pixels `roi` depend on: roi widened by
/// `halo` (filter_halo()), clipped to the frame; x and y only.
inline ROI
halo_region(const ROI& roi, const ROI& frame, int halo)
{
    return OIIO::roi_intersection(ROI(roi.xbegin - halo, roi.xend + halo,
                                      roi.ybegin - halo, roi.yend + halo),
                                  ROI(frame.xbegin, frame.xend,
                                      frame.ybegin, frame.yend));
}

/// The ImageBuf-returning form of an operation (as OIIO's): `op(result)`
/// runs the bool form into a fresh result; a failure that left no message
/// gets "<opname> error".
template<class Op>
ImageBuf
returned_image(const char* opname, Op&& op)
{
    ImageBuf result;
    if (!op(result) && !result.has_error())
        result.errorfmt("{} error", opname);
    return result;
}

}  // namespace detail
}  // namespace zdenoise
