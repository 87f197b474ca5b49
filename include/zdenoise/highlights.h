// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// No highlight the render does not have (docs/FILTER.md section 1a): after
// remodulation, each output channel is at most the brightest input value of
// that channel around the pixel. Conventions as in zdenoise.h (ImageBufAlgo
// style, bit-identical for every thread count, any ROI computed exactly).

#pragma once

#include <zdenoise/zdenoise.h>

namespace zdenoise {

/// Half the side of the square bound_highlights() looks over: 4, a 9x9.
/// Measured on 72 cases (bench/path_mode.md, "No highlight the input does
/// not have"): a 5x5 bound bites where 4-spp light is sparse (up to 4 %
/// worse), a 9x9 at most 0.07 %; wider ones catch fewer of the spikes.
constexpr int kHighlightRadius = 4;

/// Lower, in place, channels 0-2 of `dst` over roi wherever they are above
/// the largest finite value of the same channel of `radiance` within
/// kHighlightRadius pixels (a Chebyshev square, clipped to `frame`).
///
/// A denoised value is a weighted mean of the light around it times the
/// pixel's albedo; where the albedo is itself a noisy estimate (Cycles'
/// Denoising Albedo at a rough metal passes through to what it reflects
/// and adds the emission it meets), one pixel's albedo can multiply its
/// neighbours' light into a highlight several times brighter than any
/// input pixel near it. Values at or below the bound, NaN and infinite
/// values of dst, and pixels with no finite radiance around them are left
/// as they are; other channels are not touched.
///
/// @param dst       The denoised image (float, at least 3 channels),
///                  holding roi; changed in place.
/// @param radiance  The noisy radiance dst was denoised from (at least 3
///                  channels), read over roi widened by kHighlightRadius
///                  and clipped to `frame`.
/// @param frame     The frame the square is clipped to (default: the
///                  radiance's data window).
/// @param roi       The pixels to bound (default: dst's data window).
/// @param nthreads  Threads (0: OIIO's default). The result does not
///                  depend on it.
/// @return false with an error on dst when an image does not hold what it
///                  must.
ZDENOISE_API bool bound_highlights(ImageBuf& dst, const ImageBuf& radiance,
                                   ROI frame = {}, ROI roi = {},
                                   int nthreads = 0);

}  // namespace zdenoise
