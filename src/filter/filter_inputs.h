// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The per-pixel planes the regression filter works on: the quotient, its
// pixel classes, noise estimate and guides, decoded once into contiguous
// float arrays over a region (the output ROI plus the filter's halo), and
// the stages that decode them (docs/FILTER.md sections 2-4):
// decode_filter_inputs() runs classify_pixels() (pixel_classes.cpp),
// decode_normals() and decode_object_ids() (guide_weight.cpp),
// raw_variance() (noise_estimate.cpp), split_outliers() (outliers.cpp) and
// smooth_noise() (noise_estimate.cpp).

#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include <zdenoise/zdenoise.h>

#include <OpenImageIO/imagebufalgo_util.h>

#include "internal.h"

namespace zdenoise {
namespace detail {

using OIIO::ImageBuf;
using OIIO::ROI;

/// The smallest magnitude a mean or value is divided by (docs/FILTER.md:
/// EPS).
constexpr double kEps = 1e-8;

/// Pixel class bits (docs/FILTER.md section 2).
enum PixelClass : uint8_t {
    kSurface    = 1 << 0,  ///< alpha > 0 and a valid depth
    kFitPoint   = 1 << 1,  ///< surface, demodulated and finite in R, G, B
    kReceiveR   = 1 << 2,  ///< surface and demodulated in R (then G, B)
    kReceiveAny = 7 << 2,
    kNonFinite  = 1 << 5,  ///< some RGB quotient value is NaN or Inf
};

/// Bitwise id comparison: Cryptomatte ids are float bit patterns that may
/// be NaN, and plain ids compare equal exactly.
inline bool
same_id(float a, float b)
{
    uint32_t ia, ib;
    std::memcpy(&ia, &a, 4);
    std::memcpy(&ib, &b, 4);
    return ia == ib;
}

/// A decoded normal is all zero where the pixel has none.
inline bool
no_normal(const float (&n)[3])
{
    return n[0] == 0.0f && n[1] == 0.0f && n[2] == 0.0f;
}

/// The filter's row kernels are built twice, for the baseline x86-64 and for
/// AVX2 (x86-64-v3), and the loader picks one for the CPU. Their sources
/// are compiled without FMA contraction and sum in a fixed order, so both
/// builds compute the same floats (src/CMakeLists.txt).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#    define ZDENOISE_ROW_KERNEL \
        __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#    define ZDENOISE_ROW_KERNEL
#endif

/// Points per block of the row kernels' lanes.
constexpr int kLanes = 8;

/// Elements past the last pixel of the planes the filter's row kernels read
/// (zl, vs, sigma, cls, zfit): a kernel reads whole blocks of lanes, past a
/// row segment's end, and masks what lies beyond it.
constexpr size_t kPlanePadding = 16;

/// An outlier split off the quotient (docs/FILTER.md section 3a): where it
/// is and the radiance taken out of it, per channel.
struct Outlier {
    int x = 0, y = 0;
    float excess[3] = {};  ///< z (La + albedo_eps): radiance
};

/// The decoded filter input over `region` (row-major, `width` pixels a row).
struct FilterInputs {
    ROI region;          ///< pixels held (within the image's data window)
    ROI image;           ///< the whole image (FilterOptions::frame)
    int width = 0, height = 0;

    std::vector<float> zl;     ///< luminance of z (fit points)
    /// PixelClass bits, 32 bits wide so that the filter kernels read them
    /// in lanes as wide as their floats.
    std::vector<uint32_t> cls;
    std::vector<float> sigma;  ///< relative noise of zl (fit points)
    std::vector<float> vs;     ///< smoothed variance of zl (fit points)
    /// exp(-sigma) of the good fit points (sigma <= sigma_good), 0 at the
    /// others: the part of a point's fit weight that no window changes.
    std::vector<float> fit_prior;
    /// z of the fit points, one plane per channel, 0 at other pixels: what
    /// the fit reads, contiguous along a row and always finite.
    std::vector<float> zfit[3];
    /// The radiance z (La + albedo_eps) of the fit points, one plane per
    /// channel, 0 at other pixels: the range a window's radiance saw.
    std::vector<float> lfit[3];
    /// 1 / (La + albedo_eps) where a channel is demodulated, else 0: what
    /// turns that range back into a bound on z at a receiver.
    std::vector<float> inv_albedo[3];
    /// The outliers split off z (section 3a), in raster order.
    std::vector<Outlier> outliers;

    // Guides (empty when not given), planar with kPlanePadding zeros after
    // the last pixel, as the guide kernel reads them (guide_kernel.h).
    /// The unit normal, one plane per component; all zero where a pixel
    /// has none.
    std::vector<float> normal[3];
    std::vector<float> invdepth;  ///< 1/depth on surface pixels
    int id_pairs = 0;             ///< 0: no id, -1: plain id, k: k pairs
    /// Object id planes: one for a plain id; for k pairs, plane 2a the id
    /// of rank a (float bits) and plane 2a + 1 its normalised coverage.
    std::vector<std::vector<float>> ids;

    bool has_normal() const { return !normal[0].empty(); }

    size_t index(int x, int y) const
    {
        return size_t(y - region.ybegin) * size_t(width)
               + size_t(x - region.xbegin);
    }
    bool in_region(int x, int y) const
    {
        return x >= region.xbegin && x < region.xend && y >= region.ybegin
               && y < region.yend;
    }
};

/// Channels [chbegin, chend) of `img` over `region` as floats.
std::vector<float>
read_channels(const ImageBuf& img, ROI region, int chbegin, int chend);

/// Run `row(y)` for every row of the region, in parallel.
template<class F>
void
for_rows(const ROI& region, int nthreads, F&& row)
{
    OIIO::parallel_for(int64_t(region.ybegin), int64_t(region.yend),
                       [&](int64_t y) { row(int(y)); },
                       paropt_any_length(nthreads));
}

}  // namespace detail
}  // namespace zdenoise
