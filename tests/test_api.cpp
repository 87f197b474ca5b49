// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The library API as a program uses it: any pixel type in, errors reported
// through the destination image (never thrown), inputs of the wrong shape
// refused with a message that names them.

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include <gtest/gtest.h>

#include <OpenImageIO/imagebufalgo.h>

#include <zdenoise/zdenoise.h>

#include "reference_filter.h"

using namespace OIIO;

namespace {

/// A noisy radiance over a two-tone albedo, and that albedo.
void
make_scene(ImageBuf& radiance, ImageBuf& albedo, int w = 40, int h = 32)
{
    radiance.reset(ImageSpec(w, h, 4, TypeFloat));
    albedo.reset(ImageSpec(w, h, 3, TypeFloat));
    std::mt19937 rng(7);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float a = ((x / 3 + y / 2) % 2) ? 0.8f : 0.3f;
            // noise in [0.5, 1.5): an integer-exact generator, same everywhere
            const float n = 0.5f + float(rng() % 1024) / 1024.0f;
            const float light = 0.5f + 0.5f * float(x) / float(w);
            const float alb[3] = { a, a * 0.9f, a * 0.7f };
            albedo.setpixel(x, y, alb, 3);
            const float rad[4] = { alb[0] * light * n, alb[1] * light * n,
                                   alb[2] * light * n, 1.0f };
            radiance.setpixel(x, y, rad, 4);
        }
}

ImageBuf
converted(const ImageBuf& src, TypeDesc type)
{
    ImageBuf out;
    out.copy(src, type);
    return out;
}

float
max_abs_diff(const ImageBuf& a, const ImageBuf& b, int nch)
{
    float m = 0.0f;
    for (int y = a.ybegin(); y < a.yend(); ++y)
        for (int x = a.xbegin(); x < a.xend(); ++x)
            for (int c = 0; c < nch; ++c)
                m = std::max(m, std::fabs(a.getchannel(x, y, 0, c)
                                          - b.getchannel(x, y, 0, c)));
    return m;
}

}  // namespace


TEST(Api, HalfAndIntegerInputsGiveTheFloatResult)
{
    ImageBuf radiance, albedo;
    make_scene(radiance, albedo);
    // Quantise once so that every type holds exactly the same values.
    ImageBuf rad_half = converted(radiance, TypeHalf);
    ImageBuf alb_u8   = converted(albedo, TypeUInt8);
    ImageBuf rad_f    = converted(rad_half, TypeFloat);
    ImageBuf alb_f    = converted(alb_u8, TypeFloat);

    ImageBuf expect = zdenoise::denoise(rad_f, alb_f);
    ASSERT_FALSE(expect.has_error()) << expect.geterror();
    ImageBuf got = zdenoise::denoise(rad_half, alb_u8);
    ASSERT_FALSE(got.has_error()) << got.geterror();
    EXPECT_EQ(got.spec().format, TypeFloat) << "results are float";
    EXPECT_EQ(max_abs_diff(expect, got, 4), 0.0f)
        << "half radiance and 8-bit albedo must give exactly the float result";

    // A half destination given by the caller is filled in its own type.
    ImageBuf half_dst(ImageSpec(radiance.spec().width, radiance.spec().height, 4, TypeHalf));
    ASSERT_TRUE(zdenoise::denoise(half_dst, rad_half, alb_u8)) << half_dst.geterror();
    EXPECT_LT(max_abs_diff(expect, half_dst, 3), 2e-3f);
}


TEST(Api, AlphaAndExtraChannelsPassThrough)
{
    // RGB, a varying alpha (0 in places: "no surface", which the filter
    // passes through) and an AOV that is no colour, each pixel its own value:
    // a channel copied from the wrong pixel or channel would show.
    ImageBuf rgba, albedo;
    make_scene(rgba, albedo);
    const int w = rgba.spec().width, h = rgba.spec().height;
    ImageSpec spec(w, h, 5, TypeFloat);
    spec.channelnames  = { "R", "G", "B", "A", "AOV.x" };
    spec.alpha_channel = 3;
    ImageBuf radiance(spec);
    std::mt19937 rng(11);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float px[5];
            rgba.getpixel(x, y, px, 3);
            px[3] = (x + 2 * y) % 7 == 0 ? 0.0f : float(1 + rng() % 1000) / 997.0f;
            px[4] = float(int(rng() % 20001) - 10000) * 3.7e-3f;
            radiance.setpixel(x, y, px, 5);
        }
    for (const int select : { 0, 1 }) {
        SCOPED_TRACE(testing::Message() << "select " << select);
        zdenoise::FilterOptions opt;
        opt.select      = select;
        ImageBuf result = zdenoise::denoise(radiance, albedo, {}, opt);
        ASSERT_FALSE(result.has_error()) << result.geterror();
        ASSERT_EQ(result.nchannels(), 5);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 3; c < 5; ++c) {
                    const float a = radiance.getchannel(x, y, 0, c);
                    const float b = result.getchannel(x, y, 0, c);
                    ASSERT_EQ(std::memcmp(&a, &b, sizeof(float)), 0)
                        << "pixel " << x << "," << y << " channel " << c << ": "
                        << b << " for " << a;
                }
        // The colour is denoised (not all passed through with them).
        EXPECT_GT(max_abs_diff(radiance, result, 3), 0.0f);
    }
}


TEST(Api, ErrorsComeThroughDstNotExceptions)
{
    ImageBuf radiance, albedo;
    make_scene(radiance, albedo);

    // Albedo smaller than the radiance.
    ImageBuf small_albedo(ImageSpec(10, 10, 3, TypeFloat));
    ImageBuf dst;
    EXPECT_FALSE(zdenoise::denoise(dst, radiance, small_albedo));
    EXPECT_NE(dst.geterror().find("albedo"), std::string::npos);

    // Two-channel radiance.
    ImageBuf two(ImageSpec(40, 32, 2, TypeFloat));
    ImageBuf r2 = zdenoise::denoise(two, albedo);
    EXPECT_TRUE(r2.has_error());
    EXPECT_NE(r2.geterror().find("channel"), std::string::npos);

    // Uninitialized inputs.
    ImageBuf empty;
    ImageBuf r3 = zdenoise::regression_filter(empty, albedo);
    EXPECT_TRUE(r3.has_error());

    // A guide of the wrong shape is named.
    ImageBuf normal(ImageSpec(40, 32, 2, TypeFloat));
    zdenoise::Guides guides;
    guides.normal = &normal;
    ImageBuf r4   = zdenoise::denoise(radiance, albedo, guides);
    EXPECT_TRUE(r4.has_error());
    EXPECT_NE(r4.geterror().find("normal"), std::string::npos) << r4.geterror();

    // An id guide with an odd number of channels (not id/coverage pairs).
    ImageBuf ids(ImageSpec(40, 32, 3, TypeFloat));
    zdenoise::Guides g2;
    g2.object_id = &ids;
    ImageBuf r5  = zdenoise::denoise(radiance, albedo, g2);
    EXPECT_TRUE(r5.has_error());

    // Only one half buffer.
    zdenoise::Guides g3;
    g3.half_a   = &radiance;
    ImageBuf r6 = zdenoise::denoise(radiance, albedo, g3);
    EXPECT_TRUE(r6.has_error());

    // Invalid options are named.
    zdenoise::FilterOptions opt;
    opt.r_max   = 1;
    ImageBuf r7 = zdenoise::denoise(radiance, albedo, {}, opt);
    EXPECT_TRUE(r7.has_error());
    EXPECT_NE(r7.geterror().find("r_max"), std::string::npos) << r7.geterror();
    opt         = {};
    opt.albedo_eps = 0.0f;
    ImageBuf r8 = zdenoise::demodulate(radiance, albedo, 0.0f);
    EXPECT_TRUE(r8.has_error());
}


TEST(Api, StatsCountWindowsAndStops)
{
    ImageBuf radiance, albedo;
    make_scene(radiance, albedo);
    zdenoise::FilterStats stats;
    zdenoise::FilterOptions exact;
    exact.centre_stride = 1;
    ImageBuf result = zdenoise::denoise(radiance, albedo, {}, exact, &stats);
    ASSERT_FALSE(result.has_error());
    EXPECT_EQ(stats.pixels, 40 * 32);
    EXPECT_EQ(stats.windows, 40 * 32) << "every pixel is a window centre here";
    EXPECT_EQ(stats.stop_quality + stats.stop_size + stats.stop_edge, stats.windows);
    // The windows and their radii are the plain reference's (today's
    // filter, which the selection's statistics describe).
    zdenoise_ref::RefStats ref;
    zdenoise_ref::denoise(zdenoise_ref::from_imagebuf(radiance),
                          zdenoise_ref::from_imagebuf(albedo), {}, exact, &ref);
    std::printf("  mean radius %.3f (reference %.3f); stops %lld %lld %lld (%lld %lld %lld)\n",
                stats.mean_radius, ref.mean_radius, (long long)stats.stop_quality,
                (long long)stats.stop_size, (long long)stats.stop_edge,
                (long long)ref.stop_quality, (long long)ref.stop_size,
                (long long)ref.stop_edge);
    EXPECT_NEAR(stats.mean_radius, ref.mean_radius, 0.02);
    EXPECT_NEAR(double(stats.stop_edge), double(ref.stop_edge), 0.01 * stats.windows);
    EXPECT_NEAR(double(stats.stop_size), double(ref.stop_size), 0.01 * stats.windows);
    EXPECT_EQ(stats.passthrough_pixels, 0);
    EXPECT_NE(zdenoise::describe({}).find("eta=0.02"), std::string::npos);
}
