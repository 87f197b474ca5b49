// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The diagnostic maps (FilterOptions::diagnostics, --diagnostics,
// --diagnostics-png) as a lighter reads them: the remaining error is high
// where the frame had fewer samples; asking for the maps changes nothing
// else; they do not depend on the threads; the command and recipes add
// them to the output, and the picture has its legend.

#include <cmath>
#include <string>
#include <vector>

#include <OpenImageIO/imagebufalgo.h>

#include <zdenoise/zdenoise.h>

#include "cli_test.h"
#include "synthetic_scenes.h"

using namespace OIIO;
using namespace cli_test;

namespace {

/// The mean of channel `c` of `img` over columns [x0, x1).
double
mean_channel(const ImageBuf& img, int c, int x0, int x1)
{
    double sum = 0.0;
    int n      = 0;
    for (int y = 0; y < img.spec().height; ++y)
        for (int x = x0; x < x1; ++x, ++n)
            sum += img.getchannel(x, y, 0, c);
    return sum / n;
}

/// A fine texture under smooth light whose left half was rendered with 4
/// samples a pixel and its right half with 64.
synth::Scene
half_4_half_64(int w, int h)
{
    synth::Scene few  = synth::fine_texture(w, h, { 4, 7 });
    synth::Scene many = synth::fine_texture(w, h, { 64, 7 });
    ROI right         = many.noisy.roi();
    right.xbegin      = w / 2;
    ImageBuf right_half = ImageBufAlgo::cut(many.noisy, right);
    ImageBufAlgo::paste(few.noisy, w / 2, 0, 0, 0, right_half);
    return few;
}

}  // namespace


TEST(Diagnostics, RemainingErrorIsHigherWhereTheFrameHadFewerSamples)
{
    const int w = 128, h = 64;
    synth::Scene s = half_4_half_64(w, h);
    ImageBuf maps;
    zdenoise::FilterOptions opt;
    opt.diagnostics = &maps;
    ImageBuf out    = zdenoise::denoise(s.noisy, s.albedo, {}, opt);
    ASSERT_FALSE(out.has_error()) << out.geterror();
    ASSERT_EQ(maps.nchannels(), 4);
    EXPECT_EQ(maps.spec().channelnames, zdenoise::diagnostic_channels());
    // Away from the seam (windows reach 2 r_max across it).
    const int few0 = 0, few1 = w / 2 - 32, many0 = w / 2 + 32, many1 = w;
    const double noise_few = mean_channel(maps, 2, few0, few1);
    const double noise_many = mean_channel(maps, 2, many0, many1);
    const double error_few = mean_channel(maps, 3, few0, few1);
    const double error_many = mean_channel(maps, 3, many0, many1);
    const double radius_few = mean_channel(maps, 0, few0, few1);
    const double radius_many = mean_channel(maps, 0, many0, many1);
    std::printf("  noise 4 spp %.4f, 64 spp %.4f; remaining error %.4f, %.4f; "
                "radius %.2f, %.2f\n",
                noise_few, noise_many, error_few, error_many, radius_few, radius_many);
    // The noise is estimated from the image; the scene's is known: a pixel
    // is the mean of spp exponential samples, relative deviation
    // 1/sqrt(spp) (measured: 0.509 and 0.124).
    EXPECT_NEAR(noise_few, 1.0 / std::sqrt(4.0), 0.1 / std::sqrt(4.0));
    EXPECT_NEAR(noise_many, 1.0 / std::sqrt(64.0), 0.1 / std::sqrt(64.0));
    // The windows grow until their predicted noise reaches eta: larger
    // where the input has 4x the noise (measured: 13.1 and 4.1).
    EXPECT_GT(radius_few, 2.0 * radius_many);
    // The filter evens much of it out (its windows grow larger on the
    // left, towards the same target), but the error left is still higher
    // there (measured: 0.027 and 0.017)...
    EXPECT_GT(error_few, 1.25 * error_many);
    // ... as it truly is: the output's relMSE is higher there too (0.0036
    // and 0.0005: the map's eta is the noise part of the error only, and
    // the bias of low sample counts is not in it; docs/DIAGNOSTICS.md).
    EXPECT_GT(synth::rel_mse(out, s.clean, few0, few1, 0, h),
              2.0 * synth::rel_mse(out, s.clean, many0, many1, 0, h));
    // Stop codes are what the filter can do.
    for (int y = 0; y < h; y += 5)
        for (int x = 0; x < w; x += 3) {
            const float code = maps.getchannel(x, y, 0, 1);
            EXPECT_TRUE(code == 1.0f || code == 2.0f || code == 3.0f) << code;
        }
}


TEST(Diagnostics, RadiusIsSmallAtAnEdgeAndLargeOnFlatLight)
{
    // A hard shadow edge at 16 spp: the windows at the edge stop there
    // (stop code 3) and stay small; those on the flat light either side
    // grow (measured: mean radius 4.4 at the edge, 8.7 and 8.9 beyond
    // 16 px either side).
    const synth::Scene s = synth::shadow_edge(128, 48, { 16, 5 });
    ImageBuf maps;
    zdenoise::FilterOptions opt;
    opt.diagnostics = &maps;
    const ImageBuf out = zdenoise::denoise(s.noisy, s.albedo, {}, opt);
    ASSERT_FALSE(out.has_error()) << out.geterror();
    const int e = s.edge_x;
    const double at_edge = mean_channel(maps, 0, e - 2, e + 2);
    const double lit = mean_channel(maps, 0, 8, e - 16);
    const double shadow = mean_channel(maps, 0, e + 16, 120);
    std::printf("  radius at the edge %.2f, lit %.2f, shadow %.2f\n", at_edge, lit, shadow);
    EXPECT_LT(at_edge, 0.7 * lit);
    EXPECT_LT(at_edge, 0.7 * shadow);
    EXPECT_GT(mean_channel(maps, 1, e - 2, e + 2), 2.5) << "mostly edge stops there";
    EXPECT_LT(mean_channel(maps, 1, 8, e - 16), 1.1) << "quality stops on the flat light";
}


TEST(Diagnostics, ChangeNothingAndDoNotDependOnThreadsOrTiles)
{
    synth::Scene s = half_4_half_64(96, 80);
    ImageBuf plain = zdenoise::denoise(s.noisy, s.albedo);
    ImageBuf maps1, maps2, strip_maps;
    zdenoise::FilterOptions opt;
    opt.diagnostics = &maps1;
    ImageBuf with1  = zdenoise::denoise(s.noisy, s.albedo, {}, opt, nullptr,
                                        {}, 1);
    opt.diagnostics = &maps2;
    ImageBuf with2  = zdenoise::denoise(s.noisy, s.albedo, {}, opt, nullptr,
                                        {}, 2);
    EXPECT_TRUE(synth::same_pixels(plain, with1));
    EXPECT_TRUE(synth::same_pixels(with1, with2));
    EXPECT_TRUE(synth::same_pixels(maps1, maps2));
    // A strip of rows computed alone has the whole image's maps there.
    ROI strip   = s.noisy.roi();
    strip.ybegin = 30;
    strip.yend   = 50;
    opt.diagnostics = &strip_maps;
    ImageBuf part   = zdenoise::denoise(s.noisy, s.albedo, {}, opt, nullptr,
                                        strip);
    ASSERT_FALSE(part.has_error()) << part.geterror();
    ASSERT_EQ(strip_maps.roi().ybegin, 30);
    ROI four     = strip;
    four.chbegin = 0;
    four.chend   = 4;
    EXPECT_TRUE(synth::same_pixels(ImageBufAlgo::cut(strip_maps, four),
                            ImageBufAlgo::cut(maps1, four)));
}


TEST(Diagnostics, LayersCombineTheirMaps)
{
    synth::Scene s = half_4_half_64(96, 48);
    ImageBuf half_light = ImageBufAlgo::mul(s.noisy, 0.5f);
    std::vector<zdenoise::Layer> layers(2);
    layers[0].name     = "a";
    layers[0].radiance = &half_light;
    layers[0].albedo   = &s.albedo;
    layers[1]          = layers[0];
    layers[1].name     = "b";
    ImageBuf maps, single_maps;
    zdenoise::FilterOptions opt;
    opt.diagnostics = &single_maps;
    zdenoise::denoise(half_light, s.albedo, {}, opt);
    opt.diagnostics = &maps;
    ImageBuf out    = zdenoise::layered_denoise(layers, nullptr, {}, opt);
    ASSERT_FALSE(out.has_error()) << out.geterror();
    ASSERT_EQ(maps.nchannels(), 4);
    // Two equal layers: the radius and stop of either; the relative noise
    // and error of a sum of two independent equal parts, 1/sqrt(2) of one.
    for (int y = 0; y < 48; y += 7)
        for (int x = 0; x < 96; x += 5) {
            EXPECT_NEAR(maps.getchannel(x, y, 0, 0),
                        single_maps.getchannel(x, y, 0, 0), 1e-4);
            EXPECT_EQ(maps.getchannel(x, y, 0, 1),
                      single_maps.getchannel(x, y, 0, 1));
            EXPECT_NEAR(maps.getchannel(x, y, 0, 3),
                        single_maps.getchannel(x, y, 0, 3) / std::sqrt(2.0f),
                        1e-5);
        }
}


TEST(Diagnostics, RefusesAnImageTooSmallForThem)
{
    synth::Scene s = synth::fine_texture(32, 32, { 8, 3 });
    ImageBuf maps(ImageSpec(32, 32, 2, TypeFloat));
    zdenoise::FilterOptions opt;
    opt.diagnostics = &maps;
    ImageBuf out    = zdenoise::denoise(s.noisy, s.albedo, {}, opt);
    EXPECT_TRUE(out.has_error());
    EXPECT_NE(out.geterror().find("diagnostics image needs 4 channels"),
              std::string::npos);
}


TEST_F(CliTest, DiagnosticsAddChannelsAndAPicture)
{
    const std::string in = kSourceDir
                           + "/share/samples/cornell_textured_spp16_crop.exr";
    RunResult r = run("--in '" + in + "' -o '" + path("plain.exr") + "'");
    ASSERT_EQ(r.status, 0) << r.err;
    r = run("--in '" + in + "' -o '" + path("maps.exr")
            + "' --diagnostics --diagnostics-png '" + path("error.png") + "'");
    ASSERT_EQ(r.status, 0) << r.err;
    ImageBuf plain(path("plain.exr")), maps(path("maps.exr"));
    ASSERT_TRUE(maps.read(0, 0, true, TypeFloat)) << maps.geterror();
    ASSERT_TRUE(plain.read(0, 0, true, TypeFloat)) << plain.geterror();
    ASSERT_EQ(maps.nchannels(), plain.nchannels() + 4);
    for (const std::string& n : zdenoise::diagnostic_channels())
        EXPECT_GE(maps.spec().channelindex("zdenoise." + n), 0) << n;
    // Every other channel as without the maps.
    for (int c = 0; c < plain.nchannels(); ++c) {
        const int m = maps.spec().channelindex(plain.spec().channelnames[c]);
        ASSERT_GE(m, 0);
        for (int y = 0; y < plain.spec().height; y += 3)
            for (int x = 0; x < plain.spec().width; x += 3)
                ASSERT_EQ(maps.getchannel(x, y, 0, m),
                          plain.getchannel(x, y, 0, c))
                    << plain.spec().channelnames[c];
    }
    // The maps' values, on a frame whose noise is known: a fine texture at
    // 16 spp, each pixel the mean of 16 exponential samples (relative
    // deviation 1/4). The noise map estimates that; the error map is the
    // predicted noise of the windows, which stop growing when it reaches
    // --eta (0.02): about that where they stopped so (stop code 1; a pixel
    // mixes the windows that reached it, a few stopped otherwise), and
    // more than half of it, since the radius before (half as large) had
    // not reached it (measured: noise 0.258, error 0.0201).
    const synth::Scene s = synth::fine_texture(96, 64, { 16, 9 });
    ASSERT_TRUE(s.noisy.write(path("synth.exr"))) << s.noisy.geterror();
    ASSERT_TRUE(s.albedo.write(path("synth_albedo.exr"))) << s.albedo.geterror();
    r = run("--in '" + path("synth.exr") + "' --albedo '" + path("synth_albedo.exr")
            + "' -o '" + path("synth_maps.exr") + "' --diagnostics");
    ASSERT_EQ(r.status, 0) << r.err;
    ImageBuf synth_maps(path("synth_maps.exr"));
    ASSERT_TRUE(synth_maps.read(0, 0, true, TypeFloat)) << synth_maps.geterror();
    const int stop = synth_maps.spec().channelindex("zdenoise.stop");
    const int noise = synth_maps.spec().channelindex("zdenoise.noise");
    const int error = synth_maps.spec().channelindex("zdenoise.error");
    double noise_mean = 0.0, error_mean = 0.0;
    int quality = 0;
    for (int y = 0; y < s.h; ++y)
        for (int x = 0; x < s.w; ++x) {
            noise_mean += synth_maps.getchannel(x, y, 0, noise);
            if (synth_maps.getchannel(x, y, 0, stop) == 1.0f) {
                error_mean += synth_maps.getchannel(x, y, 0, error);
                ++quality;
            }
        }
    noise_mean /= double(s.w) * s.h;
    error_mean /= quality;
    std::printf("  16 spp: noise %.4f (1/4 true), error %.4f where the windows "
                "stopped at eta (%d of %d pixels)\n",
                noise_mean, error_mean, quality, s.w * s.h);
    EXPECT_NEAR(noise_mean, 0.25, 0.025);
    EXPECT_GT(quality, s.w * s.h / 2);
    EXPECT_GT(error_mean, 0.5 * 0.02);
    EXPECT_LT(error_mean, 1.2 * 0.02);

    // The picture: the frame, with the legend in a band below it.
    ImageBuf png(path("error.png"));
    ASSERT_TRUE(png.read()) << png.geterror();
    EXPECT_EQ(png.spec().width, plain.spec().width);
    EXPECT_GT(png.spec().height, plain.spec().height + 20);
    EXPECT_EQ(png.spec().nchannels, 3);
    // The legend's bar runs from dark (low error) to bright (high).
    const int bar_y = plain.spec().height + 10;
    float dark[3], bright[3];
    png.getpixel(8, bar_y, dark);
    png.getpixel(png.spec().width - 8, bar_y, bright);
    EXPECT_LT(dark[0] + dark[1] + dark[2], bright[0] + bright[1] + bright[2]);
    EXPECT_EQ(files(), (std::vector<std::string> { "error.png", "maps.exr", "plain.exr",
                                                   "synth.exr", "synth_albedo.exr",
                                                   "synth_maps.exr" }));
}


TEST_F(CliTest, DiagnosticsPictureOfASequenceNeedsAFramePattern)
{
    RunResult r = run("--in '" + path("shot.#.exr") + "' -o '"
                      + path("clean.#.exr") + "' --frames 1-2 "
                      + "--diagnostics-png '" + path("error.png") + "'");
    expect_one_line_error(r, "--diagnostics-png");
    EXPECT_NE(r.err.find("error.#.png"), std::string::npos) << r.err;
}
