// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The low-frequency energy correction (docs/FILTER.md section 7b,
// FilterOptions::energy_radius), as a user sees it: skewed low-sample light
// keeps its level without blotches, and a clean region is left as it was.
// The reference (tests/reference_energy.cpp) checks its arithmetic in
// test_filter_reference.cpp.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include <zdenoise/zdenoise.h>

#include "synthetic_scenes.h"

using OIIO::ImageBuf;

namespace {

constexpr int kSize = 160;

/// A smooth light (a ramp and a slow wave) over a flat grey albedo; where
/// `noisy_from` <= x, each pixel the mean of 4 samples of heavy-tailed
/// noise (E^2 / 2, E exponential: mean 1, a sample's relative standard
/// deviation 2.2, as a 4-spp interior's bounced light), else the light
/// itself. Returns the clean and the noisy radiance and the albedo.
void
skewed_light(int noisy_from, ImageBuf& clean, ImageBuf& noisy, ImageBuf& albedo)
{
    std::vector<float> c(3 * kSize * kSize), n(c.size()), a(c.size(), 0.6f);
    std::mt19937 rng(1845);
    std::exponential_distribution<float> e(1.0f);
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const float light = 0.6f * (0.5f + 0.5f * float(x) / kSize
                                        + 0.2f * std::sin(float(y) / 17.0f));
            float mean = 0.0f;
            for (int s = 0; s < 4; ++s) {
                const float v = e(rng);
                mean += 0.25f * v * v / 2.0f;
            }
            const size_t i = 3 * (size_t(y) * kSize + size_t(x));
            for (int ch = 0; ch < 3; ++ch) {
                c[i + ch] = light;
                n[i + ch] = x >= noisy_from ? light * mean : light;
            }
        }
    clean  = synth::make_image(kSize, kSize, 3, c);
    noisy  = synth::make_image(kSize, kSize, 3, n);
    albedo = synth::make_image(kSize, kSize, 3, a);
}

/// The relMSE of the 31x31 box means (clipped at the frame) on a lattice of
/// centres 8 pixels apart: the error of the blotches.
double
box_error(const ImageBuf& img, const ImageBuf& truth)
{
    double sum = 0.0;
    int n      = 0;
    for (int yc = 4; yc < kSize; yc += 8)
        for (int xc = 4; xc < kSize; xc += 8, ++n) {
            const int x0 = std::max(xc - 15, 0), x1 = std::min(xc + 16, kSize);
            const int y0 = std::max(yc - 15, 0), y1 = std::min(yc + 16, kSize);
            const double got  = synth::mean_luminance(img, x0, x1, y0, y1);
            const double want = synth::mean_luminance(truth, x0, x1, y0, y1);
            sum += (got - want) * (got - want) / (want * want + 1e-2);
        }
    return sum / n;
}

ImageBuf
run(const ImageBuf& noisy, const ImageBuf& albedo, int energy_radius)
{
    zdenoise::FilterOptions opt;
    opt.energy_radius = energy_radius;
    ImageBuf out = zdenoise::denoise(noisy, albedo, {}, opt);
    EXPECT_FALSE(out.has_error()) << out.geterror();
    return out;
}

}  // namespace


// The value term weighs the bright tail of the noise down: without the
// correction the light comes out low and in blotches; with it the level is
// kept to 1 % and the blotches' error falls, the noise still removed.
TEST(EnergyCorrection, SkewedLowSampleLightKeepsItsLevel)
{
    ImageBuf clean, noisy, albedo;
    skewed_light(0, clean, noisy, albedo);
    const ImageBuf off = run(noisy, albedo, 0);
    const ImageBuf on  = run(noisy, albedo, 12);
    auto level = [&](const ImageBuf& img) {
        return synth::mean_luminance(img, 0, kSize, 0, kSize)
               / synth::mean_luminance(clean, 0, kSize, 0, kSize);
    };
    std::printf("  skewed 4-sample light: level %.4f (without the correction %.4f, "
                "the render's %.4f); box means' error %.3g (%.3g, the render's "
                "%.3g); relMSE %.3g (%.3g, the render's %.3g)\n",
                level(on), level(off), level(noisy), box_error(on, clean),
                box_error(off, clean), box_error(noisy, clean),
                synth::rel_mse(on, clean), synth::rel_mse(off, clean),
                synth::rel_mse(noisy, clean));
    EXPECT_NEAR(level(on) / level(noisy), 1.0, 0.02);
    EXPECT_LT(std::abs(level(on) / level(noisy) - 1.0), 0.5 * std::abs(level(off) / level(noisy) - 1.0));
    EXPECT_LT(box_error(on, clean), 0.7 * box_error(off, clean));
    EXPECT_LT(5.0 * synth::rel_mse(on, clean), synth::rel_mse(noisy, clean));
}


// A noise-free region beside a noisy one: the correction, which reads the
// blur of both, moves no pixel of the clean region further from the input
// (there the truth) than the filter alone leaves it, by more than 0.5 %
// (0.17 % measured): each pixel moves by at most its own noise. The two
// columns at the boundary are the exception: their own noise estimate
// (their 3x3) reads the noisy side (the last one moves 2.4 %).
TEST(EnergyCorrection, CleanRegionIsNotMadeWorse)
{
    ImageBuf clean, noisy, albedo;
    skewed_light(kSize / 2, clean, noisy, albedo);
    const ImageBuf off = run(noisy, albedo, 0);
    const ImageBuf on  = run(noisy, albedo, 12);
    double worse = -1.0, changed = 0.0;
    int worst_x = -1;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize / 2 - 2; ++x) {
            const double want = synth::luminance(clean, x, y);
            const double e_on  = std::abs(synth::luminance(on, x, y) - want) / want;
            const double e_off = std::abs(synth::luminance(off, x, y) - want) / want;
            if (e_on - e_off > worse)
                worst_x = x;
            worse   = std::max(worse, e_on - e_off);
            changed = std::max(changed, std::abs(synth::luminance(on, x, y)
                                                 - synth::luminance(off, x, y)) / want);
        }
    std::printf("  clean half: largest change by the correction %.2g; largest "
                "increase of a pixel's error %.2g (column %d); relMSE %.3g (%.3g without)\n",
                changed, worse, worst_x, synth::rel_mse(on, clean, 0, kSize / 2, 0, kSize),
                synth::rel_mse(off, clean, 0, kSize / 2, 0, kSize));
    EXPECT_LT(worse, 0.005);
}
