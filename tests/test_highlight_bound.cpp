// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// No highlight the render does not have (docs/FILTER.md section 1a,
// bound_highlights()): a noisy albedo spike does not remodulate its
// neighbours' light into a highlight, and the bound is, channel by
// channel, the brightest input value within kHighlightRadius (checked
// against a plain loop, at every thread count).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <zdenoise/highlights.h>
#include <zdenoise/zdenoise.h>

#include "reference_filter.h"
#include "synthetic_scenes.h"

using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

constexpr int kSize = 64;

using zdenoise_ref::RefImage;

}  // namespace


// Cycles' albedo at a rough metal is a Monte Carlo estimate that adds the
// emission its paths meet: here 3 % of the pixels' albedos are 10-50x the
// surface's 0.5, while the radiance is the surface's. Remodulated by them,
// the neighbours' filtered light would become highlights the render does
// not show anywhere near.
TEST(HighlightBound, ANoisyAlbedoSpikeMakesNoHighlight)
{
    std::vector<float> radiance(3 * kSize * kSize), albedo(radiance.size(), 0.5f);
    std::mt19937 rng(77);
    std::normal_distribution<float> noise(0.0f, 0.1f);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (size_t i = 0; i < radiance.size(); i += 3) {
        const float r = 0.5f * (1.0f + noise(rng));
        const float a = u(rng) < 0.03f ? 5.0f + 20.0f * u(rng) : 0.5f;
        for (int c = 0; c < 3; ++c) {
            radiance[i + size_t(c)] = r;
            albedo[i + size_t(c)]   = a;
        }
    }
    const ImageBuf rad = synth::make_image(kSize, kSize, 3, radiance);
    const ImageBuf alb = synth::make_image(kSize, kSize, 3, albedo);
    ImageBuf out = zdenoise::denoise(rad, alb, zdenoise::Guides{});
    ASSERT_FALSE(out.has_error()) << out.geterror();
    const RefImage lib = zdenoise_ref::from_imagebuf(out);
    const RefImage bounded
        = zdenoise_ref::bound_highlights(lib, zdenoise_ref::from_imagebuf(rad));
    float brightest = 0.0f;
    for (size_t i = 0; i < lib.px.size(); ++i) {
        ASSERT_EQ(lib.px[i], bounded.px[i]) << "value " << i << " above the input around it";
        brightest = std::max(brightest, lib.px[i]);
    }
    EXPECT_LT(brightest, 1.0f) << "twice the light";
    // The noise is still removed.
    const ImageBuf truth = synth::make_image(kSize, kSize, 3, std::vector<float>(radiance.size(), 0.5f));
    EXPECT_LT(synth::rel_mse(out, truth), 0.3 * synth::rel_mse(rad, truth));
}


TEST(HighlightBound, TheBoundIsTheBrightestInputWithinFourPixels)
{
    std::vector<float> radiance(3 * kSize * kSize), denoised(radiance.size());
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 2.0f);
    for (size_t i = 0; i < radiance.size(); ++i) {
        radiance[i] = u(rng);
        denoised[i] = u(rng) * 1.5f;
    }
    // Non-finite input is no bound; a pixel with none around keeps its value.
    for (int y = 40; y < 52; ++y)
        for (int x = 40; x < 52; ++x)
            for (int c = 0; c < 3; ++c)
                radiance[3 * (size_t(y) * kSize + size_t(x)) + size_t(c)]
                    = (x + y) % 2 ? std::numeric_limits<float>::quiet_NaN()
                                  : std::numeric_limits<float>::infinity();
    denoised[3 * (size_t(10) * kSize + 10)] = std::numeric_limits<float>::quiet_NaN();
    const ImageBuf rad = synth::make_image(kSize, kSize, 3, radiance);
    const RefImage expect = zdenoise_ref::bound_highlights(
        zdenoise_ref::from_imagebuf(synth::make_image(kSize, kSize, 3, denoised)),
        zdenoise_ref::from_imagebuf(rad));
    const ROI roi(5, 60, 3, 58);
    ImageBuf reference;
    for (int nthreads : { 1, 2, 5 }) {
        ImageBuf out = synth::make_image(kSize, kSize, 3, denoised);
        ASSERT_TRUE(zdenoise::bound_highlights(out, rad, {}, roi, nthreads))
            << out.geterror();
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x)
                for (int c = 0; c < 3; ++c) {
                    const float want = roi.contains(x, y)
                                           ? expect.at(x, y, c)
                                           : denoised[3 * (size_t(y) * kSize + size_t(x)) + size_t(c)];
                    const float got = out.getchannel(x, y, 0, c);
                    if (std::isnan(want))
                        ASSERT_TRUE(std::isnan(got)) << x << "," << y;
                    else
                        ASSERT_EQ(got, want) << x << "," << y << " channel " << c;
                }
        if (reference.initialized())
            EXPECT_TRUE(synth::same_pixels(out, reference)) << nthreads << " threads";
        else
            reference = out;
    }
}


TEST(HighlightBound, BadInputsSayWhichAndWhy)
{
    const ImageBuf rad = synth::make_image(16, 16, 3, std::vector<float>(3 * 16 * 16, 1.0f));
    ImageBuf none;
    EXPECT_FALSE(zdenoise::bound_highlights(none, rad));
    EXPECT_NE(none.geterror().find("bound_highlights: dst is not initialized"), std::string::npos)
        << none.geterror();
    ImageBuf out            = synth::make_image(16, 16, 3, std::vector<float>(3 * 16 * 16, 2.0f));
    const ImageBuf small    = synth::make_image(8, 8, 3, std::vector<float>(3 * 8 * 8, 1.0f));
    EXPECT_FALSE(zdenoise::bound_highlights(out, small, rad.roi()));
    EXPECT_NE(out.geterror().find("radiance"), std::string::npos) << out.geterror();
}
