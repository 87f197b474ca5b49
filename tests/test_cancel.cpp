// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// FilterOptions::cancel as a program meets it: a flag set before the call
// stops it at once, a flag set partway (from the progress report, so that
// the point is the same on every run) stops it within a block, with the
// error "zdenoise: cancelled" and no result in dst; a flag given and never
// set changes no bit of the result. The time a stop takes is measured, not
// tested (bench/cancel_latency.py).

#include <algorithm>
#include <atomic>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/imagebufalgo.h>

#include <zdenoise/selection.h>
#include <zdenoise/zdenoise.h>

#include "synthetic_scenes.h"

using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

const std::string kCancelled = "zdenoise: cancelled";

/// A scene of many blocks of centres (progress reported often), guides
/// that vary from pixel to pixel.
synth::Scene
test_scene()
{
    synth::Scene s = synth::staircase(192, 160, 8, { 8, 11 });
    synth::vary_guides(s, true);
    return s;
}

zdenoise::Guides
guides_of(const synth::Scene& s)
{
    zdenoise::Guides g;
    g.normal = &s.normal;
    g.depth  = &s.depth;
    return g;
}

/// What the progress report saw: every fraction, and how many came after
/// the report that set the flag.
struct ProgressLog {
    std::vector<float> fractions;
    int after_cancel = -1;  ///< -1: the flag was never set
};

/// Options whose progress sets `flag` at the first report at or beyond
/// `at` (never when `at` > 1), logging into `log`.
zdenoise::FilterOptions
cancelling_at(float at, std::atomic<bool>& flag, ProgressLog& log, int select)
{
    zdenoise::FilterOptions opt;
    opt.select   = select;
    opt.cancel   = &flag;
    opt.progress = [at, &flag, &log](float f) {
        log.fractions.push_back(f);
        if (log.after_cancel >= 0)
            ++log.after_cancel;
        else if (f >= at) {
            flag = true;
            log.after_cancel = 0;
        }
    };
    return opt;
}

/// Two layers of the scene (its light split 60 / 40), as a layered render.
std::vector<zdenoise::Layer>
two_layers(const synth::Scene& s, ImageBuf& first, ImageBuf& second)
{
    first  = OIIO::ImageBufAlgo::mul(s.noisy, 0.6f);
    second = OIIO::ImageBufAlgo::mul(s.noisy, 0.4f);
    zdenoise::Layer a, b;
    a.name     = "first";
    a.radiance = &first;
    a.albedo   = &s.albedo;
    b.name     = "second";
    b.radiance = &second;
    b.albedo   = &s.albedo;
    return { a, b };
}

/// Every pixel of img's data window is 0 in every channel.
bool
all_zero(const ImageBuf& img)
{
    const std::vector<float> px = synth::pixels(img);
    return std::all_of(px.begin(), px.end(), [](float v) { return v == 0.0f; });
}

}  // namespace


TEST(Cancel, FlagSetBeforeTheCallReturnsAtOnceWithTheCancelledError)
{
    const synth::Scene s = test_scene();
    std::atomic<bool> flag { true };
    ProgressLog log;
    zdenoise::FilterOptions opt = cancelling_at(2.0f, flag, log, 1);

    ImageBuf filtered = zdenoise::regression_filter(s.noisy, s.albedo, {}, opt);
    EXPECT_EQ(filtered.geterror(), kCancelled);
    EXPECT_FALSE(filtered.initialized()) << "no image is made";

    ImageBuf denoised;
    EXPECT_FALSE(zdenoise::denoise(denoised, s.noisy, s.albedo, guides_of(s), opt));
    EXPECT_EQ(denoised.geterror(), kCancelled);
    EXPECT_FALSE(denoised.initialized());

    ImageBuf first, second, sum;
    EXPECT_FALSE(zdenoise::layered_denoise(sum, two_layers(s, first, second),
                                           nullptr, guides_of(s), opt));
    EXPECT_EQ(sum.geterror(), kCancelled);

    zdenoise::FeatureRegressionOptions fo;
    fo.cancel = &flag;
    ImageBuf pilot(OIIO::ImageSpec(s.w, s.h, 4, OIIO::TypeFloat)), regressed;
    EXPECT_FALSE(zdenoise::feature_regression(regressed, s.noisy, s.albedo,
                                              pilot, {}, fo));
    EXPECT_EQ(regressed.geterror(), kCancelled);

    EXPECT_TRUE(log.fractions.empty()) << "no work was begun";
}


TEST(Cancel, FlagSetPartwayStopsTheRunWithinABlock)
{
    const synth::Scene s = test_scene();
    for (const int select : { 0, 1 }) {
        std::atomic<bool> unset { false };
        ProgressLog whole;
        ASSERT_FALSE(zdenoise::denoise(s.noisy, s.albedo, guides_of(s),
                                       cancelling_at(2.0f, unset, whole, select),
                                       nullptr, {}, 2)
                         .has_error());
        for (const float at : { 0.0f, 0.3f }) {
            SCOPED_TRACE(testing::Message() << "select " << select << ", set at "
                                            << at);
            std::atomic<bool> flag { false };
            ProgressLog log;
            const zdenoise::FilterOptions opt = cancelling_at(at, flag, log, select);
            // The caller's image: its pixels must not be left half filtered.
            ImageBuf dst(s.noisy.spec());
            OIIO::ImageBufAlgo::copy(dst, s.noisy);
            EXPECT_FALSE(zdenoise::denoise(dst, s.noisy, s.albedo, guides_of(s),
                                           opt, nullptr, {}, 2));
            EXPECT_EQ(dst.geterror(), kCancelled);
            EXPECT_TRUE(all_zero(dst)) << "the caller's pixels are set to 0";
            ASSERT_GE(log.after_cancel, 0) << "the flag was set";
            // Blocks already begun on the other thread may still report.
            EXPECT_LE(log.after_cancel, 2);
            EXPECT_LT(*std::max_element(log.fractions.begin(), log.fractions.end()),
                      1.0f)
                << "the run never finished";
            EXPECT_LT(log.fractions.size() + 4, whole.fractions.size())
                << "a whole run reports once a block";
        }
    }
}


TEST(Cancel, FlagSetInTheFirstLayerStopsTheLayeredDenoise)
{
    const synth::Scene s = test_scene();
    ImageBuf first, second;
    const std::vector<zdenoise::Layer> layers = two_layers(s, first, second);

    std::atomic<bool> unset { false };
    ProgressLog whole;
    ImageBuf full;
    ASSERT_TRUE(zdenoise::layered_denoise(full, layers, nullptr, guides_of(s),
                                          cancelling_at(2.0f, unset, whole, 1),
                                          nullptr, {}, 2))
        << full.geterror();

    std::atomic<bool> flag { false };
    ProgressLog log;
    ImageBuf sum;
    EXPECT_FALSE(zdenoise::layered_denoise(sum, layers, nullptr, guides_of(s),
                                           cancelling_at(0.15f, flag, log, 1),
                                           nullptr, {}, 2));
    EXPECT_EQ(sum.geterror(), kCancelled) << "one line, not the layer's";
    EXPECT_FALSE(sum.initialized()) << "no sum is made";
    ASSERT_GE(log.after_cancel, 0);
    EXPECT_LE(log.after_cancel, 2);
    // Each of the two layers reports its half of the whole: the first
    // stopped, the second never began.
    EXPECT_LT(log.fractions.size() * 3, whole.fractions.size());
    EXPECT_LT(*std::max_element(log.fractions.begin(), log.fractions.end()), 0.5f);
}


TEST(Cancel, FlagNeverSetChangesNoBit)
{
    const synth::Scene s = test_scene();
    for (const int select : { 0, 1 }) {
        SCOPED_TRACE(testing::Message() << "select " << select);
        zdenoise::FilterOptions plain;
        plain.select = select;
        zdenoise::FilterOptions flagged = plain;
        std::atomic<bool> flag { false };
        flagged.cancel = &flag;

        zdenoise::FilterStats plain_stats, flagged_stats;
        const ImageBuf expect = zdenoise::denoise(s.noisy, s.albedo, guides_of(s),
                                                  plain, &plain_stats, {}, 2);
        const ImageBuf got = zdenoise::denoise(s.noisy, s.albedo, guides_of(s),
                                               flagged, &flagged_stats, {}, 2);
        ASSERT_FALSE(got.has_error()) << got.geterror();
        EXPECT_TRUE(synth::same_pixels(got, expect));
        EXPECT_EQ(flagged_stats.windows, plain_stats.windows);
        EXPECT_EQ(flagged_stats.radius_sum, plain_stats.radius_sum);

        ImageBuf first, second;
        const std::vector<zdenoise::Layer> layers = two_layers(s, first, second);
        const ImageBuf layered = zdenoise::layered_denoise(layers, nullptr,
                                                           guides_of(s), plain);
        const ImageBuf layered_flagged
            = zdenoise::layered_denoise(layers, nullptr, guides_of(s), flagged);
        ASSERT_FALSE(layered_flagged.has_error()) << layered_flagged.geterror();
        EXPECT_TRUE(synth::same_pixels(layered_flagged, layered));
    }
}
