// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Layered denoising: the library op loses nothing of the beauty when it
// filters nothing, and removes each layer's noise when it does.

#include <cmath>
#include <string>
#include <vector>

#include <zdenoise/zdenoise.h>

#include <gtest/gtest.h>

#include <OpenImageIO/imagebufalgo.h>
#include "synthetic_scenes.h"

using namespace OIIO;

namespace {

constexpr int W = 48, H = 40;

/// a * b per pixel and channel (the first 3 channels).
ImageBuf
product(const ImageBuf& a, const ImageBuf& b)
{
    return ImageBufAlgo::mul(a, b);
}

/// L / colour where colour > 0, else 0: how Cycles writes a lighting pass.
ImageBuf
cycles_divide(const ImageBuf& radiance, const ImageBuf& colour)
{
    ImageBuf q(radiance.spec());
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 3; ++c) {
                const float col = colour.getchannel(x, y, 0, c);
                const float v = col > 0.0f ? radiance.getchannel(x, y, 0, c) / col
                                           : 0.0f;
                float px[3];
                q.getpixel(x, y, px, 3);
                px[c] = v;
                q.setpixel(x, y, px, 3);
            }
    return q;
}

ImageBuf
constant(float v, int nch = 3)
{
    ImageBuf img(ImageSpec(W, H, nch, TypeFloat));
    ImageBufAlgo::fill(img, std::vector<float>(size_t(nch), v));
    return img;
}

float
max_rel_diff(const ImageBuf& a, const ImageBuf& b, int a0 = 0, int b0 = 0)
{
    float m = 0.0f;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 3; ++c) {
                const float u = a.getchannel(x, y, 0, a0 + c);
                const float v = b.getchannel(x, y, 0, b0 + c);
                m = std::max(m, std::fabs(u - v) / (std::fabs(v) + 1e-3f));
            }
    return m;
}

/// A render in Cycles' passes: a diffuse lobe (fine texture), a glossy lobe
/// present on the right part only (colour 0 elsewhere, as Cycles writes an
/// absent lobe), and an emitter block that only the residual holds.
struct LobeRender {
    synth::Scene diffuse = synth::fine_texture(W, H, { 8, 11 });
    synth::Scene glossy  = synth::shadow_edge(W, H, { 8, 12 });
    ImageBuf diff_col, diff_z, gloss_col, gloss_z, emit, beauty, clean,
        denoising_albedo;

    LobeRender()
    {
        diff_col  = diffuse.albedo;
        gloss_col = product(glossy.albedo, constant(0.4f));
        emit      = constant(0.0f);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const float none[3] = { 0.0f, 0.0f, 0.0f };
                if (x < 10)
                    gloss_col.setpixel(x, y, none, 3);
                if (x >= 20 && x < 24 && y >= 16 && y < 20) {
                    const float e[3] = { 5.0f, 4.0f, 3.0f };
                    diff_col.setpixel(x, y, none, 3);
                    gloss_col.setpixel(x, y, none, 3);
                    emit.setpixel(x, y, e, 3);
                }
            }
        diff_z  = cycles_divide(diffuse.noisy, diffuse.albedo);
        gloss_z = cycles_divide(glossy.noisy, glossy.albedo);
        // The renderer's composition, Combined = sum colour * lighting + Emit.
        beauty = ImageBufAlgo::add(
            ImageBufAlgo::add(product(diff_col, diff_z), product(gloss_col, gloss_z)),
            emit);
        ImageBuf clean_gloss = product(gloss_col, cycles_divide(glossy.clean, glossy.albedo));
        clean = ImageBufAlgo::add(
            ImageBufAlgo::add(product(diff_col, cycles_divide(diffuse.clean, diffuse.albedo)),
                              clean_gloss),
            emit);
        denoising_albedo = ImageBufAlgo::add(ImageBufAlgo::add(diff_col, gloss_col), emit);
    }

    std::vector<zdenoise::Layer> layers(bool filter) const
    {
        std::vector<zdenoise::Layer> l(2);
        l[0].name     = "Diff";
        l[0].radiance = &diff_z;
        l[0].albedo   = &diff_col;
        l[1].name     = "Gloss";
        l[1].radiance = &gloss_z;
        l[1].albedo   = &gloss_col;
        for (auto& layer : l) {
            layer.divided = true;
            layer.filter  = filter;
        }
        return l;
    }
};


}  // namespace


// ---- the library op ----

TEST(LayeredDenoise, UnfilteredLayersAndResidualAddUpToTheBeauty)
{
    LobeRender r;
    ImageBuf sum = zdenoise::layered_denoise(r.layers(false), &r.emit);
    ASSERT_FALSE(sum.has_error()) << sum.geterror();
    EXPECT_EQ(sum.nchannels(), 3);
    EXPECT_LT(max_rel_diff(sum, r.beauty), 1e-6f)
        << "with filtering off, the layers (colour x divided lighting, where the "
           "colour is 0 too) plus the residual must give the beauty back";

    // A layer given as radiance (not divided) adds up the same way.
    std::vector<zdenoise::Layer> layers = r.layers(false);
    ImageBuf diff_radiance = product(r.diff_col, r.diff_z);
    layers[0].radiance     = &diff_radiance;
    layers[0].divided      = false;
    EXPECT_LT(max_rel_diff(zdenoise::layered_denoise(layers, &r.emit), r.beauty), 1e-6f);
}


TEST(LayeredDenoise, EachLayerIsDenoisedOnItsOwn)
{
    LobeRender r;
    std::vector<zdenoise::Layer> layers = r.layers(true);
    ImageBuf diff_out, gloss_out;
    layers[0].denoised = &diff_out;
    layers[1].denoised = &gloss_out;
    zdenoise::FilterStats stats;
    ImageBuf out = zdenoise::layered_denoise(layers, &r.emit, {}, {}, &stats);
    ASSERT_FALSE(out.has_error()) << out.geterror();

    const double before = synth::rel_mse(r.beauty, r.clean);
    const double after  = synth::rel_mse(out, r.clean);
    EXPECT_LT(after * 5.0, before) << "relMSE noisy " << before << " -> " << after;
    EXPECT_GT(stats.windows, 0);

    // The output is the sum of what each layer's own filter gives (and the
    // layers handed back are those terms).
    ImageBuf diff_expect = product(zdenoise::regression_filter(r.diff_z, r.diff_col), r.diff_col);
    ImageBufAlgo::clamp(diff_expect, diff_expect, 0.0f, 1e30f);
    EXPECT_LT(max_rel_diff(diff_out, diff_expect), 1e-6f);
    EXPECT_LT(max_rel_diff(out, ImageBufAlgo::add(ImageBufAlgo::add(diff_out, gloss_out), r.emit)),
              1e-5f);
    // The emitter block passes through exactly (it is the residual only).
    float o[3], e[3];
    out.getpixel(21, 17, o, 3);
    r.emit.getpixel(21, 17, e, 3);
    for (int c = 0; c < 3; ++c)
        EXPECT_FLOAT_EQ(o[c], e[c]);
    // Where the glossy lobe is absent its layer contributes exactly 0.
    EXPECT_EQ(gloss_out.getchannel(3, 5, 0, 1), 0.0f);
}


TEST(LayeredDenoise, ErrorsNameTheLayer)
{
    LobeRender r;
    ImageBuf dst;
    EXPECT_FALSE(zdenoise::layered_denoise(dst, {}, nullptr));
    EXPECT_NE(dst.geterror().find("no layers"), std::string::npos) << dst.geterror();

    std::vector<zdenoise::Layer> layers = r.layers(true);
    ImageBuf small(ImageSpec(8, 8, 3, TypeFloat));
    layers[1].albedo = &small;
    ImageBuf out     = zdenoise::layered_denoise(layers, nullptr);
    EXPECT_TRUE(out.has_error());
    EXPECT_NE(out.geterror().find("layer 'Gloss' albedo"), std::string::npos) << out.geterror();
}


