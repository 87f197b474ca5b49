// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Denoising the alpha (coverage) of a render (docs/ALPHA.md): motion blur,
// depth of field, hair and volumes over transparent film give fractional
// alpha that is a Monte Carlo estimate like the colour, and a compositor
// puts the colour over its plate with it. Conventions as in zdenoise.h
// (ImageBufAlgo style, bit-identical for every thread count, any ROI
// computed exactly).

#pragma once

#include <zdenoise/zdenoise.h>

namespace zdenoise {

/// The rows and columns around an output pixel that denoise_alpha() reads:
/// filter_halo(options) + 1 (keep_structure() reads the filtered coverage
/// one pixel beyond the output).
ZDENOISE_API int alpha_halo(const FilterOptions& options = {});

/// Denoise the coverage in channel 0 of `alpha` with the render's guides.
///
/// The coverage is filtered as light of albedo 1 by denoise() (its
/// options, with the normal and object id guides only: `variance` and the
/// halves describe the colour, and the depth of a partly covered pixel
/// mixes the object's with the background's by the pixel's own samples;
/// without progress, diagnostics or hat diagonal), given back where the
/// filter removed more than its noise (keep_structure(): an anti-aliased
/// edge the filter blurred), and clamped to [0, 1]. A pixel whose coverage is exactly 0
/// or 1, and each of its 8 neighbours' too (an object's inside, empty
/// film, a silhouette without anti-aliasing), keeps its value bit for bit:
/// nothing there is noise. A coverage of 0 or 1 beside fractional ones is
/// a sample of a blurred or anti-aliased edge and is filtered.
///
/// @param dst      Receives one float channel over roi (allocated when
///                 uninitialised, else it must hold roi and a channel).
/// @param alpha    The coverage; channel 0 is read, over roi widened by
///                 alpha_halo(options) and clipped to the frame.
///                 Non-finite values are filtered from their neighbours
///                 (0 where none is finite).
/// @param guides   The render's normal, depth and object id guides (as
///                 for denoise(); the noise guides are ignored).
/// @param options  The filter's options (FilterOptions::frame as there).
/// @param roi      The output pixels; default: alpha's data window.
/// @param nthreads Threads; 0 = all.
/// @return false with an error on dst for an unusable input.
ZDENOISE_API bool denoise_alpha(ImageBuf& dst, const ImageBuf& alpha,
                                const Guides& guides = {},
                                const FilterOptions& options = {},
                                ROI roi = {}, int nthreads = 0);
ZDENOISE_API ImageBuf denoise_alpha(const ImageBuf& alpha,
                                    const Guides& guides = {},
                                    const FilterOptions& options = {},
                                    ROI roi = {}, int nthreads = 0);

}  // namespace zdenoise
