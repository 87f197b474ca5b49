// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The filter's result does not depend on how it is run: thread count, ROI,
// data-window origin, progress callback (docs/FILTER.md section 8).

#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include <zdenoise/simd.h>
#include <zdenoise/zdenoise.h>

#include "synthetic_scenes.h"

using OIIO::ImageBuf;
using OIIO::ROI;
using synth::Scene;

namespace {

/// Count of float values that differ bitwise (memcmp per value).
size_t
count_bit_differences(const std::vector<float>& a, const std::vector<float>& b)
{
    if (a.size() != b.size())
        return size_t(-1);
    size_t n = 0;
    for (size_t i = 0; i < a.size(); ++i)
        if (std::memcmp(&a[i], &b[i], sizeof(float)) != 0)
            ++n;
    return n;
}

std::vector<float>
roi_pixels(const ImageBuf& img, ROI roi)
{
    roi.chbegin = 0;
    roi.chend   = img.nchannels();
    std::vector<float> px(roi.npixels() * roi.nchannels());
    EXPECT_TRUE(img.get_pixels(roi, OIIO::TypeFloat, px.data()))
        << img.geterror();
    return px;
}

/// A scene with several strips (> 2*33 rows), every guide given.
struct Fixture {
    Scene s = synth::staircase(72, 112, 8, { 8, 808 });
    zdenoise::Guides g;
    Fixture()
    {
        g.normal    = &s.normal;
        g.depth     = &s.depth;
        g.object_id = &s.object_id;
    }
};

}  // namespace


// 1 thread vs 2 and 3 threads: bit-identical output and identical stats,
// with the default r_max (strips of 33 rows) and a small one (32 rows).
TEST(FilterDeterminism, ThreadCountGivesBitIdenticalOutput)
{
    Fixture f;
    // r_max, and the pyramid radius (docs/FILTER.md 5.1)
    const int cases[][2] = { { 16, 0 }, { 5, 0 }, { 16, 8 } };
    for (const auto& [rmax, pyramid] : cases) {
        zdenoise::FilterOptions opt;
        opt.r_max          = rmax;
        opt.pyramid_radius = pyramid;
        SCOPED_TRACE("r_max " + std::to_string(rmax) + ", pyramid "
                     + std::to_string(pyramid));
        zdenoise::FilterStats st1;
        ImageBuf ref = zdenoise::denoise(f.s.noisy, f.s.albedo, f.g, opt, &st1,
                                         {}, 1);
        ASSERT_FALSE(ref.has_error()) << ref.geterror();
        std::vector<float> p1 = synth::pixels(ref);
        for (int nt : { 2, 3 }) {
            zdenoise::FilterStats st;
            ImageBuf out = zdenoise::denoise(f.s.noisy, f.s.albedo, f.g, opt,
                                             &st, {}, nt);
            ASSERT_FALSE(out.has_error()) << out.geterror();
            EXPECT_EQ(count_bit_differences(p1, synth::pixels(out)), 0u)
                << "float values differing between 1 and " << nt << " threads";
            EXPECT_EQ(st.windows, st1.windows) << nt << " threads";
            EXPECT_EQ(st.stop_quality, st1.stop_quality) << nt << " threads";
            EXPECT_EQ(st.stop_size, st1.stop_size) << nt << " threads";
            EXPECT_EQ(st.stop_edge, st1.stop_edge) << nt << " threads";
            EXPECT_EQ(st.mean_radius, st1.mean_radius) << nt << " threads";
        }
    }
}

// Filtering a sub-ROI gives exactly the whole-image pixels there (inner
// ROI, ROIs touching the borders, with 1 and 2 threads), for both
// regression_filter and denoise.
TEST(FilterDeterminism, RoiGivesExactlyTheWholeImagePixels)
{
    Fixture f;
    for (int pyramid : { 0, 4 }) {
    SCOPED_TRACE("pyramid " + std::to_string(pyramid));
    zdenoise::FilterOptions opt;
    opt.r_max          = 8;
    opt.pyramid_radius = pyramid;
    ImageBuf whole = zdenoise::denoise(f.s.noisy, f.s.albedo, f.g, opt);
    ASSERT_FALSE(whole.has_error()) << whole.geterror();
    ImageBuf z      = zdenoise::demodulate(f.s.noisy, f.s.albedo);
    ImageBuf zwhole = zdenoise::regression_filter(z, f.s.albedo, f.g, opt);
    ASSERT_FALSE(zwhole.has_error()) << zwhole.geterror();

    const ROI rois[] = { ROI(17, 53, 29, 83), ROI(0, 20, 0, 40),
                         ROI(50, 72, 90, 112), ROI(0, 72, 40, 41) };
    for (const ROI& roi : rois) {
        for (int nt : { 1, 2 }) {
            SCOPED_TRACE("roi x " + std::to_string(roi.xbegin) + "-"
                         + std::to_string(roi.xend) + " y "
                         + std::to_string(roi.ybegin) + "-"
                         + std::to_string(roi.yend) + ", threads "
                         + std::to_string(nt));
            zdenoise::FilterStats st;
            ImageBuf part = zdenoise::denoise(f.s.noisy, f.s.albedo, f.g, opt,
                                              &st, roi, nt);
            ASSERT_FALSE(part.has_error()) << part.geterror();
            EXPECT_EQ(count_bit_differences(roi_pixels(whole, roi),
                                            roi_pixels(part, roi)),
                      0u)
                << "denoise: ROI pixels differ from the whole-image run";
            EXPECT_EQ(st.pixels, (int64_t)roi.npixels())
                << "stats.pixels should count the ROI's pixels";

            ImageBuf zpart = zdenoise::regression_filter(z, f.s.albedo, f.g, opt,
                                                         nullptr, roi, nt);
            ASSERT_FALSE(zpart.has_error()) << zpart.geterror();
            EXPECT_EQ(count_bit_differences(roi_pixels(zwhole, roi),
                                            roi_pixels(zpart, roi)),
                      0u)
                << "regression_filter: ROI pixels differ from the whole-image run";
        }
    }
    }
}

// Moving every input's data window (strips are anchored at its origin)
// changes nothing but the coordinates.
TEST(FilterDeterminism, DataWindowOriginDoesNotChangeTheResult)
{
    Fixture f;
    for (int pyramid : { 0, 4 }) {
    SCOPED_TRACE("pyramid " + std::to_string(pyramid));
    zdenoise::FilterOptions opt;
    opt.r_max          = 6;
    opt.pyramid_radius = pyramid;  // its blocks are anchored at the origin
    ImageBuf ref = zdenoise::denoise(f.s.noisy, f.s.albedo, f.g, opt);
    ASSERT_FALSE(ref.has_error()) << ref.geterror();

    const int ox = -7, oy = 13;
    ImageBuf L = synth::shifted(f.s.noisy, ox, oy);
    ImageBuf A = synth::shifted(f.s.albedo, ox, oy);
    ImageBuf N = synth::shifted(f.s.normal, ox, oy);
    ImageBuf D = synth::shifted(f.s.depth, ox, oy);
    ImageBuf I = synth::shifted(f.s.object_id, ox, oy);
    zdenoise::Guides g;
    g.normal     = &N;
    g.depth      = &D;
    g.object_id  = &I;
    ImageBuf out = zdenoise::denoise(L, A, g, opt, nullptr, {}, 2);
    ASSERT_FALSE(out.has_error()) << out.geterror();
    EXPECT_EQ(out.spec().x, ox);
    EXPECT_EQ(out.spec().y, oy);
    EXPECT_EQ(count_bit_differences(synth::pixels(ref), synth::pixels(out)), 0u)
        << "moving the data window origin changed pixel values";
    }
}

// The progress callback is called, ends at 1, and changes nothing.
TEST(FilterDeterminism, ProgressCallbackChangesNothing)
{
    Scene s = synth::fine_texture(64, 48, { 8, 909 });
    zdenoise::FilterOptions opt;
    opt.r_max    = 6;
    ImageBuf ref = zdenoise::denoise(s.noisy, s.albedo, {}, opt);
    ASSERT_FALSE(ref.has_error()) << ref.geterror();
    std::vector<float> calls;
    opt.progress = [&](float p) { calls.push_back(p); };
    ImageBuf out = zdenoise::denoise(s.noisy, s.albedo, {}, opt, nullptr, {}, 2);
    ASSERT_FALSE(out.has_error()) << out.geterror();
    EXPECT_EQ(count_bit_differences(synth::pixels(ref), synth::pixels(out)), 0u)
        << "a progress callback changed the result";
    ASSERT_FALSE(calls.empty()) << "progress callback never called";
    for (size_t i = 1; i < calls.size(); ++i)
        EXPECT_LE(calls[i - 1], calls[i]) << "progress went backwards";
    EXPECT_GE(calls.front(), 0.0f);
    EXPECT_FLOAT_EQ(calls.back(), 1.0f) << "progress should end at 1";
}

// layered_denoise() reports each layer as its share of the whole: the
// progress of light by path (a direct layer and the rest) never goes back.
TEST(FilterDeterminism, LayeredProgressNeverGoesBack)
{
    Scene a = synth::fine_texture(64, 48, { 8, 909 });
    Scene b = synth::fine_texture(64, 48, { 8, 910 });
    std::vector<zdenoise::Layer> layers(2);
    layers[0].name     = "direct";
    layers[0].radiance = &a.noisy;
    layers[0].albedo   = &a.albedo;
    layers[0].direct   = true;
    layers[1].name     = "rest";
    layers[1].radiance = &b.noisy;
    layers[1].albedo   = &b.albedo;
    zdenoise::FilterOptions opt;
    opt.r_max = 6;
    std::vector<float> calls;
    opt.progress = [&](float p) { calls.push_back(p); };
    ImageBuf out = zdenoise::layered_denoise(layers, nullptr, {}, opt);
    ASSERT_FALSE(out.has_error()) << out.geterror();
    ASSERT_FALSE(calls.empty()) << "progress callback never called";
    for (size_t i = 1; i < calls.size(); ++i)
        ASSERT_LE(calls[i - 1], calls[i]) << "progress went back at report " << i;
    EXPECT_LE(calls.front(), 0.5f) << "the first layer is half of the work";
    EXPECT_FLOAT_EQ(calls.back(), 1.0f) << "progress should end at 1";
}

// Inputs of another pixel type (half) give exactly what the same values
// given as float give.
TEST(FilterDeterminism, HalfInputsEqualFloatInputs)
{
    Scene s = synth::fine_texture(48, 40, { 8, 1001 });
    zdenoise::FilterOptions opt;
    opt.r_max = 5;
    auto to_half = [](const ImageBuf& img) {
        OIIO::ImageSpec spec = img.spec();
        spec.set_format(OIIO::TypeHalf);
        ImageBuf h(spec);
        std::vector<float> px = synth::pixels(img);
        h.set_pixels(h.roi(), OIIO::TypeFloat, px.data());
        return h;
    };
    ImageBuf Lh = to_half(s.noisy), Ah = to_half(s.albedo);
    ImageBuf Lf = synth::shifted(Lh, 0, 0), Af = synth::shifted(Ah, 0, 0);
    ASSERT_EQ(Lf.spec().format, OIIO::TypeFloat);
    ImageBuf outh = zdenoise::denoise(Lh, Ah, {}, opt);
    ImageBuf outf = zdenoise::denoise(Lf, Af, {}, opt);
    ASSERT_FALSE(outh.has_error()) << outh.geterror();
    ASSERT_FALSE(outf.has_error()) << outf.geterror();
    EXPECT_EQ(count_bit_differences(synth::pixels(outh), synth::pixels(outf)), 0u)
        << "half inputs filtered differently from the same values as float";
}


// The noise estimate's 5x5 medians run as a vector kernel on boxes without
// a NaN residual and one by one elsewhere; it takes only minima and maxima,
// so every instruction set gives the same estimate to the bit, next to
// NaN, Inf and zero-albedo pixels (holes) and object borders as inside.
TEST(FilterDeterminism, EveryInstructionSetGivesTheSameNoiseEstimate)
{
    const std::vector<std::string> targets = zdenoise::simd_targets();
    ASSERT_FALSE(targets.empty());
    for (Scene s : { synth::holes(61, 47, { 4, 71 }),
                     synth::two_objects(61, 47, { 4, 72 }) }) {
        const ImageBuf z = zdenoise::demodulate(s.noisy, s.albedo);
        std::vector<std::vector<float>> noise;
        for (const std::string& t : targets) {
            SCOPED_TRACE(t);
            ASSERT_TRUE(zdenoise::set_simd_target(t));
            ImageBuf maps;
            zdenoise::FilterOptions opt;
            opt.select      = 0;
            opt.diagnostics = &maps;
            ImageBuf out    = zdenoise::regression_filter(z, s.albedo, {}, opt);
            ASSERT_FALSE(out.has_error()) << out.geterror();
            ROI r    = maps.roi();
            r.chbegin = 2;  // "noise"
            r.chend   = 3;
            std::vector<float> n(r.npixels());
            ASSERT_TRUE(maps.get_pixels(r, OIIO::TypeFloat, n.data()));
            noise.push_back(n);
            EXPECT_EQ(count_bit_differences(noise.back(), noise.front()), 0u);
        }
        size_t estimated = 0;
        for (float v : noise.front())
            estimated += v > 0.0f;
        EXPECT_GT(estimated, noise.front().size() / 2);
    }
    ASSERT_TRUE(zdenoise::set_simd_target(""));
}
