// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Layered denoising: the library op loses nothing of the beauty when it
// filters nothing, and removes each layer's noise when it does; the
// command recognises the conventions of docs/LAYERS.md (Blender Cycles,
// Arnold-style AOVs, specular depth layers, multipart EXR), decodes
// Cryptomatte into the id guide, and writes the output types asked for.

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <OpenImageIO/imageio.h>

#include <zdenoise/zdenoise.h>

#include "cli_test.h"
#include "synthetic_scenes.h"

using namespace OIIO;
using namespace cli_test;

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


/// One named channel of an image, for writing files.
struct Channel {
    std::string name;
    const ImageBuf* image;
    int channel;
};

/// A float image of the channels (all W x H).
ImageBuf
assemble(const std::vector<Channel>& channels)
{
    ImageSpec spec(W, H, int(channels.size()), TypeFloat);
    spec.channelnames.clear();
    for (const Channel& c : channels)
        spec.channelnames.push_back(c.name);
    spec.alpha_channel = -1;
    ImageBuf out(spec);
    std::vector<float> plane(size_t(W) * H);
    for (size_t i = 0; i < channels.size(); ++i) {
        const Channel& c = channels[i];
        c.image->get_pixels(ROI(0, W, 0, H, 0, 1, c.channel, c.channel + 1), TypeFloat,
                            plane.data());
        out.set_pixels(ROI(0, W, 0, H, 0, 1, int(i), int(i) + 1), TypeFloat, plane.data());
    }
    return out;
}

/// Channels LAYER.R,G,B (or the given component names) of `img`.
void
add_rgb(std::vector<Channel>& chans, const std::string& layer, const ImageBuf& img,
        const char* comps = "RGB")
{
    for (int c = 0; comps[c]; ++c)
        chans.push_back({ (layer.empty() ? "" : layer + ".") + std::string(1, comps[c]),
                          &img, c });
}

/// `start` plus the RGB of each named layer of `out` (written by --aovs).
ImageBuf
aov_sum(const ImageBuf& out, std::initializer_list<const char*> names, ImageBuf start)
{
    const ImageSpec& s = out.spec();
    for (const char* layer : names) {
        const int c = s.channelindex(std::string(layer) + ".R");
        EXPECT_GE(c, 0) << "--aovs must write " << layer;
        if (c < 0)
            continue;
        ImageBuf l;
        ImageBufAlgo::channels(l, out, 3, { c, c + 1, c + 2 });
        start = ImageBufAlgo::add(start, l);
    }
    return start;
}

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


TEST(LayeredDenoise, AReflectedLayerKeepsEdgesItsGuidesDoNotShow)
{
    // A glossy layer reflecting a hard light/shadow boundary on a flat,
    // uniformly coloured surface: the guides (one plane, one object) say
    // nothing of the edge, so only the edge test can keep it.
    LobeRender r;
    const ImageBuf clean_gloss_z = cycles_divide(r.glossy.clean, r.glossy.albedo);
    const ImageBuf clean_gloss   = product(r.gloss_col, clean_gloss_z);
    const int ex                 = r.glossy.edge_x;
    auto edge_error = [&](bool reflected) {
        std::vector<zdenoise::Layer> layers = r.layers(true);
        ImageBuf gloss_out;
        layers[1].reflected = reflected;
        layers[1].denoised  = &gloss_out;
        const zdenoise::Guides guides = { &r.glossy.normal, &r.glossy.depth };
        ImageBuf out = zdenoise::layered_denoise(layers, nullptr, guides);
        EXPECT_FALSE(out.has_error()) << out.geterror();
        return std::make_pair(synth::rel_mse(gloss_out, clean_gloss, ex - 3, ex + 3, 0, H),
                              synth::rel_mse(gloss_out, clean_gloss));
    };
    const auto plain = edge_error(false), reflected = edge_error(true);
    // Measured: edge relMSE noisy 0.058, plain 0.047, reflected 0.017.
    EXPECT_LT(reflected.first * 1.5, plain.first)
        << "the stricter edge test of a reflected layer must keep the reflected edge";
    EXPECT_LT(reflected.second * 3.0, synth::rel_mse(product(r.gloss_col, r.gloss_z), clean_gloss))
        << "and still remove the layer's noise";
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


// ---- conventions, through the command ----

class LayersCli : public CliTest {
protected:
    /// The LobeRender as a Blender Cycles multilayer EXR.
    std::string write_cycles(const LobeRender& r, const std::string& name,
                             const ImageBuf* env = nullptr)
    {
        const std::string P = "ViewLayer.";
        ImageBuf alpha = constant(1.0f, 1), zero = constant(0.0f);
        ImageBuf dir = product(r.diff_z, constant(0.7f)), ind = product(r.diff_z, constant(0.3f));
        std::vector<Channel> ch;
        add_rgb(ch, P + "Combined", r.beauty);
        ch.push_back({ P + "Combined.A", &alpha, 0 });
        add_rgb(ch, P + "Denoising Albedo", r.denoising_albedo);
        add_rgb(ch, P + "DiffCol", r.diff_col);
        add_rgb(ch, P + "DiffDir", dir);
        add_rgb(ch, P + "DiffInd", ind);
        add_rgb(ch, P + "GlossCol", r.gloss_col);
        add_rgb(ch, P + "GlossDir", r.gloss_z);
        add_rgb(ch, P + "GlossInd", zero);
        add_rgb(ch, P + "Emit", r.emit);
        add_rgb(ch, P + "Env", env ? *env : zero);
        ImageBuf img = assemble(ch);
        EXPECT_TRUE(img.write(path(name))) << img.geterror();
        return path(name);
    }

    /// Arnold-style AOVs of the LobeRender (diffuse, specular with their
    /// albedos; N, Z; emission only in the beauty).
    std::vector<Channel> arnold_channels(const LobeRender& r, std::vector<ImageBuf>& keep)
    {
        keep.clear();
        keep.reserve(8);
        keep.push_back(product(r.diff_col, r.diff_z));    // 0 diffuse
        keep.push_back(product(r.gloss_col, r.gloss_z));  // 1 specular
        keep.push_back(constant(1.0f, 1));                // 2 alpha
        keep.push_back(r.glossy.normal);                  // 3 N
        keep.push_back(r.glossy.depth);                   // 4 Z
        std::vector<Channel> ch;
        add_rgb(ch, "", r.beauty);
        ch.push_back({ "A", &keep[2], 0 });
        add_rgb(ch, "diffuse", keep[0]);
        add_rgb(ch, "diffuse_albedo", r.diff_col);
        add_rgb(ch, "specular", keep[1]);
        add_rgb(ch, "specular_albedo", r.gloss_col);
        add_rgb(ch, "N", keep[3], "XYZ");
        ch.push_back({ "Z", &keep[4], 0 });
        return ch;
    }
};


TEST_F(LayersCli, CyclesLobesAreFoundAndTheirAovsAddUpToTheBeauty)
{
    LobeRender r;
    const std::string in = write_cycles(r, "cycles.exr");
    RunResult res = run("--in " + in + " -o " + path("out.exr") + " --mode layers --aovs -v");
    ASSERT_EQ(res.status, 0) << res.err;
    for (const char* needle : { "Blender Cycles", "layer     ViewLayer.Diff: ViewLayer.DiffDir",
                                "ViewLayer.DiffInd", "albedo ViewLayer.DiffCol", "(divided by it)",
                                "layer     ViewLayer.Gloss",
                                "ViewLayer.GlossCol.B (divided by it) (reflected: stricter edge test)",
                                "residual  ViewLayer.Env.R,ViewLayer.Env.G,ViewLayer.Env.B, not filtered",
                                "ViewLayer.Residual: the beauty minus the layers minus ViewLayer.Env.R,"
                                "ViewLayer.Env.G,ViewLayer.Env.B with albedo ViewLayer.Denoising Albedo" })
        EXPECT_NE(res.out.find(needle), std::string::npos) << "-v lacks '" << needle << "':\n"
                                                           << res.out;
    EXPECT_EQ(res.out.find("ViewLayer.Trans"), std::string::npos) << "no Trans passes were written";
    EXPECT_NE(res.out.find("mode layers: 3 layer(s)"), std::string::npos)
        << "Diff, Gloss and the residual:\n" << res.out;

    ImageBuf out(path("out.exr"));
    ASSERT_TRUE(out.read(0, 0, true, TypeFloat)) << out.geterror();
    const ImageSpec& s = out.spec();
    const int combined = s.channelindex("ViewLayer.Combined.R");
    ImageBuf sum = constant(0.0f);
    for (const char* layer : { "ViewLayer.Diff", "ViewLayer.Gloss", "ViewLayer.Residual" }) {
        const int c = s.channelindex(std::string(layer) + ".R");
        ASSERT_GE(c, 0) << "--aovs must write " << layer;
        ImageBuf l;
        ImageBufAlgo::channels(l, out, 3, { c, c + 1, c + 2 });
        sum = ImageBufAlgo::add(sum, l);
    }
    EXPECT_LT(max_rel_diff(out, sum, combined, 0), 1e-5f)
        << "the denoised layers written with --aovs must add up to the denoised beauty";
    ImageBuf beauty;
    ImageBufAlgo::channels(beauty, out, 3, { combined, combined + 1, combined + 2 });
    EXPECT_LT(synth::rel_mse(beauty, r.clean) * 3.0, synth::rel_mse(r.beauty, r.clean));
}


TEST_F(LayersCli, CyclesLobeColoursArePrefilteredWithTheRendersSamples)
{
    // Cycles' DiffCol, GlossCol, TransCol and the residual's Denoising
    // Albedo are pixel means of the render's samples, with the same
    // coverage noise at texture and object edges as beauty mode's albedo:
    // each is prefiltered (docs/LAYERS.md, "Colours"), and remodulation no
    // longer multiplies that noise back (public set, 4 spp: 8-23 % lower
    // relMSE).
    const std::string in = kSourceDir + "/share/samples/cornell_textured_spp16_crop.exr";
    const std::string ref = kSourceDir + "/share/samples/cornell_textured_ref_crop.exr";
    RunResult r = run("--in '" + in + "' -o '" + path("pre.exr") + "' --mode layers -v");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("colours   prefiltered as 16 samples a pixel "
                         "(cycles.ViewLayer.samples): ViewLayer.Diff, ViewLayer.Gloss, "
                         "ViewLayer.Trans, ViewLayer.Residual"),
              std::string::npos)
        << r.out;
    r = run("--in '" + in + "' -o '" + path("plain.exr") + "' --mode layers --no-albedo-prefilter -v");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("colours   not prefiltered (--no-albedo-prefilter)"), std::string::npos)
        << r.out;
    ImageBuf pre(path("pre.exr")), plain(path("plain.exr")), truth(ref);
    ASSERT_TRUE(pre.read(0, 0, true, TypeFloat));
    ASSERT_TRUE(plain.read(0, 0, true, TypeFloat));
    const double with = synth::rel_mse(pre, truth), without = synth::rel_mse(plain, truth);
    std::printf("  bundled crop, layers: relMSE %.5f without the prefilter, %.5f with\n",
                without, with);
    EXPECT_LT(with, 0.985 * without);  // 0.00195 against 0.00202 when written
    EXPECT_NE(pre.spec().get_string_attribute("zdenoise.parameters")
                  .find("mode=layers albedo-samples=16"),
              std::string::npos);
    // The colour passes themselves are carried through as they were.
    ImageBuf noisy(in);
    for (const char* name : { "ViewLayer.DiffCol.G", "ViewLayer.GlossCol.R" }) {
        const int c = pre.spec().channelindex(name);
        ASSERT_GE(c, 0) << name;
        for (int y = 0; y < 96; y += 7)
            for (int x = 0; x < 96; x += 5)
                ASSERT_EQ(pre.getchannel(x, y, 0, c), noisy.getchannel(x, y, 0, c)) << name;
    }
}


TEST_F(LayersCli, TextureSeenInAMirrorIsKept)
{
    // The right half is a mirror (no diffuse colour, a flat GlossCol 0.9)
    // reflecting a finely textured wall; Cycles divides the reflected light
    // by GlossCol, so the texture is in the quotient, while its Denoising
    // Albedo passes through the mirror to the wall's texture. Where
    // DiffCol is 0 the glossy lobe is divided by the Denoising Albedo
    // instead (docs/LAYERS.md, "Mirrors and glass"), as beauty mode does.
    synth::Scene wall = synth::fine_texture(W, H, { 8, 31 });
    const int mirror_x = W / 2;
    ImageBuf diff_col = wall.albedo, gloss_col = constant(0.0f), den = wall.albedo;
    ImageBuf diff_z = cycles_divide(wall.noisy, wall.albedo), gloss_z = constant(0.0f);
    ImageBuf beauty = wall.noisy, clean = wall.clean;
    for (int y = 0; y < H; ++y)
        for (int x = mirror_x; x < W; ++x)
            for (int c = 0; c < 3; ++c) {
                const float tint = 0.9f;
                auto set = [&](ImageBuf& img, float v) {
                    float px[3];
                    img.getpixel(x, y, px, 3);
                    px[c] = v;
                    img.setpixel(x, y, px, 3);
                };
                set(diff_col, 0.0f);
                set(diff_z, 0.0f);
                set(gloss_col, tint);
                set(gloss_z, wall.noisy.getchannel(x, y, 0, c));
                set(den, tint * wall.albedo.getchannel(x, y, 0, c));
                set(beauty, tint * wall.noisy.getchannel(x, y, 0, c));
                set(clean, tint * wall.clean.getchannel(x, y, 0, c));
            }
    const std::string P = "ViewLayer.";
    ImageBuf alpha = constant(1.0f, 1), zero = constant(0.0f);
    std::vector<Channel> ch;
    add_rgb(ch, P + "Combined", beauty);
    ch.push_back({ P + "Combined.A", &alpha, 0 });
    add_rgb(ch, P + "Denoising Albedo", den);
    add_rgb(ch, P + "DiffCol", diff_col);
    add_rgb(ch, P + "DiffDir", diff_z);
    add_rgb(ch, P + "DiffInd", zero);
    add_rgb(ch, P + "GlossCol", gloss_col);
    add_rgb(ch, P + "GlossDir", gloss_z);
    add_rgb(ch, P + "GlossInd", zero);
    add_rgb(ch, P + "Emit", zero);
    add_rgb(ch, P + "Env", zero);
    ImageBuf file = assemble(ch);
    ASSERT_TRUE(file.write(path("mirror.exr"))) << file.geterror();

    RunResult r = run("--in " + path("mirror.exr") + " -o " + path("through.exr")
                      + " --mode layers -v");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("layer     ViewLayer.Gloss: over ViewLayer.Denoising Albedo.R,"
                         "ViewLayer.Denoising Albedo.G,ViewLayer.Denoising Albedo.B where "
                         "ViewLayer.DiffCol is 0 (mirrors, clear glass)"),
              std::string::npos)
        << r.out;
    // The same lobes given with --layer: divided by GlossCol everywhere.
    r = run("--in " + path("mirror.exr") + " -o " + path("flat.exr")
            + " --layer diffuse=DiffDir+DiffInd:DiffCol:divided"
              " --layer glossy=GlossDir+GlossInd:GlossCol:divided:reflected");
    ASSERT_EQ(r.status, 0) << r.err;
    ImageBuf through(path("through.exr")), flat(path("flat.exr"));
    ASSERT_TRUE(through.read(0, 0, true, TypeFloat)) << through.geterror();
    ASSERT_TRUE(flat.read(0, 0, true, TypeFloat)) << flat.geterror();
    const double noisy_err   = synth::rel_mse(beauty, clean, mirror_x, W, 0, H);
    const double through_err = synth::rel_mse(through, clean, mirror_x, W, 0, H);
    const double flat_err    = synth::rel_mse(flat, clean, mirror_x, W, 0, H);
    std::printf("  mirror half: relMSE noisy %.5f, over GlossCol %.5f, over the Denoising "
                "Albedo %.5f\n", noisy_err, flat_err, through_err);
    EXPECT_LT(through_err * 2.0, flat_err) << "the texture seen in the mirror must be kept";
    EXPECT_LT(through_err * 3.0, noisy_err);
    // The diffuse half is not touched by it: its pixels are flat's, to
    // float rounding (measured: 6e-8 at most).
    float worst = 0.0f;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < mirror_x - 4; ++x)
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, std::fabs(through.getchannel(x, y, 0, c)
                                                  - flat.getchannel(x, y, 0, c)));
    EXPECT_LE(worst, 1e-6f) << "the mirror's routing changed the diffuse half";
}


TEST_F(LayersCli, CyclesEnvironmentIsAddedAsItIs)
{
    // The environment seen directly: a sharp, bright checker in the
    // beauty's Env pass (and, as Cycles does, in Denoising Albedo).
    LobeRender r;
    ImageBuf env = constant(0.0f);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            if (y < 8 && ((x / 2 + y / 2) % 2)) {
                const float e[3] = { 2.0f, 2.5f, 3.0f };
                env.setpixel(x, y, e, 3);
            }
    r.beauty           = ImageBufAlgo::add(r.beauty, env);
    r.denoising_albedo = ImageBufAlgo::add(r.denoising_albedo, env);
    // No emitter: the residual layer is empty but for rounding.
    r.beauty           = ImageBufAlgo::sub(r.beauty, r.emit);
    r.denoising_albedo = ImageBufAlgo::sub(r.denoising_albedo, r.emit);
    r.emit             = constant(0.0f);
    const std::string in = write_cycles(r, "cycles_env.exr", &env);
    RunResult res = run("--in " + in + " -o " + path("out.exr") + " --mode layers --aovs -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("residual  ViewLayer.Env.R,ViewLayer.Env.G,ViewLayer.Env.B, not "
                           "filtered"),
              std::string::npos)
        << res.out;
    EXPECT_NE(res.out.find("ViewLayer.Residual.R,G,B (mean radius 0.00)"), std::string::npos)
        << "no window is spent on a residual that holds only rounding:\n" << res.out;

    ImageBuf out(path("out.exr"));
    ASSERT_TRUE(out.read(0, 0, true, TypeFloat)) << out.geterror();
    const ImageSpec& s = out.spec();
    const ImageBuf sum
        = aov_sum(out, { "ViewLayer.Diff", "ViewLayer.Gloss", "ViewLayer.Residual" }, env);
    EXPECT_LT(max_rel_diff(out, sum, s.channelindex("ViewLayer.Combined.R"), 0), 1e-5f)
        << "the output must be the denoised layers plus the environment exactly as rendered";
}


TEST_F(LayersCli, PathModeFiltersTheDirectLightApartAndAddsUp)
{
    LobeRender r;
    const std::string in = write_cycles(r, "cycles_path.exr");
    RunResult res = run("--in " + in + " -o " + path("out.exr") + " --mode path --aovs -v");
    ASSERT_EQ(res.status, 0) << res.err;
    for (const char* needle :
         { "mode path: the direct light apart from the rest, 2 layer(s)",
           "layer     ViewLayer.DiffDir: ViewLayer.DiffDir.R,ViewLayer.DiffDir.G,"
           "ViewLayer.DiffDir.B with albedo ViewLayer.DiffCol",
           "(direct: structure beyond its noise kept)",
           "ViewLayer.Residual: the beauty minus the layers with albedo "
           "ViewLayer.Denoising Albedo" })
        EXPECT_NE(res.out.find(needle), std::string::npos) << "-v lacks '" << needle << "':\n"
                                                           << res.out;
    ImageBuf out(path("out.exr"));
    ASSERT_TRUE(out.read(0, 0, true, TypeFloat)) << out.geterror();
    const ImageSpec& s = out.spec();
    const ImageBuf sum
        = aov_sum(out, { "ViewLayer.DiffDir", "ViewLayer.Residual" },
                  constant(0.0f));
    EXPECT_LT(max_rel_diff(out, sum, s.channelindex("ViewLayer.Combined.R"), 0), 1e-5f)
        << "the direct light and the rest must add up to the denoised beauty";
    EXPECT_EQ(res.out.find("not filtered"), std::string::npos)
        << "path mode keeps the environment in the residual:\n" << res.out;
    ImageBuf beauty;
    const int combined = s.channelindex("ViewLayer.Combined.R");
    ImageBufAlgo::channels(beauty, out, 3, { combined, combined + 1, combined + 2 });
    // Less than layers mode's 3x: this render's DiffDir and DiffInd are one
    // noise scaled (0.7 and 0.3 of it), equally clean, which no render's
    // are; the split has nothing to gain, the direct light is routed back
    // into the residual where it is no cleaner, and the direct layer's
    // 5-px significance filter is noisier than the regression where it
    // fires.
    EXPECT_LT(synth::rel_mse(beauty, r.clean) * 1.2, synth::rel_mse(r.beauty, r.clean));

    // A Cycles file without the direct light apart is refused by name.
    std::vector<Channel> ch;
    add_rgb(ch, "ViewLayer.Combined", r.beauty);
    add_rgb(ch, "ViewLayer.Denoising Albedo", r.denoising_albedo);
    ImageBuf plain = assemble(ch);
    ASSERT_TRUE(plain.write(path("plain.exr"))) << plain.geterror();
    RunResult refused = run("--in " + path("plain.exr") + " -o " + path("bad.exr")
                            + " --mode path");
    expect_one_line_error(refused, "--mode path: '" + path("plain.exr")
                                       + "' has no direct light pass apart");
}


TEST_F(LayersCli, ArnoldStyleAovsSinglePartAndMultipart)
{
    LobeRender r;
    std::vector<ImageBuf> keep;
    std::vector<Channel> ch = arnold_channels(r, keep);
    ImageBuf one = assemble(ch);
    ASSERT_TRUE(one.write(path("arnold.exr"))) << one.geterror();

    // The same AOVs as a multipart EXR: the beauty in part "rgba" (R,G,B,A,
    // N, Z), each AOV in a part named after it with channels R,G,B.
    {
        std::vector<ImageSpec> specs;
        std::vector<std::vector<Channel>> parts;
        parts.push_back({ ch[0], ch[1], ch[2], ch[3] });
        for (size_t i = 16; i < ch.size(); ++i)
            parts[0].push_back(ch[i]);
        for (size_t a = 0; a < 4; ++a) {
            std::vector<Channel> p(ch.begin() + 4 + 3 * long(a), ch.begin() + 7 + 3 * long(a));
            for (Channel& c : p)
                c.name = c.name.substr(c.name.find('.') + 1);
            parts.push_back(p);
        }
        const char* names[] = { "rgba", "diffuse", "diffuse_albedo", "specular", "specular_albedo" };
        std::vector<ImageBuf> bufs;
        for (size_t i = 0; i < parts.size(); ++i) {
            bufs.push_back(assemble(parts[i]));
            ImageSpec spec = bufs.back().spec();
            spec.attribute("name", names[i]);
            specs.push_back(spec);
        }
        auto outp = ImageOutput::create(path("multipart.exr"));
        ASSERT_TRUE(outp && outp->supports("multiimage"));
        ASSERT_TRUE(outp->open(path("multipart.exr"), int(specs.size()), specs.data()))
            << outp->geterror();
        for (size_t i = 0; i < bufs.size(); ++i) {
            if (i > 0) {
                ASSERT_TRUE(outp->open(path("multipart.exr"), specs[i],
                                       ImageOutput::AppendSubimage));
            }
            ASSERT_TRUE(bufs[i].write(outp.get())) << bufs[i].geterror();
        }
        outp->close();
    }

    ImageBuf results[2];
    const char* files[] = { "arnold.exr", "multipart.exr" };
    for (int f = 0; f < 2; ++f) {
        const std::string out = path(std::string("out_") + files[f]);
        RunResult res = run("--in " + path(files[f]) + " -o " + out + " --mode layers -v");
        ASSERT_EQ(res.status, 0) << files[f] << ": " << res.err;
        for (const char* needle : { "Arnold style", "layer     diffuse: diffuse.R",
                                    "with albedo diffuse_albedo.R", "layer     specular",
                                    "specular_albedo.B (reflected: stricter edge test)",
                                    "residual  the beauty minus the layers, not filtered",
                                    "normal    '", "channels N.X,N.Y,N.Z", "channels Z" })
            EXPECT_NE(res.out.find(needle), std::string::npos)
                << files[f] << ": -v lacks '" << needle << "':\n"
                << res.out;
        results[f].reset(out);
        ASSERT_TRUE(results[f].read(0, 0, true, TypeFloat)) << results[f].geterror();
        EXPECT_EQ(results[f].nsubimages(), 1) << "the output is one multilayer part";
        EXPECT_LT(synth::rel_mse(results[f], r.clean) * 3.0, synth::rel_mse(r.beauty, r.clean))
            << files[f];
    }
    EXPECT_GE(results[1].spec().channelindex("diffuse_albedo.G"), 0)
        << "every part's channels are carried into the output under PART.CHANNEL";
    EXPECT_LT(max_rel_diff(results[0], results[1]), 1e-6f)
        << "one part or many, the same channels give the same result";
}


TEST_F(LayersCli, SpecularDepthLayersAndExplicitLayersOverrideDetection)
{
    LobeRender r;
    ImageBuf spec0 = product(r.diff_col, r.diff_z), spec1 = product(r.gloss_col, r.gloss_z);
    ImageBuf alpha = constant(1.0f, 1);
    std::vector<Channel> ch;
    add_rgb(ch, "", r.beauty);
    ch.push_back({ "A", &alpha, 0 });
    add_rgb(ch, "spec0", spec0);
    add_rgb(ch, "spec0_albedo", r.diff_col);
    add_rgb(ch, "spec1", spec1);
    add_rgb(ch, "spec1_albedo", r.gloss_col);
    add_rgb(ch, "residual", r.emit);
    ImageBuf img = assemble(ch);
    ASSERT_TRUE(img.write(path("spec.exr")));

    RunResult res = run("--in " + path("spec.exr") + " -o " + path("out.exr") + " --mode layers -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_EQ(res.out.find("spec0_albedo.B (reflected"), std::string::npos)
        << "spec0 (no specular event) is not reflected:\n" << res.out;
    for (const char* needle : { "specular depth layers", "layer     spec0: spec0.R",
                                "layer     spec1: spec1.R",
                                "spec1_albedo.B (reflected: stricter edge test)",
                                "residual  residual.R,residual.G,"
                                "residual.B, not filtered" })
        EXPECT_NE(res.out.find(needle), std::string::npos) << "-v lacks '" << needle << "':\n"
                                                           << res.out;

    // --layer replaces the detected layers (and implies --mode layers);
    // --residual the residual.
    res = run("--in " + path("spec.exr") + " -o " + path("out2.exr")
              + " --layer first=spec0:spec0_albedo:reflected --residual spec1+residual -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("mode layers: 1 layer(s) (--layer)"), std::string::npos) << res.out;
    EXPECT_NE(res.out.find("layer     first: spec0.R"), std::string::npos) << res.out;
    EXPECT_NE(res.out.find("spec0_albedo.B (reflected: stricter edge test)"), std::string::npos)
        << "--layer ...:reflected marks the layer:\n" << res.out;
    EXPECT_NE(res.out.find("residual  spec1.R,spec1.G,spec1.B + residual.R"), std::string::npos)
        << res.out;
    EXPECT_EQ(res.out.find("layer     spec1"), std::string::npos) << res.out;

    expect_one_line_error(run("--in " + path("spec.exr") + " -o " + path("o.exr")
                              + " --layer nonsense"),
                          "--layer");
    write_image("plain.exr", W, H, { "R", "G", "B" }, 0.5f);
    RunResult none = run("--in " + path("plain.exr") + " -o " + path("o.exr") + " --mode layers");
    expect_one_line_error(none, "no layers found");
}


TEST_F(LayersCli, CryptomatteRanksAreTheObjectIdGuide)
{
    synth::Scene s = synth::two_objects_cryptomatte(W, H, { 16, 606 }, 0.2f);
    ImageBuf alpha = constant(1.0f, 1);
    std::vector<Channel> ch;
    const std::string P = "ViewLayer.";
    add_rgb(ch, P + "Combined", s.noisy);
    ch.push_back({ P + "Combined.A", &alpha, 0 });
    add_rgb(ch, P + "Denoising Albedo", s.albedo);
    add_rgb(ch, P + "CryptoObject00", s.object_id, "rgba");
    ch.push_back({ P + "IndexOB.X", &s.object_id, 0 });  // rank 0's id
    ImageBuf img = assemble(ch);
    img.specmod().attribute("cryptomatte/0123abc/name", "ViewLayer.CryptoObject");
    img.specmod().attribute("cryptomatte/0123abc/manifest", "{\"a\":\"3ea0c9e0\"}");
    ASSERT_TRUE(img.write(path("crypto.exr")));

    RunResult res = run("--in " + path("crypto.exr") + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("mode beauty"), std::string::npos) << "beauty is the default";
    EXPECT_NE(res.out.find("channels ViewLayer.CryptoObject00.r,ViewLayer.CryptoObject00.g,"
                           "ViewLayer.CryptoObject00.b,ViewLayer.CryptoObject00.a"),
              std::string::npos)
        << "the id guide must be the Cryptomatte rank pairs, not IndexOB:\n"
        << res.out;

    // The command gives what the library gives with the (id, coverage)
    // guide, so the anti-aliased column weighs both objects by coverage.
    zdenoise::Guides g;
    g.object_id   = &s.object_id;
    ImageBuf want = zdenoise::denoise(s.noisy, s.albedo, g);
    ImageBuf out(path("out.exr"));
    ASSERT_TRUE(out.read(0, 0, true, TypeFloat));
    EXPECT_LT(max_rel_diff(out, want), 1e-6f);
    // What bleeds across is the anti-aliased column's share of the bright
    // object (within the overlap weight's coverage); the value term holds
    // it back. Its noise scale (value_noise, docs/FILTER.md section 5)
    // lets more through at 16 spp: the first dark column +14.6 % with
    // value_noise 0, +20.2 % with 1; a quarter is the bound.
    const int blend = s.edge_x - 1;
    for (int x : { blend - 2, blend - 1, blend + 1, blend + 2 }) {
        const double truth = synth::mean_luminance(s.clean, x, x + 1, 0, H);
        const double got   = synth::mean_luminance(out, x, x + 1, 0, H);
        std::printf("  column %d: %.4f, truth %.4f (%+.1f %%)\n", x, got, truth,
                    100.0 * (got - truth) / truth);
        EXPECT_LT(std::fabs(got - truth) / truth, 0.25) << "column " << x;
    }
}


// Blender writes the compositor's output as a layer of its own
// ("Composite.Combined", no other pass) and each view layer as another; the
// EXR's sorted channel list puts "Back." and "Composite." before
// "ViewLayer.". The render is the layer with a Denoising Albedo, and its
// guides are its own (not Back's Cryptomatte); the other layers are kept.
TEST_F(LayersCli, CyclesCompositeAndOtherViewLayersAreNotTheRender)
{
    synth::Scene s     = synth::two_objects_cryptomatte(W, H, { 16, 808 }, 0.2f);
    synth::Scene other = synth::two_objects_cryptomatte(W, H, { 8, 42 }, 0.2f);
    ImageBuf alpha = constant(1.0f, 1), grey = constant(0.25f);
    std::vector<Channel> ch;
    add_rgb(ch, "Back.Combined", grey);
    ch.push_back({ "Back.Combined.A", &alpha, 0 });
    add_rgb(ch, "Back.CryptoObject00", other.object_id, "rgba");
    add_rgb(ch, "Composite.Combined", grey);
    ch.push_back({ "Composite.Combined.A", &alpha, 0 });
    const std::string P = "ViewLayer.";
    add_rgb(ch, P + "Combined", s.noisy);
    ch.push_back({ P + "Combined.A", &alpha, 0 });
    add_rgb(ch, P + "Denoising Albedo", s.albedo);
    add_rgb(ch, P + "CryptoObject00", s.object_id, "rgba");
    ImageBuf img = assemble(ch);
    ASSERT_TRUE(img.write(path("composite.exr")));

    RunResult res = run("--in " + path("composite.exr") + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("Blender Cycles multilayer EXR (layer 'ViewLayer.')"),
              std::string::npos)
        << res.out;
    EXPECT_NE(res.out.find("channels ViewLayer.CryptoObject00.r,ViewLayer.CryptoObject00.g,"
                           "ViewLayer.CryptoObject00.b,ViewLayer.CryptoObject00.a"),
              std::string::npos)
        << "the id guide must be the view layer's own Cryptomatte:\n"
        << res.out;

    zdenoise::Guides g;
    g.object_id   = &s.object_id;
    ImageBuf want = zdenoise::denoise(s.noisy, s.albedo, g);
    ImageBuf out(path("out.exr"));
    ASSERT_TRUE(out.read(0, 0, true, TypeFloat));
    const ImageSpec& os = out.spec();
    EXPECT_LT(max_rel_diff(out, want, os.channelindex(P + "Combined.R"), 0), 1e-6f);
    for (const char* layer : { "Back.Combined.R", "Composite.Combined.R" })
        EXPECT_LT(max_rel_diff(out, grey, os.channelindex(layer), 0), 1e-6f)
            << layer << " is kept as it is";
}


// Half buffers given as Cycles files of their own take their Combined pass,
// as --in does, not the file's first three channels (CryptoObject00.r,g,b
// in a Cycles file): the command gives what the library gives with the
// halves' radiance.
TEST_F(LayersCli, CyclesHalvesTakeTheirCombinedPass)
{
    synth::Scene s = synth::two_objects_cryptomatte(W, H, { 16, 707 }, 0.2f);
    ImageBuf alpha = constant(1.0f, 1);
    const std::string P = "ViewLayer.";
    auto write = [&](const ImageBuf& radiance, const std::string& name) {
        std::vector<Channel> ch;
        add_rgb(ch, P + "Combined", radiance);
        ch.push_back({ P + "Combined.A", &alpha, 0 });
        add_rgb(ch, P + "CryptoObject00", s.object_id, "rgba");
        add_rgb(ch, P + "Denoising Albedo", s.albedo);
        ImageBuf img = assemble(ch);
        EXPECT_TRUE(img.write(path(name))) << img.geterror();
        return path(name);
    };
    const std::string in = write(s.noisy, "frame.exr");
    const std::string a = write(s.half_a, "half_a.exr"), b = write(s.half_b, "half_b.exr");
    RunResult res = run("--in " + in + " --halves " + a + " " + b + " -o "
                        + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("half A    '" + a + "' channels ViewLayer.Combined.R,"
                           "ViewLayer.Combined.G,ViewLayer.Combined.B"),
              std::string::npos)
        << res.out;
    zdenoise::Guides g;
    g.object_id   = &s.object_id;
    g.half_a      = &s.half_a;
    g.half_b      = &s.half_b;
    ImageBuf want = zdenoise::denoise(s.noisy, s.albedo, g);
    ImageBuf out(path("out.exr"));
    ASSERT_TRUE(out.read(0, 0, true, TypeFloat));
    EXPECT_LT(max_rel_diff(out, want), 1e-6f);
}


TEST_F(LayersCli, OutputTypeOptionKeepsCryptomatteFloat)
{
    LobeRender r;
    ImageBuf alpha = constant(1.0f, 1);
    std::vector<Channel> ch;
    const std::string P = "ViewLayer.";
    add_rgb(ch, P + "Combined", r.beauty);
    ch.push_back({ P + "Combined.A", &alpha, 0 });
    add_rgb(ch, P + "Denoising Albedo", r.denoising_albedo);
    ImageBuf ranks = constant(0.25f, 4);
    add_rgb(ch, P + "CryptoObject00", ranks, "rgba");
    ImageBuf img = assemble(ch);
    img.specmod().attribute("cryptomatte/0123abc/name", "ViewLayer.CryptoObject");
    img.specmod().attribute("cryptomatte/0123abc/manifest", "{\"a\":\"3ea0c9e0\"}");
    std::vector<TypeDesc> types(ch.size(), TypeHalf);
    for (size_t i = 7; i < types.size(); ++i)
        types[i] = TypeFloat;
    img.set_write_format(types);
    ASSERT_TRUE(img.write(path("in.exr")));

    // (EXR stores channels sorted by name: look them up by name.)
    auto type_of = [&](const std::string& file, const std::string& channel) {
        auto in = ImageInput::open(path(file));
        EXPECT_TRUE(in);
        EXPECT_EQ(in->spec().get_string_attribute("cryptomatte/0123abc/manifest"),
                  "{\"a\":\"3ea0c9e0\"}");
        const int c = in->spec().channelindex(channel);
        EXPECT_GE(c, 0) << channel;
        return in->spec().channelformat(c);
    };
    for (const char* d : { "", "-d half", "-d float" }) {
        RunResult res = run("--in " + path("in.exr") + " -o " + path("out.exr") + " " + d);
        ASSERT_EQ(res.status, 0) << d << ": " << res.err;
        const TypeDesc beauty = std::string(d) == "-d float" ? TypeFloat : TypeHalf;
        for (size_t i = 0; i < ch.size(); ++i)
            EXPECT_EQ(type_of("out.exr", ch[i].name), i < 7 ? beauty : TypeFloat)
                << "'" << d << "' channel " << ch[i].name
                << (i < 7 ? "" : ": Cryptomatte channels stay float");
    }
    expect_one_line_error(run("--in " + path("in.exr") + " -o " + path("o.exr") + " -d int"),
                          "-d");
}


// ---- role files and the auxiliary image (--aux, docs/AUX.md) ----

// A Cycles frame of two_objects_cryptomatte whose Denoising Albedo is the
// scene's albedo times `albedo_scale` (a stand-in for a render's own,
// noisier albedo), with Denoising Normal and Depth when `guides`.
class AuxCli : public LayersCli {
protected:
    synth::Scene s = synth::two_objects_cryptomatte(W, H, { 16, 709 }, 0.2f);
    ImageBuf alpha = constant(1.0f, 1);
    ImageBuf own_albedo = product(s.albedo, constant(0.8f));

    std::string write_frame(const std::string& name, const ImageBuf& albedo,
                            bool guides = false)
    {
        const std::string P = "ViewLayer.";
        std::vector<Channel> ch;
        add_rgb(ch, P + "Combined", s.noisy);
        ch.push_back({ P + "Combined.A", &alpha, 0 });
        add_rgb(ch, P + "CryptoObject00", s.object_id, "rgba");
        add_rgb(ch, P + "Denoising Albedo", albedo);
        if (guides) {
            add_rgb(ch, P + "Denoising Normal", s.normal, "XYZ");
            ch.push_back({ P + "Denoising Depth.Z", &s.depth, 0 });
        }
        ImageBuf img = assemble(ch);
        EXPECT_TRUE(img.write(path(name))) << img.geterror();
        return path(name);
    }

    std::string write_rgb(const std::string& name, const ImageBuf& rgb)
    {
        std::vector<Channel> ch;
        add_rgb(ch, "", rgb);
        ImageBuf img = assemble(ch);
        EXPECT_TRUE(img.write(path(name))) << img.geterror();
        return path(name);
    }

    ImageBuf output(const std::string& name)
    {
        ImageBuf out(path(name));
        EXPECT_TRUE(out.read(0, 0, true, TypeFloat)) << out.geterror();
        return out;
    }

    zdenoise::Guides crypto_guides() const
    {
        zdenoise::Guides g;
        g.object_id = &s.object_id;
        return g;
    }
};


// --albedo given a Cycles file of its own takes its Denoising Albedo, not
// its first three channels (CryptoObject00.r,g,b); a file of several layers
// with no albedo by a convention is refused with its layers named.
TEST_F(AuxCli, AlbedoFileOfSeveralLayersGivesItsAlbedoLayer)
{
    const std::string in    = write_frame("frame.exr", own_albedo);
    const std::string other = write_frame("other.exr", s.albedo);
    RunResult res = run("--in " + in + " --albedo " + other + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("albedo    '" + other + "' channels ViewLayer.Denoising Albedo.R,"),
              std::string::npos)
        << res.out;
    EXPECT_LT(max_rel_diff(output("out.exr"),
                           zdenoise::denoise(s.noisy, s.albedo, crypto_guides())),
              1e-6f);

    std::vector<Channel> ch;
    add_rgb(ch, "foo", s.albedo);
    add_rgb(ch, "bar", s.albedo, "rgb");
    ImageBuf img = assemble(ch);
    ASSERT_TRUE(img.write(path("layers.exr")));
    for (const char* flag : { "--albedo", "--normal" }) {
        res = run("--in " + in + " " + flag + " " + path("layers.exr") + " -o " + path("o2.exr"));
        expect_one_line_error(res, "layers.exr");
        EXPECT_NE(res.err.find("bar, foo"), std::string::npos) << res.err;
        EXPECT_EQ(res.status, 1);
    }
    // A :ch= selection still chooses any of them.
    res = run("--in " + in + " --albedo:ch=bar " + path("layers.exr") + " -o " + path("o3.exr"));
    EXPECT_EQ(res.status, 0) << res.err;
}


// --aux with a plain RGB image: by default the auxiliary albedo
// demodulates and remodulates (docs/AUX.md); with the internal switch
// ZDENOISE_AUX_DEMODULATE=render the render's own albedo demodulates and
// the auxiliary one remodulates (the library's denoise() with a
// remodulation albedo).
TEST_F(AuxCli, AuxAlbedoRemodulates)
{
    const std::string in  = write_frame("frame.exr", own_albedo);
    const std::string aux = write_rgb("aux.exr", s.albedo);
    RunResult res = run("--in " + in + " --aux " + aux + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("plain R,G,B image (an albedo)"), std::string::npos) << res.out;
    EXPECT_NE(res.out.find("albedo    '" + aux + "' channels R,G,B"), std::string::npos)
        << res.out;
    // The render's own albedo is the aux's times 0.8: 20 % off, far beyond
    // what a noise-free aux may differ by, so the check rejects the aux at
    // every pixel and the render's own albedo does both (docs/AUX.md).
    EXPECT_NE(res.out.find("the render's own used at 1920 pixels (100.00 %)"),
              std::string::npos)
        << res.out;
    EXPECT_LT(max_rel_diff(output("out.exr"),
                           zdenoise::denoise(s.noisy, own_albedo, crypto_guides())),
              1e-6f);

    ::setenv("ZDENOISE_AUX_DEMODULATE", "render", 1);
    res = run("--in " + in + " --aux " + aux + " -o " + path("out_render.exr") + " -v");
    ::unsetenv("ZDENOISE_AUX_DEMODULATE");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("aux albedo '" + aux + "' channels R,G,B"), std::string::npos)
        << res.out;
    const ImageBuf want
        = zdenoise::denoise(s.noisy, own_albedo, &s.albedo, crypto_guides());
    ASSERT_FALSE(want.has_error()) << want.geterror();
    EXPECT_LT(max_rel_diff(output("out_render.exr"), want), 1e-6f);
    // Not what the render's own albedo alone gives.
    EXPECT_GT(max_rel_diff(want, zdenoise::denoise(s.noisy, own_albedo, crypto_guides())),
              0.05f);

    // A beauty with no albedo of its own: the auxiliary one does both.
    const std::string plain = write_rgb("plain.exr", s.noisy);
    res = run("--in " + plain + " --aux " + aux + " -o " + path("out_plain.exr"));
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_LT(max_rel_diff(output("out_plain.exr"), zdenoise::denoise(s.noisy, s.albedo)),
              1e-6f);
}


// An auxiliary Cycles file: its Denoising Albedo is the albedo, its normal
// and depth replace the render's guides (the render here has none).
TEST_F(AuxCli, AuxCyclesFileGivesItsGuides)
{
    const std::string in  = write_frame("frame.exr", own_albedo);
    const std::string aux = write_frame("aux.exr", s.albedo, true);
    RunResult res = run("--in " + in + " --aux " + aux + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("normal    '" + aux + "' channels ViewLayer.Denoising Normal.X"),
              std::string::npos)
        << res.out;
    EXPECT_NE(res.out.find("depth     '" + aux + "' channels ViewLayer.Denoising Depth.Z"),
              std::string::npos)
        << res.out;
    zdenoise::Guides g = crypto_guides();
    g.normal           = &s.normal;
    g.depth            = &s.depth;
    // The id guide is the auxiliary file's (the same ranks); the albedo the
    // render's own, as in AuxAlbedoRemodulates (the aux's is 20 % off).
    EXPECT_LT(max_rel_diff(output("out.exr"), zdenoise::denoise(s.noisy, own_albedo, g)),
              1e-6f);
    // --no-normal still wins.
    res = run("--in " + in + " --aux " + aux + " --no-normal -o " + path("o2.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_EQ(res.out.find("Denoising Normal"), std::string::npos) << res.out;
}


// An auxiliary albedo that is 0 where the render sees light (a black world
// behind the sky) is not let through: the render's own albedo is used
// there, -v counts those pixels, and the output keeps the render's light
// (docs/AUX.md, "Wrong auxiliary pixels").
TEST_F(AuxCli, AWrongAuxPixelIsNotLetThrough)
{
    const std::string in = write_frame("frame.exr", s.albedo);
    ImageBuf black_sky   = s.albedo;
    const ROI sky(0, W, 0, 8, 0, 1, 0, 3);
    ImageBufAlgo::fill(black_sky, { 0.0f, 0.0f, 0.0f }, sky);
    const std::string aux = write_rgb("aux.exr", black_sky);
    RunResult res = run("--in " + in + " --aux " + aux + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    const size_t at = res.out.find("the render's own used at ");
    ASSERT_NE(at, std::string::npos) << res.out;
    const long rejected = std::stol(res.out.substr(at + 25));
    EXPECT_GE(rejected, long(8 * W)) << res.out;
    EXPECT_LE(rejected, long(9 * W)) << res.out;
    // The sky keeps its light: within 5 % of the render's mean there (a
    // black aux pixel would pass the noisy radiance through or remodulate
    // it to 0).
    const auto out  = ImageBufAlgo::computePixelStats(output("out.exr"), sky);
    const auto want = ImageBufAlgo::computePixelStats(s.clean, sky);
    EXPECT_NEAR(out.avg[1], want.avg[1], 0.05 * want.avg[1]);
}


TEST_F(AuxCli, WrongAuxIsAOneLineErrorNamingTheFile)
{
    const std::string in = write_frame("frame.exr", own_albedo);
    std::vector<Channel> ch;
    add_rgb(ch, "foo", s.albedo);
    add_rgb(ch, "bar", s.albedo);
    ImageBuf img = assemble(ch);
    ASSERT_TRUE(img.write(path("layers.exr")));
    RunResult res = run("--in " + in + " --aux " + path("layers.exr") + " -o " + path("o.exr"));
    expect_one_line_error(res, "aux '" + path("layers.exr") + "'");
    EXPECT_NE(res.err.find("bar, foo"), std::string::npos) << res.err;
    EXPECT_EQ(res.status, 1);

    res = run("--in " + in + " --aux " + path("missing.exr") + " -o " + path("o.exr"));
    expect_one_line_error(res, "missing.exr");
    EXPECT_EQ(res.status, 1);

    write_image("small.exr", W / 2, H, { "R", "G", "B" }, 0.5f);
    res = run("--in " + in + " --aux " + path("small.exr") + " -o " + path("o.exr"));
    expect_one_line_error(res, "small.exr");
    EXPECT_EQ(res.status, 1);

    res = run("--in " + in + " --aux:ch=nope " + path("small.exr") + " -o " + path("o.exr"));
    expect_one_line_error(res, "small.exr");
}


// An aux of another shot is refused with one line naming both files:
// another resolution (even one whose pixels would cover the render's),
// another camera, another frame. The same camera and frame pass.
TEST_F(AuxCli, AnAuxOfAnotherShotIsRefusedNamingBoth)
{
    auto with = [&](const std::string& from, const std::string& name,
                    const std::string& camera, const std::string& frame) {
        ImageBuf img(from);
        EXPECT_TRUE(img.read(0, 0, true, TypeFloat)) << img.geterror();
        img.specmod().attribute("Camera", camera);
        img.specmod().attribute("Frame", frame);
        EXPECT_TRUE(img.write(path(name))) << img.geterror();
        return path(name);
    };
    const std::string in = with(write_frame("frame0.exr", own_albedo), "frame.exr",
                                "Camera", "001");
    const std::string aux = write_frame("aux0.exr", s.albedo);
    const std::string same = with(aux, "same.exr", "Camera", "001");
    RunResult res = run("--in " + in + " --aux " + same + " -o " + path("o.exr"));
    EXPECT_EQ(res.status, 0) << res.err;

    struct {
        const char* name;
        const char* camera;
        const char* frame;
        const char* says;
    } cases[] = { { "cam2.exr", "Camera.001", "001", "camera 'Camera.001'" },
                  { "frame2.exr", "Camera", "002", "frame '002'" } };
    for (const auto& c : cases) {
        res = run("--in " + in + " --aux " + with(aux, c.name, c.camera, c.frame) + " -o "
                  + path("o.exr"));
        expect_one_line_error(res, c.name);
        EXPECT_NE(res.err.find(c.says), std::string::npos) << res.err;
        EXPECT_NE(res.err.find(in), std::string::npos) << res.err;
        EXPECT_EQ(res.status, 1);
    }

    // Twice the resolution: its pixels cover the render's, but it is
    // another frame.
    write_image("double.exr", 2 * W, 2 * H, { "R", "G", "B" }, 0.5f);
    res = run("--in " + in + " --aux " + path("double.exr") + " -o " + path("o.exr"));
    expect_one_line_error(res, "double.exr");
    EXPECT_NE(res.err.find(std::to_string(2 * W) + "x" + std::to_string(2 * H)),
              std::string::npos)
        << res.err;
    EXPECT_NE(res.err.find(in), std::string::npos) << res.err;
    EXPECT_EQ(res.status, 1);
}


// --mode layers with --aux: the auxiliary image's lobe colours remodulate
// their layers (Cycles' Dir/Ind come divided, so the aux colour only
// multiplies back), and a lobe it has no colour for keeps its own.
TEST_F(LayersCli, AuxLobeColoursRemodulateTheirLayers)
{
    LobeRender r;
    const std::string in = write_cycles(r, "cycles.exr");
    const std::string P  = "ViewLayer.";
    const ImageBuf brighter = product(r.diff_col, constant(1.25f));
    ImageBuf black = constant(0.0f), alpha = constant(1.0f, 1);
    std::vector<Channel> ch;
    add_rgb(ch, P + "Combined", black);
    ch.push_back({ P + "Combined.A", &alpha, 0 });
    add_rgb(ch, P + "Denoising Albedo", r.denoising_albedo);
    add_rgb(ch, P + "DiffCol", brighter);
    ImageBuf aux = assemble(ch);
    ASSERT_TRUE(aux.write(path("aux.exr"))) << aux.geterror();

    RunResult plain = run("--in " + in + " -o " + path("plain.exr") + " --mode layers --aovs");
    ASSERT_EQ(plain.status, 0) << plain.err;
    RunResult res = run("--in " + in + " --aux " + path("aux.exr") + " -o " + path("aux_out.exr")
                        + " --mode layers --aovs -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("layer     ViewLayer.Diff: remodulated by the aux " + P + "DiffCol.R,"),
              std::string::npos)
        << res.out;
    EXPECT_EQ(res.out.find("ViewLayer.Gloss: remodulated"), std::string::npos)
        << "the aux has no GlossCol:\n" << res.out;

    auto layer = [&](const std::string& file, const char* name) {
        ImageBuf out(path(file));
        EXPECT_TRUE(out.read(0, 0, true, TypeFloat)) << out.geterror();
        const int c = out.spec().channelindex(P + name + ".R");
        EXPECT_GE(c, 0) << name;
        ImageBuf rgb;
        ImageBufAlgo::channels(rgb, out, 3, { c, c + 1, c + 2 });
        return rgb;
    };
    EXPECT_LT(max_rel_diff(layer("aux_out.exr", "Diff"),
                           product(layer("plain.exr", "Diff"), constant(1.25f))),
              1e-5f)
        << "the diffuse layer is its filtered light times the aux DiffCol";
    EXPECT_EQ(max_rel_diff(layer("aux_out.exr", "Gloss"), layer("plain.exr", "Gloss")), 0.0f);
}


// The library: a remodulation albedo equal to the albedo, or null, is denoise();
// where the remodulation albedo is unusable the albedo remodulates.
TEST(AuxLibrary, RemodulationAlbedo)
{
    synth::Scene s = synth::two_objects(W, H, { 16, 711 }, 0.2f);
    const ImageBuf plain = zdenoise::denoise(s.noisy, s.albedo);
    const ImageBuf same  = zdenoise::denoise(s.noisy, s.albedo, &s.albedo);
    ASSERT_FALSE(same.has_error()) << same.geterror();
    EXPECT_EQ(max_rel_diff(plain, same), 0.0f);
    EXPECT_EQ(max_rel_diff(plain, zdenoise::denoise(s.noisy, s.albedo, nullptr)), 0.0f);

    ImageBuf zero = constant(0.0f);
    EXPECT_EQ(max_rel_diff(zdenoise::denoise(s.noisy, s.albedo, &zero), plain), 0.0f);

    const ImageBuf half = product(s.albedo, constant(0.5f));
    ImageBuf q = zdenoise::demodulate(s.noisy, s.albedo);
    ImageBuf by_two;
    ASSERT_TRUE(zdenoise::remodulate(by_two, q, s.albedo, half));
    EXPECT_LT(max_rel_diff(by_two, zdenoise::remodulate(q, half)), 1e-6f);

    ImageBuf small(ImageSpec(8, 8, 3, TypeFloat));
    const ImageBuf bad = zdenoise::denoise(s.noisy, s.albedo, &small);
    EXPECT_TRUE(bad.has_error());
    EXPECT_NE(bad.geterror().find("remodulation albedo"), std::string::npos) << bad.geterror();
}


// A layer's remodulation albedo replaces its colour where both are usable:
// the layer's own colour as remodulation albedo changes nothing, and a
// clean colour times the filtered quotient is what a divided layer gives.
TEST(AuxLibrary, LayerRemodulationAlbedo)
{
    LobeRender r;
    const ImageBuf plain = zdenoise::layered_denoise(r.layers(true), &r.emit);
    std::vector<zdenoise::Layer> layers = r.layers(true);
    for (zdenoise::Layer& l : layers)
        l.remodulation_albedo = l.albedo;
    EXPECT_EQ(max_rel_diff(zdenoise::layered_denoise(layers, &r.emit), plain), 0.0f);

    const ImageBuf brighter = product(r.diff_col, constant(1.25f));
    layers = r.layers(true);
    ImageBuf diff_out;
    layers[0].remodulation_albedo = &brighter;
    layers[0].denoised            = &diff_out;
    ImageBuf sum = zdenoise::layered_denoise(layers, &r.emit);
    ASSERT_FALSE(sum.has_error()) << sum.geterror();
    const ImageBuf filtered = zdenoise::regression_filter(r.diff_z, r.diff_col);
    ImageBuf want           = product(filtered, brighter);
    ImageBufAlgo::clamp(want, want, 0.0f, 1e30f);
    EXPECT_LT(max_rel_diff(diff_out, want), 1e-5f);
}
