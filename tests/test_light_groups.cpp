// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// split_light_groups() (include/zdenoise/light_groups.h,
// docs/LIGHT_GROUPS.md): on a textured floor lit by a key light with a hard
// shadow edge, a smooth fill and a constant sky, each denoised group is at
// most half its noisy relMSE, the key's shadow edge stays in the key's
// group, the groups add up to the denoised beauty, none is negative and
// none gains energy, whatever the threads or the part computed. The command
// finds a Cycles render's Combined_<group> passes and Arnold's RGBA_<group>
// AOVs with no flags, splits them so, whatever the strips, and
// --no-light-groups copies them.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/imagebufalgo.h>

#include <zdenoise/light_groups.h>

#include "cli_test.h"

using namespace OIIO;

namespace {

constexpr int W = 96, H = 64;
constexpr int kEdge = 40;  ///< the key's shadow begins at this column

float
albedo(int x, int y)
{
    return ((x / 4 + y / 4) % 2) ? 0.7f : 0.35f;
}

/// Group k's clean light at (x, y): 0 key, 1 fill, 2 sky.
float
clean_light(int k, int x, int y)
{
    switch (k) {
    case 0: return x < kEdge ? 1.0f : 0.0f;
    case 1: return 0.3f * (0.6f + 0.4f * float(y) / H);
    default: return 0.1f;
    }
}

const float kTint[3][3] = { { 1.0f, 0.9f, 0.7f }, { 0.6f, 0.7f, 1.0f }, { 0.5f, 0.6f, 0.9f } };

struct GroupScene {
    ImageBuf clean[3], noisy[3], beauty, beauty_clean, albedo_img;
};

GroupScene
make_scene(float sigma, uint32_t seed)
{
    std::mt19937 rng(seed);
    std::gamma_distribution<float> gamma(1.0f / (sigma * sigma), sigma * sigma);
    GroupScene s;
    const ImageSpec spec(W, H, 3, TypeFloat);
    for (int k = 0; k < 3; ++k) {
        s.clean[k].reset(spec);
        s.noisy[k].reset(spec);
    }
    s.beauty.reset(spec);
    s.beauty_clean.reset(spec);
    s.albedo_img.reset(spec);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            float b[3] = {}, bc[3] = {};
            const float a = albedo(x, y);
            const float al[3] = { a, a, a };
            s.albedo_img.setpixel(x, y, al, 3);
            for (int k = 0; k < 3; ++k) {
                const float m = gamma(rng);  // mean 1, deviation sigma
                float c[3], n[3];
                for (int ch = 0; ch < 3; ++ch) {
                    c[ch] = a * clean_light(k, x, y) * kTint[k][ch];
                    n[ch] = c[ch] * m;
                    b[ch] += n[ch];
                    bc[ch] += c[ch];
                }
                s.clean[k].setpixel(x, y, c, 3);
                s.noisy[k].setpixel(x, y, n, 3);
            }
            s.beauty.setpixel(x, y, b, 3);
            s.beauty_clean.setpixel(x, y, bc, 3);
        }
    return s;
}

double
relmse(const ImageBuf& img, const ImageBuf& ref)
{
    double sum = 0.0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            float a[3], r[3];
            img.getpixel(x, y, a, 3);
            ref.getpixel(x, y, r, 3);
            for (int c = 0; c < 3; ++c)
                sum += double(a[c] - r[c]) * (a[c] - r[c]) / (double(r[c]) * r[c] + 1e-2);
        }
    return sum / (3.0 * W * H);
}

double
column_mean(const ImageBuf& img, int x0, int x1)
{
    double sum = 0.0;
    for (int y = 0; y < H; ++y)
        for (int x = x0; x < x1; ++x) {
            float a[3];
            img.getpixel(x, y, a, 3);
            sum += a[0] + a[1] + a[2];
        }
    return sum / (3.0 * H * (x1 - x0));
}

std::vector<const ImageBuf*>
noisy_groups(const GroupScene& s)
{
    return { &s.noisy[0], &s.noisy[1], &s.noisy[2] };
}

}  // namespace


TEST(LightGroups, EachGroupIsDenoisedAndTheyAddUpToTheDenoisedBeauty)
{
    for (float sigma : { 0.5f, 1.0f }) {
        const GroupScene s = make_scene(sigma, 17);
        const ImageBuf denoised = zdenoise::denoise(s.beauty, s.albedo_img);
        ASSERT_FALSE(denoised.has_error()) << denoised.geterror();
        std::vector<ImageBuf> groups;
        ASSERT_TRUE(zdenoise::split_light_groups(groups, denoised, s.beauty,
                                                 noisy_groups(s)))
            << groups[0].geterror();
        ASSERT_EQ(groups.size(), 3u);
        for (int k = 0; k < 3; ++k) {
            const double before = relmse(s.noisy[k], s.clean[k]);
            const double after  = relmse(groups[size_t(k)], s.clean[k]);
            std::printf("  noise %.1f, group %d: relMSE %.5f -> %.5f (%.2fx); "
                        "energy %.4f of the clean\n",
                        sigma, k, before, after, after / before,
                        column_mean(groups[size_t(k)], 0, W) / column_mean(s.clean[k], 0, W));
            EXPECT_LT(after, 0.5 * before) << "group " << k;
            EXPECT_LT(column_mean(groups[size_t(k)], 0, W),
                      1.03 * column_mean(s.noisy[k], 0, W))
                << "group " << k << " gains energy";
        }
        // The key's shadow: its group keeps the edge (no key light two
        // columns into the shadow), the fill's and the sky's do not take it.
        const double lit = column_mean(groups[0], kEdge - 6, kEdge - 2);
        const double dark = column_mean(groups[0], kEdge + 2, kEdge + 6);
        EXPECT_LT(dark, 0.03 * lit) << "the key's shadow edge in the key's group";
        // Without the likeness term the edge spreads: the test sees it.
        zdenoise::LightGroupOptions blind;
        blind.tolerance = 1e3f;
        std::vector<ImageBuf> spread;
        ASSERT_TRUE(zdenoise::split_light_groups(spread, denoised, s.beauty,
                                                 noisy_groups(s), {}, {}, blind));
        EXPECT_GT(column_mean(spread[0], kEdge + 2, kEdge + 6), 0.03 * lit);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                float sum[3] = {}, d[3];
                denoised.getpixel(x, y, d, 3);
                for (const ImageBuf& g : groups) {
                    float v[3];
                    g.getpixel(x, y, v, 3);
                    for (int c = 0; c < 3; ++c) {
                        ASSERT_GE(v[c], 0.0f);
                        sum[c] += v[c];
                    }
                }
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(sum[c], d[c], 1e-5f * std::fabs(d[c]) + 1e-7f)
                        << "(" << x << "," << y << ") channel " << c;
            }
    }
}


TEST(LightGroups, WhatTheGroupsDoNotCoverIsLeftToTheRest)
{
    // Only the key and the fill are groups: the sky's light is the rest.
    const GroupScene s = make_scene(0.5f, 5);
    const ImageBuf denoised = zdenoise::denoise(s.beauty, s.albedo_img);
    std::vector<ImageBuf> groups;
    ASSERT_TRUE(zdenoise::split_light_groups(groups, denoised, s.beauty,
                                             { &s.noisy[0], &s.noisy[1] }));
    const double sky_share = 1.0 - (column_mean(groups[0], 0, W) + column_mean(groups[1], 0, W))
                                       / column_mean(denoised, 0, W);
    const double clean_share = column_mean(s.clean[2], 0, W) / column_mean(s.beauty_clean, 0, W);
    std::printf("  the rest's share %.4f, the sky's %.4f\n", sky_share, clean_share);
    EXPECT_NEAR(sky_share, clean_share, 0.1 * clean_share);
}


TEST(LightGroups, SameResultForAnyThreadCountAndPart)
{
    const GroupScene s = make_scene(1.0f, 9);
    const ImageBuf denoised = zdenoise::denoise(s.beauty, s.albedo_img);
    std::vector<ImageBuf> one, two, part;
    ASSERT_TRUE(zdenoise::split_light_groups(one, denoised, s.beauty, noisy_groups(s),
                                             {}, {}, {}, {}, 1));
    ASSERT_TRUE(zdenoise::split_light_groups(two, denoised, s.beauty, noisy_groups(s),
                                             {}, {}, {}, {}, 2));
    const ROI r(20, 70, 10, 33);
    ASSERT_TRUE(zdenoise::split_light_groups(part, denoised, s.beauty, noisy_groups(s),
                                             {}, {}, {}, r, 2));
    for (size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(ImageBufAlgo::compare(one[k], two[k], 0.0f, 0.0f).nfail, 0u);
        for (int y = r.ybegin; y < r.yend; ++y)
            for (int x = r.xbegin; x < r.xend; ++x) {
                float a[3], b[3];
                one[k].getpixel(x, y, a, 3);
                part[k].getpixel(x, y, b, 3);
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(a[c], b[c]) << "(" << x << "," << y << ")";
            }
    }
}


TEST(LightGroups, BadInputsAreRefusedWithAMessage)
{
    const GroupScene s = make_scene(0.5f, 3);
    std::vector<ImageBuf> out;
    EXPECT_FALSE(zdenoise::split_light_groups(out, s.beauty, s.beauty, {}));
    EXPECT_NE(out[0].geterror().find("no light group"), std::string::npos);
    ImageBuf small(ImageSpec(8, 8, 3, TypeFloat));
    std::vector<ImageBuf> out2;
    EXPECT_FALSE(zdenoise::split_light_groups(out2, s.beauty, s.beauty, { &small }));
    EXPECT_NE(out2[0].geterror().find("light group"), std::string::npos) << out2[0].geterror();

    const std::atomic<bool> stop { true };
    zdenoise::FilterOptions cancelled;
    cancelled.cancel = &stop;
    std::vector<ImageBuf> out3;
    EXPECT_FALSE(zdenoise::split_light_groups(out3, s.beauty, s.beauty, noisy_groups(s), {},
                                              cancelled));
    EXPECT_NE(out3[0].geterror().find("cancelled"), std::string::npos) << out3[0].geterror();
}


namespace {

const char* const kGroupNames[3] = { "key", "fill", "sky" };

/// Planes of a test file: each image's first channels under `names`.
struct Plane {
    std::vector<std::string> names;
    const ImageBuf* image;
};

/// "<layer>.R", "<layer>.G", "<layer>.B" (plain R, G, B for "").
std::vector<std::string>
rgb_names(const std::string& layer)
{
    std::vector<std::string> n;
    for (const char* c : { "R", "G", "B" })
        n.push_back(layer.empty() ? c : layer + "." + c);
    return n;
}

/// The planes as one EXR of `type`, the first plane's next channel its
/// alpha.
void
write_planes(const std::vector<Plane>& planes, const std::string& file,
             TypeDesc type = TypeFloat)
{
    std::vector<std::string> names;
    for (const Plane& p : planes)
        names.insert(names.end(), p.names.begin(), p.names.end());
    ImageSpec spec(W, H, int(names.size()), TypeFloat);
    spec.channelnames  = names;
    spec.alpha_channel = 3;
    ImageBuf img(spec);
    std::vector<float> px(names.size()), one(3);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            size_t at = 0;
            for (const Plane& p : planes) {
                p.image->getpixel(x, y, one.data(), int(p.names.size()));
                std::copy(one.begin(), one.begin() + long(p.names.size()), px.begin() + long(at));
                at += p.names.size();
            }
            img.setpixel(x, y, px.data(), int(px.size()));
        }
    ASSERT_TRUE(img.write(file, type)) << img.geterror();
}

/// A 1-channel image of `v` left of column `x0` and `right` from it on.
ImageBuf
split_constant(float v, int x0 = W, float right = 0.0f)
{
    ImageBuf img(ImageSpec(W, H, 1, TypeFloat));
    ImageBufAlgo::fill(img, { v });
    ImageBufAlgo::fill(img, { right }, ROI(x0, W, 0, H, 0, 1, 0, 1));
    return img;
}

/// The scene's planes as Blender Cycles names them: the beauty with
/// `alpha`, the three light groups and the albedo.
std::vector<Plane>
cycles_group_planes(const GroupScene& s, const ImageBuf& alpha)
{
    std::vector<Plane> planes = { { rgb_names("ViewLayer.Combined"), &s.beauty },
                                  { { "ViewLayer.Combined.A" }, &alpha } };
    for (int k = 0; k < 3; ++k)
        planes.push_back({ rgb_names(std::string("ViewLayer.Combined_") + kGroupNames[k]),
                           &s.noisy[k] });
    planes.push_back({ rgb_names("ViewLayer.Denoising Albedo"), &s.albedo_img });
    return planes;
}

/// The scene as a Blender Cycles multilayer EXR with three light groups.
void
write_cycles_groups(const GroupScene& s, const std::string& file)
{
    const ImageBuf alpha = split_constant(1.0f);
    write_planes(cycles_group_planes(s, alpha), file);
}

ImageBuf
layer_of(const std::string& file, const std::string& layer)
{
    ImageBuf in(file);
    EXPECT_TRUE(in.read(0, 0, true, TypeFloat)) << in.geterror();
    std::vector<int> order;
    for (const char* c : { ".R", ".G", ".B" })
        order.push_back(in.spec().channelindex("ViewLayer." + layer + c));
    ImageBuf out;
    ImageBufAlgo::channels(out, in, 3, order);
    return out;
}

class LightGroupsCli : public cli_test::CliTest {};

/// Each group of the Cycles output `file` at most half its noisy relMSE;
/// left of column `covered` (where the groups hold all the light), their
/// sum within `gap` of the denoised beauty on every pixel, as a part of
/// the beauty's mean there.
void
expect_groups_denoised_and_adding_up(const GroupScene& s, const std::string& file,
                                     int covered, double gap = 1e-5)
{
    const ImageBuf beauty = layer_of(file, "Combined");
    ImageBuf sum(ImageSpec(W, H, 3, TypeFloat));
    ImageBufAlgo::zero(sum);
    for (int k = 0; k < 3; ++k) {
        const ImageBuf g = layer_of(file, std::string("Combined_") + kGroupNames[k]);
        const double before = relmse(s.noisy[k], s.clean[k]), after = relmse(g, s.clean[k]);
        std::printf("  command: %s relMSE %.5f -> %.5f\n", kGroupNames[k], before, after);
        EXPECT_LT(after, 0.5 * before) << kGroupNames[k];
        ImageBufAlgo::add(sum, sum, g);
    }
    const double mean = column_mean(beauty, 0, covered);
    double worst = 0.0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < covered; ++x) {
            float a[3], b[3];
            sum.getpixel(x, y, a, 3);
            beauty.getpixel(x, y, b, 3);
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, double(std::fabs(a[c] - b[c])) / mean);
        }
    EXPECT_LT(worst, gap) << "the groups add up to the denoised beauty";
}

}  // namespace


TEST_F(LightGroupsCli, CyclesLightGroupsAreFoundDenoisedAndAddUp)
{
    const GroupScene s = make_scene(0.7f, 23);
    write_cycles_groups(s, path("groups.exr"));
    const cli_test::RunResult res
        = run("--in " + path("groups.exr") + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("light groups fill, key, sky split from the denoised beauty"),
              std::string::npos)
        << res.out;
    const ImageBuf beauty = layer_of(path("out.exr"), "Combined");
    expect_groups_denoised_and_adding_up(s, path("out.exr"), W);

    ASSERT_EQ(run("--in " + path("groups.exr") + " -o " + path("strips.exr") + " --tile 8")
                  .status,
              0);
    ImageBuf whole(path("out.exr")), strips(path("strips.exr"));
    EXPECT_EQ(ImageBufAlgo::compare(whole, strips, 0.0f, 0.0f).nfail, 0u)
        << "strips of 8 rows give the whole frame's groups and beauty";

    ASSERT_EQ(run("--in " + path("groups.exr") + " -o " + path("copied.exr")
                  + " --no-light-groups")
                  .status,
              0);
    for (const char* g : kGroupNames) {
        const std::string layer = std::string("Combined_") + g;
        EXPECT_EQ(ImageBufAlgo::compare(layer_of(path("copied.exr"), layer),
                                        layer_of(path("groups.exr"), layer), 0.0f, 0.0f)
                      .nfail,
                  0u)
            << "--no-light-groups copies " << layer;
    }
    EXPECT_EQ(ImageBufAlgo::compare(layer_of(path("copied.exr"), "Combined"), beauty, 0.0f,
                                    0.0f)
                  .nfail,
              0u)
        << "the groups do not change the beauty";
}


// Arnold writes the beauty as plain R, G, B, A and a light group as the AOV
// RGBA_<group>.
TEST_F(LightGroupsCli, ArnoldLightGroupAovsAreFoundBesideAPlainBeauty)
{
    const GroupScene s = make_scene(0.7f, 31);
    const ImageBuf alpha = split_constant(1.0f);
    std::vector<Plane> planes = { { rgb_names(""), &s.beauty }, { { "A" }, &alpha } };
    for (int k = 0; k < 3; ++k)
        planes.push_back({ rgb_names(std::string("RGBA_") + kGroupNames[k]), &s.noisy[k] });
    write_planes(planes, path("arnold.exr"));
    ASSERT_TRUE(s.albedo_img.write(path("albedo.exr")));
    const cli_test::RunResult res = run("--in " + path("arnold.exr") + " --albedo "
                                        + path("albedo.exr") + " -o " + path("out.exr") + " -v");
    ASSERT_EQ(res.status, 0) << res.err;
    EXPECT_NE(res.out.find("light groups fill, key, sky split from the denoised beauty"),
              std::string::npos)
        << res.out;
    ImageBuf out(path("out.exr"));
    ASSERT_TRUE(out.read(0, 0, true, TypeFloat));
    for (int k = 0; k < 3; ++k) {
        const std::string layer = std::string("RGBA_") + kGroupNames[k];
        ImageBuf g;
        ImageBufAlgo::channels(g, out, 3,
                               { out.spec().channelindex(layer + ".R"),
                                 out.spec().channelindex(layer + ".G"),
                                 out.spec().channelindex(layer + ".B") });
        EXPECT_LT(relmse(g, s.clean[k]), 0.5 * relmse(s.noisy[k], s.clean[k])) << layer;
    }
}


// Transparent film, as Cycles renders it (half colour passes): right of
// kFilm the beauty is 0 with alpha 0, while the Env pass and the world's
// group (sky) hold the background. In every mode the beauty stays 0 there
// (layers mode used to add the Env pass back: the sky painted into the
// holes), the groups are split and add up to the beauty where the film is
// covered, and the passes not denoised are copied as they are.
TEST_F(LightGroupsCli, GroupsAreSplitInEveryModeUnderTransparentFilm)
{
    constexpr int kFilm = 80;
    constexpr float kBackground = 0.4f;
    GroupScene s = make_scene(0.7f, 41);
    const ROI hole(kFilm, W, 0, H, 0, 1, 0, 3);
    for (ImageBuf* img : { &s.beauty, &s.noisy[0], &s.noisy[1], &s.clean[0], &s.clean[1] })
        ImageBufAlgo::zero(*img, hole);
    for (ImageBuf* img : { &s.noisy[2], &s.clean[2] })
        ImageBufAlgo::fill(*img, { kBackground, kBackground, kBackground }, hole);
    // Cycles' lobes: DiffCol times (DiffDir + DiffInd) is the beauty.
    ImageBuf colour = s.albedo_img, direct, indirect;
    ImageBufAlgo::zero(colour, hole);
    ImageBufAlgo::add(direct, s.noisy[0], s.noisy[1]);
    ImageBufAlgo::div(direct, direct, s.albedo_img);
    ImageBufAlgo::div(indirect, s.noisy[2], s.albedo_img);
    ImageBufAlgo::zero(indirect, hole);
    ImageBuf env(ImageSpec(W, H, 3, TypeFloat));
    ImageBufAlgo::zero(env);
    ImageBufAlgo::fill(env, { kBackground, kBackground, kBackground }, hole);
    const ImageBuf alpha = split_constant(1.0f, kFilm, 0.0f);
    std::vector<Plane> planes = cycles_group_planes(s, alpha);
    planes.push_back({ rgb_names("ViewLayer.DiffCol"), &colour });
    planes.push_back({ rgb_names("ViewLayer.DiffDir"), &direct });
    planes.push_back({ rgb_names("ViewLayer.DiffInd"), &indirect });
    planes.push_back({ rgb_names("ViewLayer.Env"), &env });
    write_planes(planes, path("film.exr"), TypeHalf);
    for (const char* mode : { "beauty", "layers", "path" }) {
        SCOPED_TRACE(mode);
        const std::string out = path(std::string(mode) + ".exr");
        const cli_test::RunResult res = run("--in " + path("film.exr") + " -o " + out
                                            + " --mode " + mode + " -v");
        ASSERT_EQ(res.status, 0) << res.err;
        EXPECT_NE(res.out.find("light groups fill, key, sky split from the denoised beauty"),
                  std::string::npos)
            << res.out;
        // In half, the file's beauty and groups add up only to its rounding:
        // four values rounded to 2^-11 of themselves, up to 3x the mean.
        expect_groups_denoised_and_adding_up(s, out, kFilm, 0.01);
        const ImageBuf beauty = layer_of(out, "Combined");
        float worst = 0.0f;
        for (int y = 0; y < H; ++y)
            for (int x = kFilm; x < W; ++x) {
                float b[3];
                beauty.getpixel(x, y, b, 3);
                worst = std::max({ worst, std::fabs(b[0]), std::fabs(b[1]), std::fabs(b[2]) });
            }
        EXPECT_EQ(worst, 0.0f) << "no light where the film is transparent";
        for (const char* pass : { "DiffCol", "DiffDir", "Env" })
            EXPECT_EQ(ImageBufAlgo::compare(layer_of(out, pass), layer_of(path("film.exr"), pass),
                                            0.0f, 0.0f)
                          .nfail,
                      0u)
                << pass << " is copied as it is";
    }
}
