// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Light groups (docs/LIGHT_GROUPS.md): the beauty split by the lights
// that lit it (Cycles' Combined_<group>, Arnold's RGBA_<group>), each
// group denoised so that the groups add up to the denoised beauty.
// Conventions as in zdenoise.h (ImageBufAlgo style, bit-identical for
// every thread count, any ROI computed exactly).

#pragma once

#include <vector>

#include <zdenoise/zdenoise.h>

namespace zdenoise {

/// How split_light_groups() estimates each group's share of the light.
struct LightGroupOptions {
    /// Half-size of the window over which a pixel's shares are estimated.
    int radius = 6;
    /// Neighbours whose denoised light differs from the pixel's by much
    /// more than this (a symmetric relative difference per channel,
    /// (a - b) / (|a| + |b|), in a Gaussian of this deviation) are lit
    /// otherwise and count little: a shadow edge of one light keeps that
    /// light's share apart on its two sides.
    float tolerance = 0.1f;
};

/// The rows and columns around an output pixel that split_light_groups()
/// reads.
ZDENOISE_API int light_groups_halo(const LightGroupOptions& options = {});

/// Split the denoised beauty among light groups by their shares of the
/// light around each pixel.
///
/// The noisy groups G_k, the rest (the beauty minus their sum, where
/// positive) and the excess (their sum minus the beauty, where positive:
/// light the groups hold and the beauty does not, as a world group's where
/// the film is transparent) are averaged over a window around each pixel,
/// each neighbour weighted by the filter's guide weight g(q; p)
/// (docs/FILTER.md section 4: normal, depth, object id, with `filter`'s
/// normal_cut, normal_power and depth_tolerance; a pixel that is no
/// surface takes itself alone), a spatial term exp(-d^2 / radius^2) and
/// the likeness of its denoised light to the pixel's (`tolerance`). The
/// light to split is the denoised beauty plus the pixel's own excess. Per
/// channel, the window means of the groups and the rest are made to add
/// up to it by the minimum-variance adjustment of independent estimates to
/// a known sum: each takes a part of the difference in proportion to its
/// variance over the window (a clean group keeps its mean, the noisy ones
/// take the correction); a part that would go below 0 is 0 and the others
/// share what is left. So where the groups hold all the beauty's light and
/// no more, they add up to the denoised beauty exactly (to rounding); no
/// group is negative; the weights are computed once for all groups.
/// Negative group values count as 0.
///
/// @param dst       Receives one image per group (3 float channels over
///                  roi): resized to groups.size() (at least 1); each
///                  allocated when uninitialised, else it must hold roi
///                  and 3 channels.
/// @param denoised  The denoised beauty (RGB), over roi widened by
///                  light_groups_halo() and clipped to the frame.
/// @param beauty    The noisy beauty (RGB), over the same pixels.
/// @param groups    The noisy light groups (RGB each), over the same
///                  pixels. At least one.
/// @param guides    The normal, depth and object id guides, over the same
///                  pixels (the noise guides are not used).
/// @param filter    The filter's options: its guide-weight parameters,
///                  `frame` and `cancel`, as for denoise() (a cancelled
///                  call leaves dst as a cancelled denoise() leaves its).
/// @param options   The share window.
/// @param roi       The output pixels; default: the denoised beauty's data
///                  window.
/// @param nthreads  Threads; 0 = all.
/// @return false with an error on dst[0] for an unusable input.
ZDENOISE_API bool split_light_groups(std::vector<ImageBuf>& dst,
                                     const ImageBuf& denoised,
                                     const ImageBuf& beauty,
                                     const std::vector<const ImageBuf*>& groups,
                                     const Guides& guides = {},
                                     const FilterOptions& filter = {},
                                     const LightGroupOptions& options = {},
                                     ROI roi = {}, int nthreads = 0);

}  // namespace zdenoise
