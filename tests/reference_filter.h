// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// A plain, slow, obviously-correct reference implementation of the zdenoise
// regression filter, written from docs/FILTER.md (sections 1-7) and
// independently of the library. It exists only for the tests: it recomputes
// everything from scratch for every centre and every radius, in double
// precision, in one thread, centres in raster order. Read it as the
// specification in code.

#pragma once

#include <cstdint>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/zdenoise.h>

namespace zdenoise_ref {

/// A plain float image: w x h pixels of nch channels, interleaved, rows top
/// to bottom. (x0, y0) is the origin of the data window it came from (only
/// kept for the round trip to ImageBuf; all indexing here is 0-based).
/// `alpha` is the alpha channel index named by the spec, or -1.
struct RefImage {
    int w = 0, h = 0, nch = 0;
    int x0 = 0, y0 = 0;
    int alpha = -1;
    std::vector<float> px;

    RefImage() = default;
    RefImage(int w_, int h_, int nch_, float fill = 0.0f)
        : w(w_), h(h_), nch(nch_), px(size_t(w_) * h_ * nch_, fill)
    {
    }
    bool empty() const { return px.empty(); }
    bool inside(int x, int y) const { return x >= 0 && x < w && y >= 0 && y < h; }
    float at(int x, int y, int c) const { return px[(size_t(y) * w + x) * nch + c]; }
    float& at(int x, int y, int c) { return px[(size_t(y) * w + x) * nch + c]; }
};

/// ImageBuf (any pixel type) -> RefImage over its data window, as float.
RefImage from_imagebuf(const OIIO::ImageBuf& buf);
/// RefImage -> float ImageBuf with the same data window origin and alpha.
OIIO::ImageBuf to_imagebuf(const RefImage& img);

/// Optional guides, as in zdenoise::Guides (null = not given).
struct RefGuides {
    const RefImage* normal = nullptr;
    const RefImage* depth = nullptr;
    const RefImage* object_id = nullptr;
    const RefImage* variance = nullptr;
    const RefImage* half_a = nullptr;
    const RefImage* half_b = nullptr;
};

/// What the reference did (same meaning as zdenoise::FilterStats).
struct RefStats {
    int64_t pixels = 0;
    int64_t windows = 0;        ///< fit-point centres processed
    int64_t stop_quality = 0;
    int64_t stop_size = 0;
    int64_t stop_edge = 0;
    double mean_radius = 0.0;   ///< mean final radius over the windows
    int64_t passthrough_pixels = 0;  ///< >= 1 RGB channel not filtered
    int64_t nonfinite_pixels = 0;    ///< non-finite RGB value in the input
    int64_t absent_windows = 0;      ///< centres whose whole fit was absent
};

/// Section 1. Other channels are copied.
RefImage demodulate(const RefImage& L, const RefImage& La, float albedo_eps);
RefImage remodulate(const RefImage& z, const RefImage& La, float albedo_eps);

/// Section 1a: each of channels 0-2 of `out` lowered, where above, to the
/// largest finite value of that channel of L within
/// zdenoise::kHighlightRadius (clipped to the image).
RefImage bound_highlights(const RefImage& out, const RefImage& L);

/// Sections 2-7: the whole regression filter on the quotient z.
/// Uses only the filter parameters of `opt` (progress is ignored).
/// `diagnostics`, if not null, receives the maps of
/// zdenoise::diagnostic_channels() (4 channels).
RefImage regression_filter(const RefImage& z, const RefImage& La,
                           const RefGuides& guides,
                           const zdenoise::FilterOptions& opt,
                           RefStats* stats = nullptr,
                           RefImage* diagnostics = nullptr);

/// docs/FILTER.md section 12: the albedo prefilter of an albedo of
/// `samples` samples a pixel (RGB filtered, other channels copied).
/// With the halves' albedos `half_a`, `half_b` (both given or neither), the
/// variance is the larger of the model's and the 3x3 mean of (a - b)^2 / 4.
RefImage prefilter_albedo(const RefImage& albedo, int samples,
                          const RefImage* half_a = nullptr,
                          const RefImage* half_b = nullptr);

/// Section 7b: the filtered quotient zf scaled towards z's light where
/// their blurs differ by more than z's noise at that scale explains
/// (regression_filter() applies it when opt.energy_radius > 0).
RefImage correct_energy(const RefImage& z, const RefImage& zf,
                        const RefImage& La, const zdenoise::FilterOptions& opt);

/// demodulate + regression_filter + remodulate.
RefImage denoise(const RefImage& L, const RefImage& La, const RefGuides& guides,
                 const zdenoise::FilterOptions& opt, RefStats* stats = nullptr);

}  // namespace zdenoise_ref
