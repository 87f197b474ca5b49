// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The albedo prefilter (docs/FILTER.md section 12) as a user notices it:
// fine text anti-aliased with few samples and the speckled albedo of a
// rough metal come out closer to their exact albedo, flat areas stay
// exact, the result is the reference implementation's, and it does not
// depend on threads or on computing a part; the command uses it on a
// Cycles render and says so.

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <OpenImageIO/imagebufalgo.h>

#include <zdenoise/simd.h>
#include <zdenoise/zdenoise.h>

#include "cli_test.h"
#include "reference_filter.h"
#include "synthetic_scenes.h"

using namespace OIIO;
using namespace cli_test;

namespace {

/// An albedo as a renderer writes it with `samples` samples a pixel, and
/// the exact one (the pixel's footprint averaged): `at(x, y, rng)` gives
/// the albedo one sample at the continuous point (x, y) sees.
struct RenderedAlbedo {
    ImageBuf noisy, exact;
};

template<class At>
RenderedAlbedo
render_albedo(int w, int h, int samples, uint32_t seed, At at)
{
    RenderedAlbedo r;
    r.noisy.reset(ImageSpec(w, h, 3, TypeFloat));
    r.exact.reset(ImageSpec(w, h, 3, TypeFloat));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    constexpr int kExact = 1024;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float noisy[3] = { 0, 0, 0 }, exact[3] = { 0, 0, 0 };
            // Jittered strata, as renderers spread a pixel's samples
            // (Cycles' Sobol and PMJ patterns are stratified too).
            const int side = int(std::lround(std::sqrt(float(samples))));
            for (int s = 0; s < samples; ++s) {
                float a[3];
                at(x + (float(s % side) + u(rng)) / float(side),
                   y + (float(s / side) + u(rng)) / float(side), rng, a,
                   false);
                for (int c = 0; c < 3; ++c)
                    noisy[c] += a[c] / float(samples);
            }
            // The exact footprint average: a fine stratified grid, and the
            // expected value of a random albedo (`at` with a null rng).
            for (int s = 0; s < kExact; ++s) {
                float a[3];
                at(x + (float(s % 32) + 0.5f) / 32.0f,
                   y + (float(s / 32) + 0.5f) / 32.0f, rng, a, true);
                for (int c = 0; c < 3; ++c)
                    exact[c] += a[c] / float(kExact);
            }
            r.noisy.setpixel(x, y, noisy);
            r.exact.setpixel(x, y, exact);
        }
    return r;
}

/// Lines of "text": dark strokes one to two pixels wide, slanted, on
/// paper, over the middle of the frame; paper all around.
void
text_at(float x, float y, std::mt19937&, float* a, bool)
{
    const float paper[3] = { 0.85f, 0.82f, 0.75f }, ink[3] = { 0.05f, 0.05f, 0.07f };
    bool stroke = false;
    if (y > 8.0f && y < 56.0f && x > 8.0f && x < 88.0f) {
        const float line = std::fmod(y, 13.0f);
        const float u    = x + 0.3f * line;  // slanted
        stroke = line > 2.0f && line < 10.0f && std::fmod(u, 7.3f) < 2.4f;
    }
    for (int c = 0; c < 3; ++c)
        a[c] = stroke ? ink[c] : paper[c];
}

/// A rough metal ball whose first hits are glossy (albedo 0.9) with
/// probability 0.3, else its diffuse base (0.2), on a flat grey floor.
void
speckle_at(float x, float y, std::mt19937& rng, float* a, bool exact)
{
    const float dx = x - 48.0f, dy = y - 32.0f;
    float v = 0.5f;
    if (dx * dx + dy * dy < 24.0f * 24.0f) {
        if (exact)
            v = 0.3f * 0.9f + 0.7f * 0.2f;
        else
            v = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng) < 0.3f
                    ? 0.9f
                    : 0.2f;
    }
    for (int c = 0; c < 3; ++c)
        a[c] = v * (1.0f - 0.1f * float(c));
}

}  // namespace


TEST(AlbedoPrefilter, FineTextAntiAliasedWithFewSamplesComesOutCleaner)
{
    for (int samples : { 4, 16 }) {
        RenderedAlbedo r = render_albedo(96, 64, samples, 11, text_at);
        ImageBuf clean   = zdenoise::prefilter_albedo(r.noisy, samples);
        ASSERT_FALSE(clean.has_error()) << clean.geterror();
        const double before = synth::rel_mse(r.noisy, r.exact);
        const double after  = synth::rel_mse(clean, r.exact);
        std::printf("  text, %d spp: albedo relMSE %.5f -> %.5f\n", samples,
                    before, after);
        // Measured 0.89x at 4 spp and 0.97x at 16 (the stratified noise
        // of an edge falls fast: there is less to remove at 16).
        EXPECT_LT(after, (samples == 4 ? 0.95 : 1.0) * before)
            << samples << " spp";
        // The paper around the text is exact, and stays so.
        for (int y = 0; y < 5; ++y)
            for (int x = 0; x < 96; ++x)
                ASSERT_EQ(clean.getchannel(x, y, 0, 1),
                          r.noisy.getchannel(x, y, 0, 1));
    }
}


TEST(AlbedoPrefilter, SpeckledAlbedoOfARoughMetalComesOutCleaner)
{
    RenderedAlbedo r = render_albedo(96, 64, 4, 12, speckle_at);
    ImageBuf clean   = zdenoise::prefilter_albedo(r.noisy, 4);
    const double before = synth::rel_mse(r.noisy, r.exact);
    const double after  = synth::rel_mse(clean, r.exact);
    std::printf("  speckle, 4 spp: albedo relMSE %.5f -> %.5f\n", before,
                after);
    // Measured 0.88x: the model takes the samples as stratified, as a
    // renderer's are, and a lobe's choice stratifies less than an edge.
    EXPECT_LT(after, 0.95 * before);
}


TEST(AlbedoPrefilter, MatchesTheReference)
{
    RenderedAlbedo r = render_albedo(40, 36, 4, 13, text_at);
    // A NaN and an Inf, and a 4th channel that is copied.
    ImageBuf albedo = ImageBufAlgo::channels(r.noisy, 4, { 0, 1, 2, -1 },
                                             { 0, 0, 0, 0.5f });
    albedo.setpixel(12, 20, std::vector<float> { NAN, 0.3f, 0.3f, 0.5f }.data());
    albedo.setpixel(0, 0, std::vector<float> { INFINITY, 0.3f, 0.3f, 0.5f }.data());
    ImageBuf lib = zdenoise::prefilter_albedo(albedo, 4);
    zdenoise_ref::RefImage ref = zdenoise_ref::prefilter_albedo(
        zdenoise_ref::from_imagebuf(albedo), 4);
    zdenoise_ref::RefImage got = zdenoise_ref::from_imagebuf(lib);
    ASSERT_EQ(got.nch, 4);
    double worst = 0.0;
    for (int y = 0; y < 36; ++y)
        for (int x = 0; x < 40; ++x)
            for (int c = 0; c < 4; ++c) {
                const float a = got.at(x, y, c), b = ref.at(x, y, c);
                if (!std::isfinite(b)) {
                    EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0) << x << "," << y;
                    continue;
                }
                worst = std::max(worst, double(std::abs(a - b)));
            }
    std::printf("  max |library - reference| %.3g\n", worst);
    EXPECT_LT(worst, 1e-5);
}


TEST(AlbedoPrefilter, HalvesMeasureTheNoiseTheModelCannotSee)
{
    // Two independent halves of 4 samples each of a speckled albedo (the
    // rough metal's lobe choice, which stratifies less than the model
    // assumes): their difference measures the noise, and the mean of the
    // halves comes out cleaner with it than with the model alone.
    RenderedAlbedo a = render_albedo(96, 64, 4, 21, speckle_at);
    RenderedAlbedo b = render_albedo(96, 64, 4, 22, speckle_at);
    ImageBuf mean = ImageBufAlgo::mul(ImageBufAlgo::add(a.noisy, b.noisy), 0.5f);
    ImageBuf model = zdenoise::prefilter_albedo(mean, 8);
    ImageBuf halves;
    ASSERT_TRUE(zdenoise::prefilter_albedo(halves, mean, 8, a.noisy, b.noisy)) << halves.geterror();
    const double before = synth::rel_mse(mean, a.exact);
    const double with_model = synth::rel_mse(model, a.exact);
    const double with_halves = synth::rel_mse(halves, a.exact);
    std::printf("  speckle, 4+4 spp: albedo relMSE %.5f, model %.5f, halves %.5f\n", before,
                with_model, with_halves);
    EXPECT_LT(with_halves, 0.7 * with_model);
    // Halves that agree add nothing to the model.
    ImageBuf same;
    ASSERT_TRUE(zdenoise::prefilter_albedo(same, mean, 8, mean, mean));
    EXPECT_TRUE(synth::same_pixels(same, model));
    // The reference agrees, a NaN in one half included.
    a.noisy.setpixel(30, 30, std::vector<float> { NAN, 0.3f, 0.3f }.data());
    ASSERT_TRUE(zdenoise::prefilter_albedo(halves, mean, 8, a.noisy, b.noisy));
    const zdenoise_ref::RefImage ra = zdenoise_ref::from_imagebuf(a.noisy),
                                 rb = zdenoise_ref::from_imagebuf(b.noisy);
    const zdenoise_ref::RefImage ref
        = zdenoise_ref::prefilter_albedo(zdenoise_ref::from_imagebuf(mean), 8, &ra, &rb);
    const zdenoise_ref::RefImage got = zdenoise_ref::from_imagebuf(halves);
    double worst = 0.0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 96; ++x)
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, double(std::abs(got.at(x, y, c) - ref.at(x, y, c))));
    EXPECT_LT(worst, 1e-5);
    // Halves that do not cover the albedo are refused, naming them.
    ImageBuf small(ImageSpec(10, 10, 3, TypeFloat)), err;
    EXPECT_FALSE(zdenoise::prefilter_albedo(err, mean, 8, small, b.noisy));
    EXPECT_NE(err.geterror().find("half_a"), std::string::npos) << err.geterror();
}


TEST(AlbedoPrefilter, DoesNotDependOnThreadsOrOnComputingAPart)
{
    RenderedAlbedo r = render_albedo(96, 64, 4, 14, text_at);
    ImageBuf one = zdenoise::prefilter_albedo(r.noisy, 4, {}, 1);
    ImageBuf two = zdenoise::prefilter_albedo(r.noisy, 4, {}, 2);
    EXPECT_TRUE(synth::same_pixels(one, two));
    // Rows 20-40 from the rows 20-40 and the halo around them.
    const int halo = zdenoise::albedo_prefilter_halo();
    ImageBuf held  = ImageBufAlgo::crop(r.noisy, ROI(0, 96, 20 - halo, 40 + halo));
    ImageBuf part  = zdenoise::prefilter_albedo(held, 4, ROI(0, 96, 20, 40));
    ASSERT_FALSE(part.has_error()) << part.geterror();
    EXPECT_TRUE(synth::same_pixels(ImageBufAlgo::crop(part, ROI(0, 96, 20, 40)),
                            ImageBufAlgo::crop(one, ROI(0, 96, 20, 40))));
}


// Its row kernels keep the scalar code's operations and their order (no
// fused multiply-add), so every instruction set gives the same floats.
TEST(AlbedoPrefilter, EveryInstructionSetGivesTheSameFloats)
{
    RenderedAlbedo r = render_albedo(61, 23, 4, 15, text_at);
    std::vector<ImageBuf> got;
    for (const std::string& t : zdenoise::simd_targets()) {
        SCOPED_TRACE(t);
        ASSERT_TRUE(zdenoise::set_simd_target(t));
        got.push_back(zdenoise::prefilter_albedo(r.noisy, 4));
        ASSERT_FALSE(got.back().has_error()) << got.back().geterror();
        EXPECT_TRUE(synth::same_pixels(got.back(), got.front()));
    }
    ASSERT_TRUE(zdenoise::set_simd_target(""));
}


TEST_F(CliTest, CyclesAlbedoIsPrefilteredWithTheRendersSamples)
{
    const std::string in = kSourceDir
                           + "/share/samples/cornell_textured_spp16_crop.exr";
    const std::string ref = kSourceDir
                            + "/share/samples/cornell_textured_ref_crop.exr";
    // Beauty mode's albedo, named (--mode path prefilters its colours the
    // same way).
    const std::string beauty = " --mode beauty";
    RunResult r = run("--in '" + in + "' -o '" + path("pre.exr") + "' -v" + beauty);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("albedo    prefiltered as 16 samples a pixel "
                         "(cycles.ViewLayer.samples)"),
              std::string::npos)
        << r.out;
    r = run("--in '" + in + "' -o '" + path("plain.exr")
            + "' --no-albedo-prefilter -v" + beauty);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("not prefiltered (--no-albedo-prefilter)"),
              std::string::npos)
        << r.out;
    ImageBuf pre(path("pre.exr")), plain(path("plain.exr")), truth(ref);
    ASSERT_TRUE(pre.read(0, 0, true, TypeFloat));
    ASSERT_TRUE(plain.read(0, 0, true, TypeFloat));
    const double with    = synth::rel_mse(pre, truth);
    const double without = synth::rel_mse(plain, truth);
    // Today's filter alone fits the light to the albedo it is given; the
    // selection's feature regressions also regress on the albedo, which
    // takes up much of its noise (public set: the prefilter gains up to 24 %
    // with the selection, bench/results/2026-12-selection-log.md section 11; on this crop it is
    // even).
    double with_today = 0.0, without_today = 0.0;
    for (const char* flags : { "", " --no-albedo-prefilter" }) {
        r = run("--in '" + in + "' -o '" + path("today.exr") + "' --select 0" + flags + beauty);
        ASSERT_EQ(r.status, 0) << r.err;
        ImageBuf today(path("today.exr"));
        ASSERT_TRUE(today.read(0, 0, true, TypeFloat));
        (*flags ? without_today : with_today) = synth::rel_mse(today, truth);
    }
    std::printf("  bundled crop: relMSE %.5f without the prefilter, %.5f "
                "with; today's filter alone %.5f, %.5f\n",
                without, with, without_today, with_today);
    EXPECT_LT(with_today, without_today);
    EXPECT_LT(with, 1.01 * without);
    // The output says how its albedo was taken.
    EXPECT_NE(pre.spec().get_string_attribute("zdenoise.parameters")
                  .find("mode=beauty albedo-samples=16"),
              std::string::npos);
    EXPECT_EQ(plain.spec().get_string_attribute("zdenoise.parameters")
                  .find("albedo-samples"),
              std::string::npos);
    // The noisy albedo AOV itself is carried through unchanged.
    const int alb = pre.spec().channelindex("ViewLayer.Denoising Albedo.G");
    ImageBuf noisy(in);
    ASSERT_GE(alb, 0);
    for (int y = 0; y < 96; y += 7)
        for (int x = 0; x < 96; x += 5)
            ASSERT_EQ(pre.getchannel(x, y, 0, alb), noisy.getchannel(x, y, 0, alb));
}


TEST_F(CliTest, CyclesHalvesMeasureTheAlbedosNoise)
{
    // With --halves of Cycles files, the prefilter also takes the albedo's
    // variance from the halves' own Denoising Albedo (docs/FILTER.md 12).
    // Here both halves are the bundled crop: they agree, so the model
    // alone decides, and the output is the one the model gives.
    const std::string in = kSourceDir + "/share/samples/cornell_textured_spp16_crop.exr";
    RunResult r = run("--in '" + in + "' --halves '" + in + "' '" + in + "' -o '"
                      + path("halves.exr") + "' -v");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("albedo    its noise also measured from the halves' albedos "
                         "(ViewLayer.Denoising Albedo)"),
              std::string::npos)
        << r.out;
    ImageBuf out(path("halves.exr"));
    ASSERT_TRUE(out.read(0, 0, true, TypeFloat)) << out.geterror();
    EXPECT_NE(out.spec().get_string_attribute("zdenoise.parameters")
                  .find("albedo-samples=16 albedo-halves"),
              std::string::npos);
    // Halves without an albedo of their own: the model alone, said so by
    // the absence of the line.
    ImageBuf rgb = ImageBufAlgo::channels(ImageBuf(in), 3, { 0, 1, 2 });
    ASSERT_TRUE(rgb.write(path("rgb.exr")));
    r = run("--in '" + in + "' --halves '" + path("rgb.exr") + "' '" + path("rgb.exr")
            + "' -o '" + path("plain.exr") + "' -v");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.out.find("measured from the halves"), std::string::npos) << r.out;
}


TEST_F(CliTest, AlbedoSamplesMustBePositive)
{
    const std::string in = kSourceDir
                           + "/share/samples/cornell_textured_spp16_crop.exr";
    RunResult r = run("--in '" + in + "' -o '" + path("x.exr")
                      + "' --albedo-samples -3");
    expect_one_line_error(r, "--albedo-samples needs a number >= 1, got -3");
    EXPECT_TRUE(files().empty());
}
