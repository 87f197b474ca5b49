// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// denoise_alpha() (include/zdenoise/alpha.h, docs/ALPHA.md): a motion-blurred
// edge's noisy coverage over transparent film comes out much closer to the
// true coverage, within [0, 1]; solid pixels (an object's inside, empty
// film) keep their coverage bit for bit, so a hard silhouette is left
// exactly as rendered; the result is the filter's on (a, a, a) over albedo
// 1, clamped, whatever the threads or the part computed. The command
// denoises a Cycles render's Combined.A by default, keeps the colour of
// pixels left uncovered as rendered, and --no-alpha copies the alpha.

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/imagebufalgo.h>

#include <zdenoise/alpha.h>

#include "cli_test.h"

using namespace OIIO;

namespace {

constexpr int W = 96, H = 48;
constexpr int kBlurBegin = 24, kBlurEnd = 64;  ///< the blurred edge's columns

/// The true coverage of an object moving right during the shutter: empty
/// film left of the blur, the object right of it, a linear ramp between.
float
true_coverage(int x)
{
    if (x < kBlurBegin)
        return 0.0f;
    if (x >= kBlurEnd)
        return 1.0f;
    return float(x - kBlurBegin + 0.5f) / float(kBlurEnd - kBlurBegin);
}

/// The coverage as a renderer estimates it from `spp` samples a pixel:
/// the share of samples that hit the object.
ImageBuf
rendered_coverage(int spp, uint32_t seed = 11)
{
    std::mt19937 rng(seed);
    ImageBuf img(ImageSpec(W, H, 1, TypeFloat));
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            std::binomial_distribution<int> hits(spp, true_coverage(x));
            const float a = float(hits(rng)) / float(spp);
            img.setpixel(x, y, &a, 1);
        }
    return img;
}

double
blur_mse(const ImageBuf& img)
{
    double sum = 0.0;
    int n      = 0;
    for (int y = 0; y < H; ++y)
        for (int x = kBlurBegin; x < kBlurEnd; ++x) {
            float a = 0.0f;
            img.getpixel(x, y, &a, 1);
            sum += (a - true_coverage(x)) * (a - true_coverage(x));
            ++n;
        }
    return sum / n;
}

float
at(const ImageBuf& img, int x, int y)
{
    float a = 0.0f;
    img.getpixel(x, y, &a, 1);
    return a;
}

}  // namespace


TEST(Alpha, MotionBlurredCoverageIsDenoisedWithinZeroAndOne)
{
    for (int spp : { 4, 16, 64 }) {
        const ImageBuf noisy = rendered_coverage(spp);
        const ImageBuf out   = zdenoise::denoise_alpha(noisy);
        ASSERT_FALSE(out.has_error()) << out.geterror();
        const double before = blur_mse(noisy), after = blur_mse(out);
        std::printf("  %d spp: coverage MSE over the blur %.5f -> %.5f (%.2fx)\n",
                    spp, before, after, after / before);
        // Issue 46 asks for at most 0.6x the noisy alpha's error.
        EXPECT_LT(after, 0.6 * before) << spp << " spp";
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const float a = at(out, x, y);
                ASSERT_TRUE(a >= 0.0f && a <= 1.0f)
                    << "coverage " << a << " at (" << x << "," << y << ")";
            }
    }
}


TEST(Alpha, SolidPixelsKeepTheirCoverageAndAHardSilhouetteIsExact)
{
    // A hard silhouette: a disc of coverage 1 on empty film, no blur.
    ImageBuf hard(ImageSpec(W, H, 1, TypeFloat));
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const float a = (x - 40) * (x - 40) + (y - 24) * (y - 24) < 15 * 15
                                ? 1.0f : 0.0f;
            hard.setpixel(x, y, &a, 1);
        }
    const ImageBuf out = zdenoise::denoise_alpha(hard);
    ASSERT_FALSE(out.has_error()) << out.geterror();
    ImageBufAlgo::CompareResults cmp = ImageBufAlgo::compare(out, hard, 0.0f, 0.0f);
    EXPECT_EQ(cmp.nfail, 0u) << "a hard silhouette must come out as rendered";

    // Beside the blur, the empty film and the object's inside stay exact.
    const ImageBuf noisy = rendered_coverage(16);
    const ImageBuf blur  = zdenoise::denoise_alpha(noisy);
    for (int y = 0; y < H; ++y)
        for (int x : { 0, kBlurBegin - 2, kBlurEnd + 1, W - 1 })
            EXPECT_EQ(at(blur, x, y), at(noisy, x, y)) << "(" << x << "," << y << ")";
}


// The plain composition the operation stands for: the filter on (a, a, a)
// over albedo 1 (no noise or depth guide), keep_structure() against the
// coverage, clamped, solid pixels kept.
TEST(Alpha, IsTheFilterOnTheCoverageClampedWithSolidPixelsKept)
{
    const ImageBuf noisy = rendered_coverage(8, 5);
    // A variance guide must be ignored (it describes the colour), and so
    // must the depth (of a partly covered pixel: the coverage's noise).
    ImageBuf variance(ImageSpec(W, H, 1, TypeFloat)), depth(ImageSpec(W, H, 1, TypeFloat));
    const float big = 100.0f;
    ImageBufAlgo::fill(variance, &big);
    std::mt19937 rng(3);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const float z = 1.0f + 4.0f * std::uniform_real_distribution<float>(0, 1)(rng);
            depth.setpixel(x, y, &z, 1);
        }
    zdenoise::Guides g;
    g.variance         = &variance;
    g.depth            = &depth;
    const ImageBuf out = zdenoise::denoise_alpha(noisy, g);
    ASSERT_FALSE(out.has_error()) << out.geterror();

    ImageBuf light(ImageSpec(W, H, 3, TypeFloat)), albedo(ImageSpec(W, H, 3, TypeFloat));
    const float one[3] = { 1.0f, 1.0f, 1.0f };
    ImageBufAlgo::fill(albedo, one);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const float a    = at(noisy, x, y);
            const float c[3] = { a, a, a };
            light.setpixel(x, y, c, 3);
        }
    zdenoise::FilterOptions coverage;
    coverage.energy_radius = 0;  // denoise_alpha(): a coverage is no light
    const ImageBuf filtered = zdenoise::keep_structure(
        light, zdenoise::denoise(light, albedo, zdenoise::Guides(), coverage));
    int solid = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const float a = at(noisy, x, y);
            bool same = true;  // this pixel and its 8 neighbours all 0 or 1
            for (int v = std::max(y - 1, 0); v < std::min(y + 2, H); ++v)
                for (int u = std::max(x - 1, 0); u < std::min(x + 2, W); ++u)
                    same = same && (at(noisy, u, v) == 0.0f || at(noisy, u, v) == 1.0f);
            float f[3];
            filtered.getpixel(x, y, f, 3);
            const float want = same ? a : std::clamp(f[0], 0.0f, 1.0f);
            solid += same;
            ASSERT_EQ(at(out, x, y), want) << "(" << x << "," << y << ")";
        }
    EXPECT_GT(solid, W * H / 3) << "the test should have solid pixels";
}


TEST(Alpha, SameResultForAnyThreadCountAndPart)
{
    const ImageBuf noisy = rendered_coverage(16, 3);
    const ImageBuf one   = zdenoise::denoise_alpha(noisy, {}, {}, {}, 1);
    const ImageBuf two   = zdenoise::denoise_alpha(noisy, {}, {}, {}, 2);
    EXPECT_EQ(ImageBufAlgo::compare(one, two, 0.0f, 0.0f).nfail, 0u);
    const ROI part(10, 70, 17, 31);
    const ImageBuf piece = zdenoise::denoise_alpha(noisy, {}, {}, part, 2);
    ASSERT_FALSE(piece.has_error()) << piece.geterror();
    for (int y = part.ybegin; y < part.yend; ++y)
        for (int x = part.xbegin; x < part.xend; ++x)
            ASSERT_EQ(at(piece, x, y), at(one, x, y)) << "(" << x << "," << y << ")";
}


namespace {

/// A Cycles render of the moving object over transparent film, `spp`
/// samples a pixel: coverage and colour (premultiplied: the hits' light)
/// from the same samples. The albedo is the object's everywhere, as an
/// auxiliary render's can be, so that the filter's light reaches the
/// empty film.
void
write_blurred_render(const std::string& file, int spp, bool solid = false)
{
    std::mt19937 rng(29);
    std::normal_distribution<float> light_noise(0.0f, 0.3f);
    ImageSpec spec(W, H, 7, TypeFloat);
    spec.channelnames = { "ViewLayer.Combined.R", "ViewLayer.Combined.G",
                          "ViewLayer.Combined.B", "ViewLayer.Combined.A",
                          "ViewLayer.Denoising Albedo.R",
                          "ViewLayer.Denoising Albedo.G",
                          "ViewLayer.Denoising Albedo.B" };
    spec.alpha_channel = 3;
    ImageBuf img(spec);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const float p = solid ? (x < W / 2 ? 0.0f : 1.0f) : true_coverage(x);
            int hits      = 0;
            float light   = 0.0f;
            for (int s = 0; s < spp; ++s)
                if (std::uniform_real_distribution<float>(0, 1)(rng) < p) {
                    ++hits;
                    light += std::max(0.6f * (1.0f + light_noise(rng)), 0.0f);
                }
            const float a = float(hits) / float(spp), l = light / float(spp);
            const float px[7] = { l, 0.8f * l, 0.6f * l, a, 0.5f, 0.4f, 0.3f };
            img.setpixel(x, y, px, 7);
        }
    ASSERT_TRUE(img.write(file)) << img.geterror();
}

ImageBuf
read_float(const std::string& file)
{
    ImageBuf img(file);
    EXPECT_TRUE(img.read(0, 0, true, TypeFloat)) << img.geterror();
    return img;
}

class AlphaCli : public cli_test::CliTest {};

}  // namespace


TEST_F(AlphaCli, ACyclesAlphaIsDenoisedAndUncoveredPixelsKeepTheirColour)
{
    write_blurred_render(path("blur.exr"), 16);
    const cli_test::RunResult res = run("--in " + path("blur.exr") + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("alpha     '" + path("blur.exr")
                           + "' channel ViewLayer.Combined.A denoised"),
              std::string::npos)
        << res.out;
    ASSERT_EQ(run("--in " + path("blur.exr") + " -o " + path("copied.exr") + " --no-alpha")
                  .status,
              0);
    const ImageBuf in = read_float(path("blur.exr")), out = read_float(path("out.exr")),
                   copied = read_float(path("copied.exr"));
    ImageBuf a_in, a_out, a_copied;
    ImageBufAlgo::channels(a_in, in, 1, { 3 });
    ImageBufAlgo::channels(a_out, out, 1, { 3 });
    ImageBufAlgo::channels(a_copied, copied, 1, { 3 });
    const double before = blur_mse(a_in), after = blur_mse(a_out);
    std::printf("  command, 16 spp: alpha MSE over the blur %.5f -> %.5f\n", before, after);
    EXPECT_LT(after, 0.6 * before);
    EXPECT_EQ(ImageBufAlgo::compare(a_copied, a_in, 0.0f, 0.0f).nfail, 0u)
        << "--no-alpha copies the alpha";
    int uncovered = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            float o[7], i[7], c[7];
            out.getpixel(x, y, o, 7);
            in.getpixel(x, y, i, 7);
            copied.getpixel(x, y, c, 7);
            ASSERT_TRUE(o[3] >= 0.0f && o[3] <= 1.0f) << "(" << x << "," << y << ")";
            for (int k = 0; k < 3; ++k)
                if (o[3] == 0.0f) {
                    ++uncovered;
                    ASSERT_EQ(o[k], i[k]) << "uncovered (" << x << "," << y << ")";
                } else {
                    ASSERT_EQ(o[k], c[k]) << "the colour of a covered pixel is the "
                                             "filter's, alpha or not ("
                                          << x << "," << y << ")";
                }
        }
    EXPECT_GT(uncovered, W * H / 4) << "the empty film is uncovered";

    ASSERT_EQ(run("--in " + path("blur.exr") + " -o " + path("strips.exr") + " --tile 8")
                  .status,
              0);
    EXPECT_EQ(ImageBufAlgo::compare(read_float(path("strips.exr")), out, 0.0f, 0.0f).nfail,
              0u)
        << "strips of 8 rows give the whole frame's alpha and colour";
}


TEST_F(AlphaCli, ASolidAlphaChangesNothing)
{
    write_blurred_render(path("solid.exr"), 16, true);
    ASSERT_EQ(run("--in " + path("solid.exr") + " -o " + path("out.exr")).status, 0);
    ASSERT_EQ(run("--in " + path("solid.exr") + " -o " + path("copied.exr") + " --no-alpha")
                  .status,
              0);
    const ImageBuf out = read_float(path("out.exr")), copied = read_float(path("copied.exr"));
    EXPECT_EQ(ImageBufAlgo::compare(out, copied, 0.0f, 0.0f).nfail, 0u)
        << "an alpha of 0 and 1 only is left as rendered, and the colour with it";
}
