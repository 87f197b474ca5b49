// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Temporal denoising (docs/TEMPORAL.md): the neighbouring frames of an
// animation as extra evidence for frame t. Their demodulated light is
// reprojected into frame t through motion vectors and averaged with frame
// t's wherever the guides say that the same surface is seen, before the
// filter runs; disoccluded and moving parts keep frame t's light alone.
// Conventions as in zdenoise.h (ImageBufAlgo style, bit-identical for
// every thread count, any ROI computed exactly).

#pragma once

#include <vector>

#include <zdenoise/zdenoise.h>

namespace zdenoise {

/// When a neighbour's pixel counts as the same surface as frame t's.
struct TemporalOptions {
    /// Depths (Guides::depth) may differ by this fraction of frame t's.
    float depth_tolerance = 0.05f;
    /// Normals (Guides::normal) must have at least this cosine.
    float normal_cut = 0.9f;
    /// A neighbour's pixel counts only where the light agrees around it:
    /// over a box around it, the mean difference of the matched pixels'
    /// light luminance lies within `rejection_sigmas` standard errors of 0
    /// (a paired test; docs/TEMPORAL.md). It rejects what the guides cannot
    /// see: moving shadows and highlights, changing lights. The test runs
    /// on `test_scales` boxes, of radius test_radius, twice that, and so
    /// on, and every one must agree: the small box sees a change confined
    /// to a few pixels, the large ones have the pairs to see a small,
    /// broad change (a soft shadow that moves) that the noise of 25 pairs
    /// hides.
    int test_radius        = 2;
    int test_scales        = 3;
    float rejection_sigmas = 3.0f;
    /// The largest box's radius: how far around a pixel the test reads.
    int test_reach() const
    {
        return test_scales > 0 ? test_radius << (test_scales - 1) : 0;
    }
    /// As FilterOptions::albedo_eps: light = radiance / (albedo + eps)
    /// where the albedo is demodulated (docs/FILTER.md section 1).
    float albedo_eps = 1e-3f;
};

/// One frame of the sequence as temporal_combine() reads it. Every image
/// is of that frame; they share its data window.
struct TemporalFrame {
    const ImageBuf* radiance = nullptr;  ///< R, G, B (then alpha, if any)
    const ImageBuf* albedo   = nullptr;  ///< R, G, B
    /// normal, depth and object_id are compared with frame t's (each only
    /// when both frames have it); variance, half_a and half_b are combined
    /// as the radiance is, when frame t has them.
    Guides guides;
    /// For a neighbour: where each pixel of frame t shows in this frame,
    /// as an offset in pixels (2 channels: x to the right, y down the
    /// rows), over frame t's data window; non-finite where it shows
    /// nowhere. Null: the same place (a static camera and scene). Ignored
    /// for frame t itself.
    const ImageBuf* flow = nullptr;
    /// For a neighbour whose flow chains another's (t+2 through t+1: the
    /// index of t+1 in the neighbours), or -1: a pixel counts here only
    /// where it shows the same surface there too, so that a chain through
    /// an occluder (a background pixel hidden in t+1 takes the occluder's
    /// motion there) does not land on another place of a surface.
    int via = -1;
};

/// What temporal_combine() makes of frame t.
struct TemporalCombined {
    ImageBuf radiance;  ///< frame t's channels, R, G, B combined
    /// R, G, B: the albedo averaged over the same frames (what the
    /// combined radiance is to be demodulated and remodulated by: a
    /// render's albedo AOV has noise of its own, which would flicker).
    ImageBuf albedo;
    ImageBuf variance;  ///< combined, when frame t has a variance guide
    ImageBuf half_a, half_b;  ///< combined, when frame t has halves
    ImageBuf frames;    ///< 1 channel: the frames averaged at each pixel
    /// Per neighbour, the share of roi's pixels where it shows the same
    /// surface (the guides), and where it also shows the same light and
    /// counted. Near 0 on a moving shot: the flow is not where the pixels
    /// go (motion vectors of another convention).
    std::vector<double> same_surface, counted;
};

/// Average frame t's light with its neighbours': at each pixel p of roi,
/// for each neighbour whose pixel q = p + flow(p) (nearest pixel, so that
/// pixel noise stays independent) lies in its data window and shows the
/// same surface (both surface or both not; depth within depth_tolerance;
/// normals' cosine >= normal_cut; the same object id, or the same primary
/// Cryptomatte id) and the same light (the paired test at every scale),
/// the light z = L / (A + eps) of each demodulated channel is averaged,
/// as is the albedo A, and the light is remodulated by that albedo. Channels
/// that are not demodulated in both frames keep frame t's radiance.
/// Variance guides combine as the variance of that mean; halves combine
/// as the radiance. dst.radiance carries frame t's other channels. Errors
/// (a neighbour's image missing, of another size or without 2 flow
/// channels) in dst.radiance.geterror().
ZDENOISE_API bool temporal_combine(TemporalCombined& dst,
                                   const TemporalFrame& frame,
                                   const std::vector<TemporalFrame>& neighbours,
                                   const TemporalOptions& options = {},
                                   ROI roi = {}, int nthreads = 0);

/// Chain two flows: where frame t's pixels show in frame t+2, from where
/// they show in frame t+1 (`to_next`, over frame t) and where frame t+1's
/// pixels show in t+2 (`next_to_after`, over frame t+1): dst(p) = a(p) +
/// b(p + a(p)) at the nearest pixel; non-finite where p + a(p) leaves the
/// frame or either is non-finite.
ZDENOISE_API bool chain_flow(ImageBuf& dst, const ImageBuf& to_next,
                             const ImageBuf& next_to_after, ROI roi = {},
                             int nthreads = 0);

}  // namespace zdenoise
