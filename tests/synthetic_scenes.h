// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Synthetic test scenes with exact ground truth for the filter tests.
//
// Every scene is radiance = albedo * lighting (+ emission where the albedo is
// zero), rendered "noisily" like Monte Carlo: each pixel is the clean value
// times the mean of `spp` independent exponential(1) samples (a gamma(spp)
// multiplier with mean 1 and relative standard deviation 1/sqrt(spp); one
// multiplier per pixel shared by R, G, B, as path-traced noise is strongly
// correlated across channels). The samples are split into two halves A, B
// with noisy = (A + B) / 2, and the exact variance of the pixel mean
// (clean^2 / spp per channel) is provided as well. Random numbers come from
// std::mt19937 with a fixed seed, converted with our own code, so the images
// are identical with every standard library.

#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

namespace synth {

struct Noise {
    int spp       = 8;      ///< samples per pixel (even: split into halves)
    uint32_t seed = 20180194;
};

using Pixel = std::array<int, 2>;  ///< (x, y)

struct Scene {
    std::string name;
    int w = 0, h = 0;
    OIIO::ImageBuf clean;      ///< ground-truth radiance, RGB float
    OIIO::ImageBuf noisy;      ///< noisy radiance, RGB float
    OIIO::ImageBuf albedo;     ///< noise-free albedo, RGB float
    OIIO::ImageBuf normal;     ///< unit shading normal, 3 channels
    OIIO::ImageBuf depth;      ///< planar depth, 1 channel
    OIIO::ImageBuf object_id;  ///< 1 channel plain id, or 4 (id,cov) x 2
    OIIO::ImageBuf variance;   ///< exact variance of `noisy`, RGB
    OIIO::ImageBuf half_a, half_b;  ///< noisy = (half_a + half_b) / 2

    // Layout, where the scene has it
    int edge_x       = -1;  ///< first column right of a vertical edge/boundary
    int face_width   = 0;   ///< saw-tooth: width of a face in columns
    int tread_height = 0;   ///< staircase: height of a tread in rows
    std::vector<float> levels;  ///< per face/tread/side: lighting level
    std::vector<Pixel> zero_albedo;     ///< albedo 0 in all of R, G, B
    std::vector<Pixel> partial_albedo;  ///< albedo 0 in channel 2 only
    std::vector<Pixel> nonfinite;       ///< NaN / +Inf / -Inf radiance
};

/// (a) fine texture: a 2-pixel checker times per-pixel random variation in
/// the albedo, under smooth (low-frequency) lighting; flat, one object.
Scene fine_texture(int w, int h, Noise noise = {});

/// (b) a hard shadow edge: lighting 1.0 for x < edge_x, 0.25 beyond, on a
/// flat plane of uniform albedo.
Scene shadow_edge(int w, int h, Noise noise = {});

/// (c) saw-tooth: vertical faces of `face_width` columns alternating between
/// two normals 80 degrees apart, Lambert-lit from one side (even faces
/// bright, odd faces dark), equal albedo, depth of the mean plane.
Scene sawtooth(int w, int h, int face_width = 4, Noise noise = {});

/// (d) staircase: horizontal treads of `tread_height` rows, identical normal
/// and albedo, a different lighting level per tread, and a depth step
/// between treads (each tread slightly slanted).
Scene staircase(int w, int h, int tread_height = 8, Noise noise = {});

/// (e) two objects side by side (plain ids 1 and 2, boundary at edge_x),
/// same normal, depth and albedo, lighting 1.0 vs `dark`.
Scene two_objects(int w, int h, Noise noise = {}, float dark = 0.1f);

/// (e') the same two objects with a Cryptomatte-style id guide of two
/// (id, coverage) ranks (4 channels), the column edge_x - 1 being an
/// anti-aliased blend of both objects (coverage varying per row, ranks
/// sorted by coverage) whose radiance is the coverage-weighted mix.
Scene two_objects_cryptomatte(int w, int h, Noise noise = {}, float dark = 0.1f);

/// (g) a patch of 8x8 pixels facing the camera, whose variance guide says
/// every pixel is far above sigma_good, on a nearly noise-free corrugated
/// surface whose columns lean 66 degrees left and right: none of them passes
/// the patch's normal test (cosine 0.4), but each 2x2 block's mean normal
/// faces the camera. Flat light 0.5, albedo 0.5. A window of the patch
/// fitted on the pyramid's blocks has no good point at full resolution.
Scene corrugated_patch(int w, int h, Noise noise = {});

/// (f) smooth lighting on a mildly textured plane, with isolated pixels of
/// zero albedo (emitters, radiance 2.0 x noise), of zero albedo in the blue
/// channel only, and of NaN, +Inf or -Inf noisy radiance (never adjacent).
Scene holes(int w, int h, Noise noise = {});

/// Make `s`'s guides differ from row to row and column to column, so that
/// a guide or albedo read a row or a column off shows in the output: its
/// albedo (and light with it) times a checker of 2x3 pixels, its normals
/// tilted on a checker of 4x4 pixels and, with `depth_treads`, its depth in
/// treads of 5 rows (steps of 6 %, beyond the depth test's 2 %).
void vary_guides(Scene& s, bool depth_treads);

/// A float ImageBuf of w x h x nch from interleaved values.
OIIO::ImageBuf make_image(int w, int h, int nch, const std::vector<float>& px);

/// Luminance of RGB pixel (x, y) of an image.
double luminance(const OIIO::ImageBuf& img, int x, int y);

// ---- measurements used by the tests ----

/// All pixels of the data window as float (every channel).
std::vector<float> pixels(const OIIO::ImageBuf& img);

/// Mean over pixels and RGB channels of (x - ref)^2 / (ref^2 + 1e-2).
double rel_mse(const OIIO::ImageBuf& img, const OIIO::ImageBuf& ref);
/// The same over the pixels [x0, x1) x [y0, y1) only.
double rel_mse(const OIIO::ImageBuf& img, const OIIO::ImageBuf& ref, int x0,
               int x1, int y0, int y1);

/// Whether a and b have the same pixels, exactly (ImageBufAlgo::compare).
bool same_pixels(const OIIO::ImageBuf& a, const OIIO::ImageBuf& b);

/// Mean luminance over the pixels [x0, x1) x [y0, y1).
double mean_luminance(const OIIO::ImageBuf& img, int x0, int x1, int y0, int y1);

/// Pearson correlation of the high-pass luminance (pixel minus its 5x5 box
/// mean) of two images, over pixels at least `border` from the edges.
double highpass_correlation(const OIIO::ImageBuf& a, const OIIO::ImageBuf& b,
                            int border = 3);

/// The image with its data window (and display window) moved to (x, y).
OIIO::ImageBuf shifted(const OIIO::ImageBuf& img, int x, int y);

}  // namespace synth
