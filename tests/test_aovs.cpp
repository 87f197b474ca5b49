// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// --aov NAME (docs/AOVS.md): on a Cycles-style file whose beauty holds a
// noisy AOV (light on a floor with a fine checker texture: a volume, an
// LPE) and a noise-free emitter's Emit, the AOV comes out with its noise
// reduced at least 4x, its texture kept, its light kept, nothing negative,
// the emitter's pixels exactly as rendered; channels not named are copied;
// the result does not depend on the strips; a wrong name is a one-line
// error naming it.

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>

#include "cli_test.h"

using namespace OIIO;

namespace {

constexpr int W = 96, H = 64;
constexpr int kEmitter = 80;  ///< columns from here on are a lamp

/// The floor's albedo: a 2-px checker in the lower right, else 0.5.
float
albedo(int x, int y)
{
    if (x >= 48 && x < kEmitter && y >= 32)
        return ((x / 2 + y / 2) % 2) ? 0.8f : 0.2f;
    return 0.5f;
}

struct AovFile {
    ImageBuf clean, noisy, emit;
};

/// A Cycles-style file: the beauty (the AOV's light plus another light on
/// the floor, and a lamp of constant emission right of kEmitter), its
/// albedo (the lamp's: its emission, as Cycles'), a plane's normal and
/// depth, the AOV ViewLayer.Volume (noisy, relative deviation `sigma`),
/// the lamp's ViewLayer.Emit and ViewLayer.Other (not to be touched).
AovFile
write_file(const std::string& file, float sigma, uint32_t seed)
{
    std::mt19937 rng(seed);
    std::gamma_distribution<float> gamma(1.0f / (sigma * sigma), sigma * sigma);
    const std::vector<std::string> names
        = { "ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
            "ViewLayer.Combined.A", "ViewLayer.Denoising Albedo.R",
            "ViewLayer.Denoising Albedo.G", "ViewLayer.Denoising Albedo.B",
            "ViewLayer.Denoising Normal.X", "ViewLayer.Denoising Normal.Y",
            "ViewLayer.Denoising Normal.Z", "ViewLayer.Denoising Depth.Z",
            "ViewLayer.Volume.R", "ViewLayer.Volume.G", "ViewLayer.Volume.B",
            "ViewLayer.Emit.R", "ViewLayer.Emit.G", "ViewLayer.Emit.B",
            "ViewLayer.Other.R", "ViewLayer.Other.G", "ViewLayer.Other.B" };
    ImageSpec spec(W, H, int(names.size()), TypeFloat);
    spec.channelnames  = names;
    spec.alpha_channel = 3;
    ImageBuf img(spec);
    AovFile f;
    for (ImageBuf* b : { &f.clean, &f.noisy, &f.emit })
        b->reset(ImageSpec(W, H, 3, TypeFloat));
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const bool lamp = x >= kEmitter;
            const float a = lamp ? 4.0f : albedo(x, y);
            const float light = 0.4f + 0.4f * float(y) / H;  // the AOV's, smooth
            const float c = lamp ? 0.0f : a * light;
            const float n = c * gamma(rng);
            const float other = lamp ? 0.0f : a * 0.3f * gamma(rng);
            const float e = lamp ? 4.0f : 0.0f;
            const float b = n + other + e;
            const float px[20] = { b, b, b, 1.0f, a, a, a, 0.0f, 0.0f, 1.0f, 5.0f,
                                   n, n, n, e, e, e, float(x), float(y), n };
            img.setpixel(x, y, px, 20);
            const float cc[3] = { c, c, c }, nn[3] = { n, n, n }, ee[3] = { e, e, e };
            f.clean.setpixel(x, y, cc, 3);
            f.noisy.setpixel(x, y, nn, 3);
            f.emit.setpixel(x, y, ee, 3);
        }
    EXPECT_TRUE(img.write(file)) << img.geterror();
    return f;
}

ImageBuf
layer_of(const std::string& file, const std::string& layer)
{
    ImageBuf in(file);
    EXPECT_TRUE(in.read(0, 0, true, TypeFloat)) << in.geterror();
    ImageBuf out;
    ImageBufAlgo::channels(out, in, 3,
                           { in.spec().channelindex(layer + ".R"),
                             in.spec().channelindex(layer + ".G"),
                             in.spec().channelindex(layer + ".B") });
    return out;
}

/// relMSE of channel 0 over columns [x0, x1) and rows [y0, y1).
double
relmse(const ImageBuf& img, const ImageBuf& ref, int x0, int x1, int y0, int y1)
{
    double sum = 0.0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            float a, r;
            img.getpixel(x, y, &a, 1);
            ref.getpixel(x, y, &r, 1);
            sum += double(a - r) * (a - r) / (double(r) * r + 1e-2);
        }
    return sum / (double(x1 - x0) * (y1 - y0));
}

class AovCli : public cli_test::CliTest {};

}  // namespace


TEST_F(AovCli, ANamedAovIsDenoisedItsTextureKeptAndTheRestCopied)
{
    const AovFile f = write_file(path("in.exr"), 0.5f, 7);
    const cli_test::RunResult res = run("--in " + path("in.exr") + " -o " + path("out.exr")
                                        + " --aov Volume --aov Emit -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("aovs      ViewLayer.Volume, ViewLayer.Emit split from the "
                           "denoised beauty"),
              std::string::npos)
        << res.out;
    const ImageBuf out = layer_of(path("out.exr"), "ViewLayer.Volume");

    const double smooth_before = relmse(f.noisy, f.clean, 2, 46, 2, 30);
    const double smooth_after  = relmse(out, f.clean, 2, 46, 2, 30);
    const double texture_before = relmse(f.noisy, f.clean, 50, kEmitter - 2, 34, H - 2);
    const double texture_after  = relmse(out, f.clean, 50, kEmitter - 2, 34, H - 2);
    std::printf("  relMSE smooth %.5f -> %.5f, textured %.5f -> %.5f\n", smooth_before,
                smooth_after, texture_before, texture_after);
    EXPECT_LT(smooth_after, smooth_before / 4.0) << "noise reduced at least 4x";
    EXPECT_LT(texture_after, texture_before / 2.0) << "the 2-px texture is kept";

    const auto in_stats  = ImageBufAlgo::computePixelStats(f.noisy);
    const auto out_stats = ImageBufAlgo::computePixelStats(out);
    EXPECT_NEAR(out_stats.avg[0] / in_stats.avg[0], 1.0, 0.01) << "light kept within 1 %";
    EXPECT_GE(out_stats.min[0], 0.0f);

    // The lamp's Emit is noise-free: left exactly as rendered.
    EXPECT_EQ(ImageBufAlgo::compare(layer_of(path("out.exr"), "ViewLayer.Emit"), f.emit, 0.0f,
                                    0.0f)
                  .nfail,
              0u)
        << "a clean AOV is left as it is";
    EXPECT_EQ(ImageBufAlgo::compare(layer_of(path("out.exr"), "ViewLayer.Other"),
                                    layer_of(path("in.exr"), "ViewLayer.Other"), 0.0f, 0.0f)
                  .nfail,
              0u)
        << "a channel not named is copied";

    ASSERT_EQ(run("--in " + path("in.exr") + " -o " + path("strips.exr")
                  + " --aov ViewLayer.Volume --aov Emit --tile 8")
                  .status,
              0);
    ImageBuf whole(path("out.exr")), strips(path("strips.exr"));
    EXPECT_EQ(ImageBufAlgo::compare(whole, strips, 0.0f, 0.0f).nfail, 0u)
        << "strips of 8 rows give the whole frame's";
}


TEST_F(AovCli, AWrongAovIsAOneLineErrorNamingIt)
{
    write_file(path("in.exr"), 0.5f, 3);
    const std::string base = "--in " + path("in.exr") + " -o " + path("out.exr");
    cli_test::expect_one_line_error(run(base + " --aov Fog"),
                                    "--aov Fog: '" + path("in.exr")
                                        + "' has no channels Fog.R,G,B");
    cli_test::expect_one_line_error(run(base + " --aov Combined"),
                                    "ViewLayer.Combined is the beauty");
    cli_test::expect_one_line_error(run(base + " --aov Volume --aov ViewLayer.Volume"),
                                    "ViewLayer.Volume is given twice");
    EXPECT_FALSE(Filesystem::exists(path("out.exr"))) << "no output on an error";
}
