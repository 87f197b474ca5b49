// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Colour management as a user meets it: the bundled config is valid, the
// input's colour space is found (and said), the filter runs in the working
// space, the output is converted and tagged, and 8-bit sRGB renders are
// linearised before filtering.

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include "ocio/colour.h"
#include "cli_harness.h"
#include "synthetic_scenes.h"

using namespace OIIO;
using namespace cli_harness;

namespace {

const std::string kSourceDir     = ZDENOISE_SOURCE_DIR;
const std::string kBundledConfig = kSourceDir + "/ocio/config.ocio";
const std::string kLinear        = "Linear Rec.709 (sRGB)";

/// The bundled config from the source tree.
const zdenoise::colour::ColourConfig&
bundled()
{
    static zdenoise::colour::ColourConfig config;
    static bool loaded = [] {
        std::string err;
        bool ok = config.load(kBundledConfig, err);
        EXPECT_TRUE(ok) << err;
        return ok;
    }();
    (void)loaded;
    return config;
}

ImageBuf
converted(const ImageBuf& src, const std::string& from, const std::string& to)
{
    ImageBuf dst;
    dst.copy(src, TypeFloat);
    std::string err;
    EXPECT_TRUE(bundled().convert_rgb(dst, from, to, err)) << err;
    return dst;
}

ImageBuf
read_float(const std::string& path)
{
    ImageBuf b(path);
    EXPECT_TRUE(b.read(0, 0, true, TypeFloat)) << b.geterror();
    return b;
}

/// Largest absolute difference over RGB.
double
max_rgb_difference(const ImageBuf& a, const ImageBuf& b)
{
    double worst  = 0.0;
    const ROI roi = a.roi();
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x)
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst,
                                 double(std::fabs(a.getchannel(x, y, 0, c)
                                                  - b.getchannel(x, y, 0, c))));
    return worst;
}

class Colour : public FolderTest {
protected:
    /// Write RGB `image` as a float EXR, with `chromaticities` if given.
    void write_exr(const std::string& name, const ImageBuf& image,
                   const float* chromaticities = nullptr)
    {
        ImageBuf b;
        b.copy(image, TypeFloat);
        if (chromaticities)
            b.specmod().attribute("chromaticities", TypeDesc(TypeDesc::FLOAT, 8),
                                  chromaticities);
        ASSERT_TRUE(b.write(path(name))) << b.geterror();
    }
};

const float kAP1[8] = { 0.713f, 0.293f, 0.165f, 0.830f, 0.128f, 0.044f, 0.32168f, 0.33767f };

}  // namespace


TEST(ColourConfig, BundledConfigPassesOciocheck)
{
    const std::string ociocheck = ZDENOISE_OCIOCHECK;
    if (ociocheck.empty())
        GTEST_SKIP() << "ociocheck not found (Debian package opencolorio-tools)";
    RunResult r = run_command(quoted(ociocheck) + " --iconfig " + quoted(kBundledConfig),
                              ::testing::TempDir() + "/ociocheck");
    EXPECT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("passed"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("ERROR"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("WARNING"), std::string::npos) << r.out;
    for (const char* space : { "Linear Rec.709 (sRGB)", "ACEScg", "ACES2065-1",
                               "sRGB - Texture", "sRGB - Display",
                               "Rec.1886 Rec.709 - Display" })
        EXPECT_NE(r.out.find(space), std::string::npos) << space << " missing:\n" << r.out;
    for (const char* role : { "(scene_linear)", "(default)", "(color_picking)", "(data)",
                              "(aces_interchange)" })
        EXPECT_NE(r.out.find(role), std::string::npos) << role << " missing:\n" << r.out;
}


TEST(ColourConfig, BundledConfigIsInstalledNextToTheProgramInTheBuildTree)
{
    // The programs in build/bin find build/share/zdenoise/ocio/config.ocio.
    const std::string cli = ZDENOISE_CLI;
    const std::string next_to = Filesystem::parent_path(Filesystem::parent_path(cli))
                                + "/share/zdenoise/ocio/config.ocio";
    EXPECT_TRUE(Filesystem::is_regular(next_to)) << next_to;
}


TEST_F(Colour, ExrWithoutChromaticitiesIsSceneLinearAndSaysSo)
{
    synth::Scene s = synth::fine_texture(32, 24);
    write_exr("noisy.exr", s.noisy);
    write_exr("albedo.exr", s.albedo);
    RunResult r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                           + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("without chromaticities: assumed scene_linear"), std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("colour config bundled"), std::string::npos) << r.out;
    ImageBuf out(path("out.exr"));
    out.init_spec(path("out.exr"), 0, 0);
    // OIIO's EXR reader reports every EXR as "Linear"; the chromaticities
    // are what a later reader can trust.
    float xy[8] = {};
    EXPECT_FALSE(out.spec().getattribute("chromaticities", TypeDesc(TypeDesc::FLOAT, 8), xy))
        << "no primaries may be invented for an input that stated none";
}


TEST_F(Colour, AcescgInputIsFilteredInTheWorkingSpaceAndWrittenBackInAcescg)
{
    // The same scene, once as linear Rec.709, once converted to ACEScg and
    // tagged so: the ACEScg run must give the Rec.709 run's result in ACEScg.
    synth::Scene s = synth::fine_texture(32, 24);
    write_exr("noisy709.exr", s.noisy);
    write_exr("albedo709.exr", s.albedo);
    write_exr("noisycg.exr", converted(s.noisy, kLinear, "ACEScg"), kAP1);
    write_exr("albedocg.exr", converted(s.albedo, kLinear, "ACEScg"), kAP1);
    RunResult r = zdenoise("--in " + path("noisy709.exr") + " --albedo " + path("albedo709.exr")
                           + " -o " + path("out709.exr"));
    ASSERT_EQ(r.status, 0) << r.err;
    r = zdenoise("--in " + path("noisycg.exr") + " --albedo " + path("albedocg.exr") + " -o "
                 + path("outcg.exr") + " -v");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("radiance colour space 'ACEScg': "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("ACEScg (AP1) primaries"), std::string::npos) << r.out;

    ImageBuf outcg = read_float(path("outcg.exr"));
    EXPECT_EQ(outcg.spec().get_string_attribute("oiio:ColorSpace"), "Linear")
        << "(OIIO 2.4's EXR reader) -- if this changes, check the tag instead";
    ImageBuf expected = converted(read_float(path("out709.exr")), kLinear, "ACEScg");
    EXPECT_LT(max_rgb_difference(outcg, expected), 1e-4);

    EXPECT_EQ(outcg.spec().get_string_attribute("zdenoise.colorspace"), "ACEScg");
}


TEST_F(Colour, OutputColourSpaceIsConvertedAndTaggedOnlyInRgb)
{
    // A fourth, non-colour channel must come through untouched.
    synth::Scene s = synth::fine_texture(24, 16);
    ImageBuf noisy_with_z;
    ImageBuf z(ImageSpec(24, 16, 1, TypeFloat));
    ImageBufAlgo::fill(z, { 7.25f });
    ImageBufAlgo::channel_append(noisy_with_z, s.noisy, z);
    noisy_with_z.specmod().channelnames = { "R", "G", "B", "Z" };
    write_exr("noisy.exr", noisy_with_z);
    write_exr("albedo.exr", s.albedo);
    RunResult r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                           + " -o " + path("lin.exr"));
    ASSERT_EQ(r.status, 0) << r.err;
    r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                 + " --ocolorspace ACES2065-1 -o " + path("ap0.exr"));
    ASSERT_EQ(r.status, 0) << r.err;
    ImageBuf ap0 = read_float(path("ap0.exr"));
    float xy[8]  = {};
    ASSERT_TRUE(ap0.spec().getattribute("chromaticities", TypeDesc(TypeDesc::FLOAT, 8), xy));
    EXPECT_NEAR(xy[0], 0.7347f, 1e-4f) << "AP0 red x";
    EXPECT_LT(max_rgb_difference(ap0, converted(read_float(path("lin.exr")), kLinear,
                                                 "ACES2065-1")),
              1e-4);
    for (int y = 0; y < 16; y += 3)
        for (int x = 0; x < 24; x += 5)
            ASSERT_EQ(ap0.getchannel(x, y, 0, 3), 7.25f) << "Z must not be converted";

    EXPECT_EQ(ap0.spec().get_string_attribute("zdenoise.colorspace"), "ACES2065-1");

    // A PNG output keeps oiio:ColorSpace itself.
    r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                 + " --ocolorspace sRGB -o " + path("out.png"));
    ASSERT_EQ(r.status, 0) << r.err;
    ImageBuf png(path("out.png"));
    png.init_spec(path("out.png"), 0, 0);
    EXPECT_EQ(png.spec().get_string_attribute("oiio:ColorSpace"), "sRGB - Texture");
}


TEST_F(Colour, UnknownColourSpaceIsOneLineListingTheConfigsSpaces)
{
    synth::Scene s = synth::fine_texture(16, 16);
    write_exr("noisy.exr", s.noisy);
    write_exr("albedo.exr", s.albedo);
    for (const char* option : { "--iscolorspace", "--albedo-colorspace", "--ocolorspace",
                                "--working-colorspace" }) {
        RunResult r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                               + " " + option + " Rec.2020-ish -o " + path("out.exr"));
        EXPECT_EQ(r.status, 1) << option;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find(option), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("'Rec.2020-ish'"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("'ACEScg'"), std::string::npos) << "should list the spaces: " << r.err;
        EXPECT_FALSE(Filesystem::exists(path("out.exr")));
    }
    RunResult r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                           + " --colorconfig " + path("nope.ocio") + " -o " + path("out.exr"));
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find("nope.ocio"), std::string::npos) << r.err;
}


TEST_F(Colour, OcioEnvironmentVariableNamesTheConfig)
{
    synth::Scene s = synth::fine_texture(16, 16);
    write_exr("noisy.exr", s.noisy);
    write_exr("albedo.exr", s.albedo);
    RunResult r = run_command("OCIO=" + quoted(kBundledConfig) + " " + quoted(ZDENOISE_CLI)
                                  + " --in " + path("noisy.exr") + " --albedo "
                                  + path("albedo.exr") + " -o " + path("out.exr") + " -v",
                              path(".run"));
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("colour config $OCIO"), std::string::npos) << r.out;
}


TEST_F(Colour, OiiotoolWithTheBundledConfigConvertsBackToTheLinearResult)
{
    // Round trip through Debian's oiiotool: zdenoise writes ACEScg, oiiotool
    // converts it back with the bundled config; that is zdenoise's linear
    // Rec.709 result.
    const std::string oiiotool = ZDENOISE_OIIOTOOL;
    if (oiiotool.empty())
        GTEST_SKIP() << "oiiotool not found (Debian package openimageio-tools)";
    synth::Scene s = synth::fine_texture(32, 24);
    write_exr("noisy.exr", s.noisy);
    write_exr("albedo.exr", s.albedo);
    RunResult r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                           + " -o " + path("lin.exr"));
    ASSERT_EQ(r.status, 0) << r.err;
    r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                 + " --ocolorspace ACEScg -o " + path("cg.exr"));
    ASSERT_EQ(r.status, 0) << r.err;
    r = run_command(host_program(oiiotool) + " --colorconfig " + quoted(kBundledConfig) + " "
                        + path("cg.exr") + " --colorconvert ACEScg " + quoted(kLinear)
                        + " -o " + path("back.exr"),
                    path(".oiiotool"));
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_LT(max_rgb_difference(read_float(path("back.exr")), read_float(path("lin.exr"))),
              1e-4);
}


// ---- (B) 8-bit sRGB renders ----

namespace {

/// The scene as an 8-bit sRGB-encoded PNG (what a user's LDR render is).
void
write_srgb_png(const ImageBuf& linear, const std::string& path)
{
    ImageBuf enc = converted(linear, kLinear, "sRGB - Texture");
    enc.set_write_format(TypeUInt8);
    ASSERT_TRUE(enc.write(path)) << enc.geterror();
}

}  // namespace


TEST_F(Colour, SrgbPngIsLinearisedForFilteringAndReencoded)
{
    synth::Scene s = synth::fine_texture(48, 32, { 32, 404 });
    ImageBuf noisy = ImageBufAlgo::mul(s.noisy, 0.8f);
    write_srgb_png(noisy, path("noisy.png"));
    write_srgb_png(s.albedo, path("albedo.png"));
    RunResult r = zdenoise("--in " + path("noisy.png") + " --albedo " + path("albedo.png")
                           + " -o " + path("out.png") + " -v");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("radiance colour space 'sRGB - Texture'"), std::string::npos)
        << r.out;
    auto in = ImageInput::open(path("out.png"));
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().format, TypeUInt8) << "8-bit in, 8-bit out";
    in.reset();

    // The same by hand: decode the PNGs to linear EXRs, denoise, encode.
    write_exr("noisy_lin.exr", converted(read_float(path("noisy.png")), "sRGB - Texture", kLinear));
    write_exr("albedo_lin.exr",
              converted(read_float(path("albedo.png")), "sRGB - Texture", kLinear));
    r = zdenoise("--in " + path("noisy_lin.exr") + " --albedo " + path("albedo_lin.exr")
                 + " -o " + path("out_lin.exr"));
    ASSERT_EQ(r.status, 0) << r.err;
    ImageBuf by_hand = converted(read_float(path("out_lin.exr")), kLinear, "sRGB - Texture");
    EXPECT_LE(max_rgb_difference(read_float(path("out.png")), by_hand), 1.0 / 255 + 1e-6)
        << "within one 8-bit step";

    // The mistake: filtering the encoded values as if they were light.
    r = zdenoise("--in " + path("noisy.png") + " --albedo " + path("albedo.png")
                 + " --iscolorspace linear --albedo-colorspace linear -o "
                 + path("mistake.png"));
    ASSERT_EQ(r.status, 0) << r.err;
    ImageBuf clean = ImageBufAlgo::mul(s.clean, 0.8f);
    const double right = synth::rel_mse(
        converted(read_float(path("out.png")), "sRGB - Texture", kLinear), clean);
    const double wrong = synth::rel_mse(
        converted(read_float(path("mistake.png")), "sRGB - Texture", kLinear), clean);
    std::printf("  sRGB PNG relMSE: linearised %.5f, filtered encoded %.5f\n", right, wrong);
    EXPECT_LT(right * 1.2, wrong)
        << "filtering sRGB-encoded values should be measurably worse";
}


TEST_F(Colour, RecipeCarriesTheColourOptionsToOiiotool)
{
    const std::string oiiotool = ZDENOISE_OIIOTOOL;
    if (oiiotool.empty())
        GTEST_SKIP() << "oiiotool not found (Debian package openimageio-tools)";
    synth::Scene s = synth::fine_texture(24, 16);
    write_exr("noisy.exr", s.noisy);
    write_exr("albedo.exr", s.albedo);
    const std::string colour = " --colorconfig " + quoted(kBundledConfig)
                               + " --ocolorspace ACEScg";
    RunResult r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                           + colour + " -o " + path("direct.exr"));
    ASSERT_EQ(r.status, 0) << r.err;
    // The config lies outside the recipe's folder: ZDENOISE_RECIPE_PATH
    // lets the recipe read it (share/zdn-format.md).
    const std::string allow = "ZDENOISE_RECIPE_PATH="
                              + quoted(Filesystem::parent_path(kBundledConfig)) + " ";
    r = run_command(allow + quoted(ZDENOISE_CLI) + " --in " + path("noisy.exr") + " --albedo "
                        + path("albedo.exr") + colour + " --write-recipe " + path("shot.zdn"),
                    path(".zdenoise"));
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string recipe = slurp(path("shot.zdn"));
    EXPECT_NE(recipe.find("\"ocolorspace\": \"ACEScg\""), std::string::npos) << recipe;
    r = run_command(allow + "OIIO_LIBRARY_PATH=" + quoted(ZDENOISE_PLUGIN_DIR) + " "
                        + host_program(oiiotool) + " " + path("shot.zdn") + " -o "
                        + path("via_recipe.exr"),
                    path(".oiiotool"));
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_EQ(max_rgb_difference(read_float(path("via_recipe.exr")),
                                 read_float(path("direct.exr"))),
              0.0);
}


TEST_F(Colour, FilteringInTheRenderingSpaceBeatsOtherPrimaries)
{
    // Demodulation is per channel: with coloured light on a texture of
    // saturated colours, the quotient radiance / albedo is the smooth light
    // only in the space the image was rendered in (here linear Rec.709).
    const int w = 48, h = 32;
    std::vector<float> clean, noisy, albedo;
    std::mt19937 rng(1234);
    std::gamma_distribution<float> noise(16.0f, 1.0f / 16.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const bool red  = ((x >> 1) + (y >> 1)) & 1;
            const float a[3] = { red ? 0.8f : 0.08f, 0.12f, red ? 0.08f : 0.8f };
            const float s    = 0.6f + 0.3f * std::sin(6.2832f * x / w);
            const float l[3] = { 1.0f * s, 0.7f * s, 0.35f * s };
            const float m    = noise(rng);
            for (int c = 0; c < 3; ++c) {
                albedo.push_back(a[c]);
                clean.push_back(a[c] * l[c]);
                noisy.push_back(a[c] * l[c] * m);
            }
        }
    write_exr("noisy.exr", synth::make_image(w, h, 3, noisy));
    write_exr("albedo.exr", synth::make_image(w, h, 3, albedo));
    const ImageBuf truth = synth::make_image(w, h, 3, clean);
    RunResult r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                           + " -o " + path("rendering.exr"));
    ASSERT_EQ(r.status, 0) << r.err;
    r = zdenoise("--in " + path("noisy.exr") + " --albedo " + path("albedo.exr")
                 + " --working-colorspace ACES2065-1 -o " + path("ap0.exr"));
    ASSERT_EQ(r.status, 0) << r.err;
    const double right = synth::rel_mse(read_float(path("rendering.exr")), truth);
    const double wrong = synth::rel_mse(read_float(path("ap0.exr")), truth);
    std::printf("  relMSE: working in the rendering space %.5f, in ACES2065-1 %.5f\n", right,
                wrong);
    EXPECT_LT(right * 1.2, wrong);
}
