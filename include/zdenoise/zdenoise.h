// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// zdenoise: a denoiser for Monte Carlo path-traced images after Zhdanov,
// Ershov & Voloboy (2018). The public API follows OpenImageIO's
// ImageBufAlgo conventions: every operation comes in two forms,
//
//     bool op(ImageBuf& dst, <inputs>, ..., ROI roi = {}, int nthreads = 0);
//     ImageBuf op(<inputs>, ..., ROI roi = {}, int nthreads = 0);
//
// The first writes into `dst` (allocating it as a float image shaped like the
// first input when `dst` is uninitialized) and returns false on error, with
// the message in `dst.geterror()`. The second returns a new image whose
// `has_error()` is true on failure. No operation throws or exits.
// regression_filter(), denoise() and layered_denoise() can be cancelled
// (FilterOptions::cancel).
//
// Channel convention: channels 0, 1, 2 of the radiance / quotient / albedo
// images are R, G, B; every other channel of the first input (alpha, AOVs)
// is copied to the output untouched. Pixel data of any type (float, half,
// integer) are accepted; all computation is in float (accumulations in
// double). `roi` selects the output pixels; the filter reads whatever it
// needs around them, so filtering a ROI gives exactly the pixels a
// whole-image run gives there. `nthreads` = 0 uses OIIO's global "threads"
// attribute; the result is bit-identical for every thread count.
//
// The algorithm, with every decision the paper leaves open, is specified in
// docs/FILTER.md.

#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/export.h>
#include <zdenoise/filter_stats.h>
#include <zdenoise/version.h>

namespace zdenoise {

using OIIO::ImageBuf;
using OIIO::ROI;

/// Every parameter of the regression filter (docs/FILTER.md section 9).
/// The defaults are tuned on the public benchmark; where they differ from
/// the method's own (edge_k, value_k, sigma_good, radius_growth,
/// centre_stride) the benchmark showed them better on every scene.
/// `algorithm_defaults()` gives the method's.
struct FilterOptions {
    /// Smallest window half-size: the window starts at (2*r_min+1)^2 pixels.
    int r_min = 2;
    /// Largest window half-size (stop criterion "size").
    int r_max = 16;
    /// Stop criterion "quality": predicted relative noise of the fitted
    /// value at the centre, sqrt(sum w^2 sigma^2) / sum w.
    float eta_target = 0.02f;
    /// Stop criterion "strong variation": a quadrant plane disagreeing with
    /// the whole-window plane at the centre by more than
    /// max(edge_k * (its predicted relative noise), tau_min) stops growth and
    /// steps back to the previous radius.
    float edge_k = 1.5f;
    float tau_min = 0.05f;
    /// Strength k of the value term exp(-k |z - <z>| / <z>) of the weight.
    float value_k = 1.0f;
    /// 1 = the value term's scale is |<z>| + t s(p0) instead of |<z>|,
    /// with s(p0) the centre's noise standard deviation and t the outlier
    /// threshold (docs/FILTER.md section 5): a difference the noise
    /// explains is not taken for structure, so that skewed Monte Carlo
    /// noise is not pulled down at low sample counts (interiors at 4 spp
    /// 30 % better, every public case better or equal); 0 = the method's
    /// |<z>|.
    int value_noise = 1;
    /// Points whose relative noise sigma exceeds this take no part in fits
    /// (they still receive the filtered value).
    float sigma_good = 3.0f;
    /// Albedo channels below this, above its inverse, or non-finite are not
    /// demodulated: the radiance passes through unchanged there. Also the
    /// epsilon of the demodulation L / (La + albedo_eps).
    float albedo_eps = 1e-3f;
    /// Depth guide: a neighbour whose inverse depth departs from the plane
    /// extrapolated from the centre by more than this fraction is on another
    /// surface (weight 0).
    float depth_tolerance = 0.02f;
    /// Normal guide: weight (n.n0)^normal_power when n.n0 > normal_cut.
    float normal_cut = 0.5f;
    float normal_power = 4.0f;
    /// Exponent of the quadrant weight w_m = max(Z/Zm, Zm/Z)^quadrant_power.
    float quadrant_power = 8.0f;
    /// Fit windows only at every centre_stride-th pixel in x and y (the
    /// lattice), plus every fit point that none of the lattice points of
    /// its cell is on the surface of; splatting covers the pixels between.
    /// 1 = every fit point a centre: the exact filter, 1.5x as slow. The
    /// default 3 is within 2 % of its relMSE on every case of the public
    /// benchmark (docs/PERFORMANCE.md "Strided centres"). A stride beyond
    /// r_min + 1 is used as r_min + 1, so that windows always overlap.
    int centre_stride = 3;
    /// With centre_stride > 1: 1 = a fit point is also a centre when a
    /// lattice window of its cell on its surface stopped at an edge (detail
    /// keeps every window); 2 = of those fit points, every other one (a
    /// checkerboard: x + y even), whose splats reach the ones between
    /// (0.82x the time on the 1080p frame, relMSE at most 1.013x;
    /// docs/PERFORMANCE.md "The default now"); 0 = the lattice only (up
    /// to 1.6x the relMSE: a preview setting).
    int stride_edges = 1;
    /// 1 = outliers (fireflies: a point above its neighbourhood's median by
    /// more than its noise allows, docs/FILTER.md section 3a) keep only the
    /// light their neighbourhood allows in the fit, and the rest of their
    /// radiance is spread over their surface around them, so that the
    /// image keeps its energy; 0 = off (the method's: the value term alone
    /// down-weights them, and their energy is lost).
    int outlier_spread = 1;
    /// The radius tried after R: max(R + 1, floor(R * radius_growth)), up
    /// to r_max; an edge steps back to the radius tried before. 1 is
    /// the method's R + 1; the default 2 (radii 2, 4, 8, 16) is about
    /// twice as fast and better on the whole public benchmark
    /// (docs/FILTER.md section 9).
    float radius_growth = 2.0f;
    /// Trial radii at or above this are fitted on the pyramid's first
    /// level, the fit points averaged 2x2 (a quarter of the points: radius
    /// 2R costs what radius R does), and splatted at full resolution
    /// (docs/FILTER.md 5.1); 0 = every fit at full resolution, the exact
    /// filter. At least 4.
    int pyramid_radius = 0;
    /// The radius r of the low-frequency energy correction (docs/FILTER.md
    /// section 7b), in pixels; 0 = none, the method's. The filtered light
    /// is scaled towards the input's where their blurs (three box passes
    /// of radius r, about a Gaussian of standard deviation r) differ by
    /// more than the input's noise at that scale explains: the light the
    /// value term takes out at low sample counts comes back, without the
    /// blotches of its uneven loss. Pixels the filter leaves as they were
    /// are not changed. It widens filter_halo() by 3 r + 1. At most 64.
    int energy_radius = 12;
    /// 1 = the noise of the light estimated from the image is also
    /// estimated as keep_structure() does (docs/FILTER.md section 14: the
    /// smallest of four directions' 5x5 pools of squared second
    /// differences), and the smaller of that and section 3's 5x5 median of
    /// residuals is taken: the median reads a lattice of thin shadow lines
    /// as noise and lets the windows fill it in. layered_denoise() sets it
    /// for a `direct` layer (measured: bench/path_mode.md, "The direct
    /// light's noise"); 0, the default elsewhere: for all light it was
    /// worse (fireflies and sparse indirect light).
    int directional_noise = 0;
    /// 1 = each pixel takes, by its estimated error (Stein's unbiased risk
    /// estimate, or the halves' cross error when half_a and half_b are
    /// given), today's filter or one of two feature regressions
    /// (docs/FILTER.md section 13, include/zdenoise/selection.h), the
    /// default: better on every public case, about 1.5x the time and twice
    /// the memory of 0 = today's filter alone, the method's own
    /// (docs/SELECTION.md; bench/results/2026-12-selection-log.md
    /// section 10).
    int select = 1;
    /// The filter's core: 0 = the windows above (the paper's adaptive
    /// radius, docs/FILTER.md sections 2-13), the default; 1 = the box
    /// core (section 15, experimental): ridge regressions on position,
    /// normal and depth over square windows of radii 1, 2, 4, ...
    /// box_radius from box sums, whose cost per pixel does not grow with
    /// the radius, and per pixel a blend of the input and the radii by
    /// their estimated risks (section 15.3). Measured on the public set at 4,
    /// 16 and 64 spp: 0.95-1.16x the default's relMSE; worse on
    /// bench/scenes/glass_cabin, and not faster in this version
    /// (bench/results/2026-12-box-core-log.md). With 1, r_min,
    /// r_max (but for the outliers' spread), the stop criteria, the
    /// weights' and the stride's options and select are not used.
    int core = 0;
    /// The box core's largest window half-size (core 1). At most 128.
    int box_radius = 64;

    /// Optional progress report with the fraction done in [0,1], called from
    /// one thread at a time (not necessarily the caller's), never going
    /// back (layered_denoise(): each layer its share). Not a filter
    /// parameter: it never changes the result.
    std::function<void(float)> progress;

    /// If not null, a flag that another thread (or `progress`) sets to stop
    /// the running call: regression_filter(), denoise() and
    /// layered_denoise() then return false with the error "zdenoise:
    /// cancelled", and dst holds no result: an image the call allocated
    /// is reset (uninitialised), a caller's has the pixels of roi set to 0.
    /// Every worker polls it between blocks, rows and stages: on a 1080p
    /// frame with 2 threads the call returns 0.01-0.18 s after the set
    /// (measured on 2026-12-06, README.md "Library"); set after the last
    /// poll, the call completes. One flag and not a progress that returns
    /// false, so that the callers of `progress` keep their signature. Not
    /// a filter parameter: it never changes the result.
    const std::atomic<bool>* cancel = nullptr;

    /// The data window of the whole image, when the images given to an
    /// operation hold only a part of it: for example a horizontal strip of
    /// rows, read with filter_halo() rows above and below the rows to
    /// compute (`roi`). Windows clip at the frame's edges, not at the
    /// images', and the filter's processing order is anchored at the
    /// frame's origin, so the result in roi is bit-identical to that of a
    /// run on the whole image. The images must cover roi widened by
    /// filter_halo() and clipped to the frame. Undefined (the default): the
    /// first input's data window is the frame. Not a filter parameter: it
    /// never changes the result.
    ROI frame;

    /// If not null, receives per-pixel maps of what the filter did, over
    /// the output pixels (docs/DIAGNOSTICS.md): float channels named as
    /// diagnostic_channels() says, allocated here when `diagnostics` is
    /// uninitialised (data window: the output's roi), else written in
    /// place (it must hold the roi and 4 channels). denoise() and
    /// layered_denoise() fill it too (layers: combined over the filtered
    /// layers, weighted by their light). Not a filter parameter: it never
    /// changes the result.
    ImageBuf* diagnostics = nullptr;

    /// If not null, receives the filter's hat diagonal D = d out_l / d z_l
    /// over the output pixels (one float channel, allocated here when
    /// uninitialised, else written in place): how much each pixel's
    /// filtered light luminance follows its own quotient luminance, every
    /// weight held fixed but the value term's (docs/FILTER.md 13.3). Stein's
    /// unbiased risk estimate of the filter's error needs it; 1 where the
    /// pixel is passed through. Only with select 0 (the selection computes
    /// its own); layered_denoise() ignores it. Not a filter parameter: it
    /// never changes the result.
    ImageBuf* hat_diagonal = nullptr;

    /// The method's own defaults (docs/FILTER.md section 9: edge_k 3, value_k 2,
    /// sigma_good 1, radius_growth 1, every fit point a centre), before
    /// tuning on data.
    static FilterOptions algorithm_defaults()
    {
        FilterOptions o;
        o.edge_k     = 3.0f;
        o.value_k    = 2.0f;
        o.sigma_good = 1.0f;
        o.radius_growth = 1.0f;
        o.centre_stride = 1;
        o.outlier_spread = 0;
        o.value_noise = 0;
        o.select = 0;
        o.energy_radius = 0;
        return o;
    }
};

/// Optional guide images for the filter. Each must have the radiance's
/// data window; a null pointer means "not given".
struct Guides {
    /// Shading normal, 3 channels (any space consistent across the image;
    /// need not be unit length: it is normalised).
    const ImageBuf* normal = nullptr;
    /// Distance or planar depth along the camera ray, channel 0. Values <= 0,
    /// >= 1e9 or non-finite mean "no surface": the pixel passes through.
    const ImageBuf* depth = nullptr;
    /// Object identity. One channel: a plain id (equal ids weight 1, else 0).
    /// 2k channels: k (id, coverage) pairs, e.g. Cryptomatte ranks; the
    /// weight is the overlap sum_id min(c_p(id), c_p0(id)) of the
    /// coverages normalised to sum 1.
    const ImageBuf* object_id = nullptr;
    /// Per-pixel variance of the radiance (variance of the pixel mean):
    /// 1 channel, or one per RGB channel.
    const ImageBuf* variance = nullptr;
    /// Two independent half renders with radiance = (A+B)/2, RGB. Used for
    /// the variance when `variance` is not given: Var = (A-B)^2/4.
    const ImageBuf* half_a = nullptr;
    const ImageBuf* half_b = nullptr;
};

/// Demodulation z = L / (La + eps) per RGB channel. Channels whose albedo is
/// below `albedo_eps`, above 1 / `albedo_eps`, or non-finite keep the
/// radiance unchanged, so that remodulate() inverts this exactly.
///
/// @param dst       Result (float when allocated here).
/// @param radiance  Noisy radiance L; channels 0-2 are RGB, any others are
///                  copied.
/// @param albedo    Noise-free albedo La, channels 0-2, same data window.
/// @param albedo_eps  Smallest albedo demodulated, also the epsilon added.
ZDENOISE_API bool demodulate(ImageBuf& dst, const ImageBuf& radiance,
                             const ImageBuf& albedo, float albedo_eps = 1e-3f,
                             ROI roi = {}, int nthreads = 0);
ZDENOISE_API ImageBuf demodulate(const ImageBuf& radiance,
                                 const ImageBuf& albedo,
                                 float albedo_eps = 1e-3f, ROI roi = {},
                                 int nthreads = 0);

/// Remodulation L = z * (La + eps), the exact inverse of demodulate() with
/// the same albedo and eps (channels not demodulated pass through).
ZDENOISE_API bool remodulate(ImageBuf& dst, const ImageBuf& quotient,
                             const ImageBuf& albedo, float albedo_eps = 1e-3f,
                             ROI roi = {}, int nthreads = 0);
ZDENOISE_API ImageBuf remodulate(const ImageBuf& quotient,
                                 const ImageBuf& albedo,
                                 float albedo_eps = 1e-3f, ROI roi = {},
                                 int nthreads = 0);

/// The adaptive-radius five-plane regression filter with splatting,
/// applied to a demodulated image (docs/FILTER.md sections 2-6).
///
/// @param dst       Filtered quotient.
/// @param quotient  Demodulated radiance z (from demodulate()); channels 0-2
///                  are filtered, any others copied. Its alpha channel (if
///                  the spec names one) marks "no surface" where it is 0.
/// @param albedo    The albedo used to demodulate: marks which channels of
///                  which pixels were demodulated (and so are filtered), and
///                  converts a radiance variance to the quotient's.
/// @param guides    Optional normal, depth, object id and noise guides.
/// @param options   Filter parameters.
/// @param stats     If not null, filled with what the filter did.
/// Non-finite quotient values never reach the output: a pixel with one is
/// left out of the fits and takes the filtered value of the windows around
/// it, or 0 where none covers it.
ZDENOISE_API bool regression_filter(ImageBuf& dst, const ImageBuf& quotient,
                                    const ImageBuf& albedo,
                                    const Guides& guides = {},
                                    const FilterOptions& options = {},
                                    FilterStats* stats = nullptr,
                                    ROI roi = {}, int nthreads = 0);
ZDENOISE_API ImageBuf regression_filter(const ImageBuf& quotient,
                                        const ImageBuf& albedo,
                                        const Guides& guides = {},
                                        const FilterOptions& options = {},
                                        FilterStats* stats = nullptr,
                                        ROI roi = {}, int nthreads = 0);

/// The significance filter (docs/FILTER.md section 14), for light that the
/// render computes with little noise and sharp structure (the direct light
/// of a sun or a small lamp: hard and thin shadows): each pixel becomes the
/// mean of the pixels within 5 px on its surface whose 3x3 neighbourhood a
/// test at the pixels' noise cannot tell from its own (the mean over the
/// nine pairs of (y_p - y_q)^2 / (V_p + V_q) below 1.5, about the 85 %
/// quantile of chi-square with 9 degrees of freedom over 9; y the
/// luminance) and whose noise is at most 4x its own. A neighbour that
/// differs beyond its noise (the other side of a shadow line) is left out,
/// so that structure the input shows is kept; a noise-free pixel (V = 0)
/// is left exactly as it is. V is estimated from the image itself: the
/// smallest, over four directions, of the 5x5 mean of squared second
/// differences along that direction (a line or an edge along one direction
/// leaves its second differences at the noise), calibrated on Gaussian
/// noise.
///
/// @param dst     The filtered light, RGB float over roi.
/// @param light   The light, channels 0-2 (a quotient, such as Cycles'
///                DiffDir, or radiance); non-finite values are left out
///                and passed through.
/// @param guides  normal (neighbours within about 25 degrees) and
///                object_id (channel 0 equal) keep surfaces apart; the
///                other guides are not used.
/// @param frame   The data window of the whole image when `light` holds
///                only a part of it (as FilterOptions::frame); the inputs
///                must then cover roi widened by significance_halo().
///                Undefined: light's data window.
ZDENOISE_API bool significance_filter(ImageBuf& dst, const ImageBuf& light,
                                      const Guides& guides = {},
                                      ROI frame = {}, ROI roi = {},
                                      int nthreads = 0);
ZDENOISE_API ImageBuf significance_filter(const ImageBuf& light,
                                          const Guides& guides = {},
                                          ROI frame = {}, ROI roi = {},
                                          int nthreads = 0);

/// Keep the structure a smoother removed (docs/FILTER.md section 14): where
/// `smoothed` departs from `light` beyond the noise of light around the
/// pixel (the mean over its 8 neighbours on its surface of
/// (y - y_smoothed)^2 / V above 3.265, the 99.9 % quantile of chi-square
/// with 8 degrees of freedom over 8; the pixel's own departure is left out,
/// so that a lone firefly the smoother removed stays removed), the result
/// is significance_filter()'s; elsewhere it is `smoothed`. Where V is 0
/// (no noise) and smoothed differs, that is `light` itself; where smoothed
/// is not finite and light is, the significance filter. Parameters as for
/// significance_filter(); `smoothed` must cover roi widened by 1 (clipped
/// to the frame): the test at roi's border reads it. If `kept` is not null,
/// it receives the number of pixels of roi that took the significance
/// filter.
ZDENOISE_API bool keep_structure(ImageBuf& dst, const ImageBuf& light,
                                 const ImageBuf& smoothed,
                                 const Guides& guides = {}, ROI frame = {},
                                 int64_t* kept = nullptr, ROI roi = {},
                                 int nthreads = 0);
ZDENOISE_API ImageBuf keep_structure(const ImageBuf& light,
                                     const ImageBuf& smoothed,
                                     const Guides& guides = {},
                                     ROI frame = {}, int64_t* kept = nullptr,
                                     ROI roi = {}, int nthreads = 0);

/// The noise estimate of significance_filter() (docs/FILTER.md section 14):
/// the variance V of the luminance of `light` at each pixel of roi, from
/// the image itself, into `dst` (1 float channel); NaN where it cannot be
/// estimated (a non-finite pixel, or no neighbour on its surface).
/// Parameters as for significance_filter(); the inputs must cover roi
/// widened by noise_variance_halo().
ZDENOISE_API bool noise_variance(ImageBuf& dst, const ImageBuf& light,
                                 const Guides& guides = {}, ROI frame = {},
                                 ROI roi = {}, int nthreads = 0);

/// How far an output pixel of noise_variance() looks.
ZDENOISE_API int noise_variance_halo();

/// How far an output pixel of significance_filter() and keep_structure()
/// looks: the 5-px search, its 3x3 test and the noise estimate's 5x5 of
/// second differences.
ZDENOISE_API int significance_halo();

/// The whole method: demodulate, regression_filter, remodulate.
/// Parameters as for those three operations.
ZDENOISE_API bool denoise(ImageBuf& dst, const ImageBuf& radiance,
                          const ImageBuf& albedo, const Guides& guides = {},
                          const FilterOptions& options = {},
                          FilterStats* stats = nullptr, ROI roi = {},
                          int nthreads = 0);
ZDENOISE_API ImageBuf denoise(const ImageBuf& radiance, const ImageBuf& albedo,
                              const Guides& guides = {},
                              const FilterOptions& options = {},
                              FilterStats* stats = nullptr, ROI roi = {},
                              int nthreads = 0);

/// denoise() with a second albedo for remodulation: the radiance is
/// demodulated by `albedo` (and filtered as that quotient), and the result
/// is remodulated by `remodulation_albedo`, a cleaner image of the same
/// reflectance (a deterministic auxiliary render, docs/AUX.md). A render's
/// own albedo shares its samples with the radiance, so their quotient is
/// free of much of the albedo's noise (anti-aliasing of texture and
/// edges); multiplying by the clean albedo then removes what is left.
/// Per RGB channel: where `albedo` is not demodulated the radiance passes
/// through as in denoise(); where `remodulation_albedo` is below
/// albedo_eps, above its inverse or non-finite, `albedo` remodulates
/// instead. A null `remodulation_albedo` (or one equal to `albedo`) is
/// denoise() above. A pointer, so that no call of the forms above can
/// reach this one (or the reverse) by an image in the wrong place.
ZDENOISE_API bool denoise(ImageBuf& dst, const ImageBuf& radiance,
                          const ImageBuf& albedo,
                          const ImageBuf* remodulation_albedo,
                          const Guides& guides = {},
                          const FilterOptions& options = {},
                          FilterStats* stats = nullptr, ROI roi = {},
                          int nthreads = 0);
ZDENOISE_API ImageBuf denoise(const ImageBuf& radiance, const ImageBuf& albedo,
                              const ImageBuf* remodulation_albedo,
                              const Guides& guides = {},
                              const FilterOptions& options = {},
                              FilterStats* stats = nullptr, ROI roi = {},
                              int nthreads = 0);

/// remodulate() of a quotient demodulated by `albedo`, by
/// `remodulation_albedo`: L = z * (Lr + eps) where `albedo` was
/// demodulated and Lr is usable (as albedo_eps defines), z * (La + eps)
/// where only `albedo` is, z elsewhere. The last step of the denoise()
/// above.
ZDENOISE_API bool remodulate(ImageBuf& dst, const ImageBuf& quotient,
                             const ImageBuf& albedo,
                             const ImageBuf& remodulation_albedo,
                             float albedo_eps = 1e-3f, ROI roi = {},
                             int nthreads = 0);

/// The albedo prefilter (docs/FILTER.md section 12): a renderer's albedo
/// AOV of N samples per pixel is noisy where a pixel's footprint mixes
/// albedos (the anti-aliasing of texture and object edges, the speckle of
/// rough glossy first hits), and remodulation multiplies that noise back
/// into the result. This makes it clean where it is noisy and leaves it
/// exact where it is not: a non-local mean over the 7x7 around each pixel,
/// 3x3 patches compared against the variance of a pixel mean of N samples
/// of the albedos its 3x3 mixes.
///
/// @param dst      Prefiltered albedo (float when allocated here); RGB
///                 filtered, any other channel copied; a non-finite value
///                 passed through.
/// @param albedo   The noisy albedo, channels 0-2. Neighbourhoods clip at
///                 its data window: to compute part of an image exactly,
///                 give it over that part widened by albedo_prefilter_halo()
///                 (clipped to the image).
/// @param samples  The samples per pixel it was rendered with (>= 1).
ZDENOISE_API bool prefilter_albedo(ImageBuf& dst, const ImageBuf& albedo,
                                   int samples, ROI roi = {},
                                   int nthreads = 0);
ZDENOISE_API ImageBuf prefilter_albedo(const ImageBuf& albedo, int samples,
                                       ROI roi = {}, int nthreads = 0);

/// The same for an albedo that is the mean of two independent halves of
/// the render, whose own albedos are `half_a` and `half_b` (channels 0-2,
/// over at least `albedo`'s data window): the variance of each value is the
/// larger of the model's above and the halves' own, the mean over the 3x3
/// (finite values within the window) of (a - b)^2 / 4 (NFOR's feature
/// variance). The halves see noise the model cannot: texture finer than a
/// pixel's 3x3, the speckle of glossy first hits. `samples` is the mean's
/// (both halves' together).
ZDENOISE_API bool prefilter_albedo(ImageBuf& dst, const ImageBuf& albedo,
                                   int samples, const ImageBuf& half_a,
                                   const ImageBuf& half_b, ROI roi = {},
                                   int nthreads = 0);

/// How far a pixel of prefilter_albedo() looks: 5 pixels.
ZDENOISE_API int albedo_prefilter_halo();

/// What pool_aux_albedo() knows of its two albedos.
struct AuxAlbedoOptions {
    /// Samples per pixel of the render's own albedo (>= 1). Unknown: 1,
    /// the noisiest it can be, so that noise is never taken for a wrong
    /// auxiliary pixel.
    int render_samples = 1;
    /// Samples per pixel of the auxiliary albedo; 0: noise-free (exact).
    int aux_samples = 0;
    /// Relative rounding of the stored values (both files): differences
    /// below it are never disagreements. Default: half float's (2^-11),
    /// the coarsest a renderer writes an albedo in.
    float precision = 1.0f / 2048.0f;
    /// The pixels AuxAlbedoStats counts (default: all of the ROI), so that
    /// strips computed with a halo count each pixel once.
    ROI counted = {};
};

/// What pool_aux_albedo() did over its output pixels.
struct AuxAlbedoStats {
    uint64_t pixels   = 0;  ///< pixels of the ROI
    uint64_t rejected = 0;  ///< of those, where the render's own was used
};

/// The auxiliary albedo made safe and pooled with the render's own
/// (docs/AUX.md, "Wrong auxiliary pixels"): where the two disagree in some
/// channel by more than 4 standard deviations of their difference (each
/// one's anti-aliasing noise: the variance of a mean of N independent
/// samples, with the mean they share if they agree, of the albedos the two
/// images' 5x5 holds) plus their rounding, the auxiliary pixel
/// shows something else than the render (the world, an emitter or a
/// holdout of another convention, another frame or camera) and the
/// render's own is used. Elsewhere both estimate the same pixel albedo
/// and are averaged with weights N^(3/2), the inverse of their stratified
/// variance (docs/FILTER.md section 12): a noise-free auxiliary albedo is
/// taken as it is, one of few samples beside a render of many counts
/// less.
///
/// @param dst     The albedo to demodulate and remodulate by (float when
///                allocated here), RGB; other channels copied from `aux`.
/// @param aux     The auxiliary albedo, channels 0-2.
/// @param render  The render's own albedo, channels 0-2. A value that is
///                not finite leaves the auxiliary one. Neighbourhoods clip
///                at each image's data window: to compute part of an image
///                exactly, give both over it widened by aux_albedo_halo().
/// @param stats   If not null, receives the counts over `roi` (within
///                options.counted).
ZDENOISE_API bool pool_aux_albedo(ImageBuf& dst, const ImageBuf& aux,
                                  const ImageBuf& render,
                                  const AuxAlbedoOptions& options = {},
                                  AuxAlbedoStats* stats = nullptr,
                                  ROI roi = {}, int nthreads = 0);

/// How far a pixel of pool_aux_albedo() looks: 2 pixels.
ZDENOISE_API int aux_albedo_halo();

/// One layer of a layered render (docs/FILTER.md section 11): the radiance of
/// one specular history or BSDF lobe with its own albedo (colour) pass.
struct Layer {
    /// What the layer is called (in messages, and for the caller's output).
    std::string name;
    /// The layer's radiance L, channels 0-2 RGB. When `divided`, the
    /// quotient z = L / colour as Blender Cycles writes its Direct/Indirect
    /// lighting passes (DiffDir + DiffInd etc.).
    const ImageBuf* radiance = nullptr;
    /// The layer's albedo (colour pass), channels 0-2, same data window.
    const ImageBuf* albedo = nullptr;
    /// `radiance` is already divided by `albedo`: it is filtered as the
    /// quotient as it is, and the result is multiplied by the albedo itself
    /// (not albedo + albedo_eps), as the renderer composes it. Channels whose
    /// albedo is below albedo_eps are not filtered (as in demodulate()).
    bool divided = false;
    /// false: the layer is not filtered, only composed (radiance, or
    /// albedo * quotient when `divided`).
    bool filter = true;
    /// The layer's light reached the camera through a glossy or specular
    /// bounce (reflection, refraction: Cycles' Gloss and Trans lobes,
    /// Arnold's specular, transmission, coat; specular depth layers 1-5).
    /// What it shows (the reflected scene) is not what the guides describe
    /// (the surface seen), so only the filter's edge test protects its
    /// detail: for such a layer the test is made stricter, edge_k times
    /// kReflectedEdgeScale (docs/LAYERS.md).
    bool reflected = false;
    /// Guides of this layer (e.g. the normals seen through a mirror); each
    /// member given here replaces the shared guide of the same kind.
    Guides guides;
    /// The layer is direct light (Cycles' DiffDir): light the renderer
    /// computes with little noise and sharp structure (hard and thin
    /// shadows). After the regression filter, keep_structure() gives back
    /// what it smoothed beyond the layer's noise (docs/FILTER.md section
    /// 14, docs/LAYERS.md "Light by path"). With a direct layer, the
    /// images must cover one more pixel around roi than filter_halo() says
    /// (keep_structure()'s 3x3 test). Its `stats` count only kept_pixels
    /// (its windows reach that extra ring, which depends on how the frame
    /// is cut).
    bool direct = false;
    /// If not null, a cleaner image of the layer's albedo (the lobe colour
    /// of a deterministic auxiliary render, docs/AUX.md) that remodulates
    /// the filtered layer in place of `albedo`, which still demodulates
    /// it (or divided it, when `divided`): as denoise() with a
    /// remodulation albedo. Where it is not usable (below albedo_eps, above
    /// its inverse, non-finite) `albedo` remodulates.
    const ImageBuf* remodulation_albedo = nullptr;
    /// If not null, receives the layer's denoised radiance (RGB float, the
    /// layer's contribution to the sum), computed in roi.
    ImageBuf* denoised = nullptr;
    /// If not null, receives what the filter did on this layer.
    FilterStats* stats = nullptr;
};

/// The factor on FilterOptions::edge_k for a Layer that is `reflected`.
constexpr float kReflectedEdgeScale = 0.5f;

/// Layered denoising (docs/FILTER.md section 11): every layer is denoised on
/// its own (demodulate, regression_filter, remodulate; or, for a divided
/// layer, regression_filter and a product with its albedo), and the result
/// is the sum of the denoised layers plus the residual, unfiltered. A
/// filtered layer's radiance is clamped at 0 (a layer's light is never
/// negative, but the filter's planes can extrapolate below 0 on a steep
/// convex ramp such as a ceiling next to a light). With
/// `filter` false on every layer the result is the plain sum of the layers
/// and the residual: when the residual is the beauty minus the layers, that
/// is the beauty (to float rounding).
///
/// @param dst       The sum, RGB (3 channels, float when allocated here).
/// @param layers    The layers, at least one; every image must cover the
///                  data window of the first layer's radiance, which the
///                  filter sees as the image (its windows clip there).
/// @param residual  What has no albedo counterpart (emission, environment,
///                  paths beyond the layers), channels 0-2, added as it is;
///                  null for none.
/// @param guides    Guides shared by the layers (Layer::guides overrides).
/// @param options   Filter parameters, the same for every layer, except
///                  edge_k on a `reflected` layer.
/// @param stats     If not null, the statistics summed over the filtered
///                  layers (pixels too; mean_radius weighted by windows).
ZDENOISE_API bool layered_denoise(ImageBuf& dst,
                                  const std::vector<Layer>& layers,
                                  const ImageBuf* residual = nullptr,
                                  const Guides& guides = {},
                                  const FilterOptions& options = {},
                                  FilterStats* stats = nullptr, ROI roi = {},
                                  int nthreads = 0);
ZDENOISE_API ImageBuf layered_denoise(const std::vector<Layer>& layers,
                                      const ImageBuf* residual = nullptr,
                                      const Guides& guides = {},
                                      const FilterOptions& options = {},
                                      FilterStats* stats = nullptr,
                                      ROI roi = {}, int nthreads = 0);

/// How far an output pixel of regression_filter(), denoise() and
/// layered_denoise() looks with these options: it depends only on input
/// pixels at most this many columns and rows away (centres up to r_max
/// away, whose windows reach r_max further, plus the 4-pixel footprint of
/// the noise estimate, plus centre_stride - 1 for the lattice points that
/// decide the centres, docs/FILTER.md section 8; plus 3 energy_radius + 1
/// for the energy correction's blur, section 7b). To compute a part of an
/// image exactly, give the inputs over that part widened by the halo and
/// clipped to the image, and say which image it is (FilterOptions::frame).
ZDENOISE_API int filter_halo(const FilterOptions& options);

/// "name=value ..." of every filter parameter, as recorded in output
/// metadata and printed by `zdenoise -v`.
ZDENOISE_API std::string describe(const FilterOptions& options);

}  // namespace zdenoise
