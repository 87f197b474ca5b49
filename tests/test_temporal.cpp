// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// temporal_combine() and chain_flow() (docs/TEMPORAL.md) on synthetic
// sequences: what a user of --temporal notices (the noise and the flicker
// fall with K, a moving object leaves no trail).

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

#include <zdenoise/temporal.h>
#include <zdenoise/zdenoise.h>

#include "synthetic_scenes.h"

using OIIO::ImageBuf;

namespace {

/// A synthetic scene as one frame of a sequence, with all its guides.
zdenoise::TemporalFrame
scene_frame(const synth::Scene& s)
{
    zdenoise::TemporalFrame f;
    f.radiance         = &s.noisy;
    f.albedo           = &s.albedo;
    f.guides.normal    = &s.normal;
    f.guides.depth     = &s.depth;
    f.guides.object_id = &s.object_id;
    return f;
}

/// Frame t of a static sequence denoised with K neighbours on each side
/// (frames t-K..t+K of `frames`, each the same scene with other noise).
ImageBuf
denoise_static(const std::vector<synth::Scene>& frames, int t, int K,
               ImageBuf* combined_radiance = nullptr)
{
    std::vector<zdenoise::TemporalFrame> neighbours;
    for (int k = t - K; k <= t + K; ++k)
        if (k != t && k >= 0 && k < int(frames.size()))
            neighbours.push_back(scene_frame(frames[size_t(k)]));
    zdenoise::TemporalCombined c;
    EXPECT_TRUE(zdenoise::temporal_combine(c, scene_frame(frames[size_t(t)]),
                                           neighbours))
        << c.radiance.geterror();
    if (combined_radiance)
        *combined_radiance = c.radiance;
    const synth::Scene& s = frames[size_t(t)];
    zdenoise::Guides g;
    g.normal    = &s.normal;
    g.depth     = &s.depth;
    g.object_id = &s.object_id;
    return zdenoise::denoise(c.radiance, s.albedo, g);
}


/// Mean over pixels and RGB of the squared difference of two images.
double
mean_square_difference(const ImageBuf& a, const ImageBuf& b)
{
    const std::vector<float> pa = synth::pixels(a), pb = synth::pixels(b);
    const int nch = a.nchannels();
    double sum    = 0.0;
    size_t n      = 0;
    for (size_t i = 0; i < pa.size(); ++i)
        if (int(i % size_t(nch)) < 3) {
            const double d = double(pa[i]) - double(pb[i]);
            sum += d * d;
            ++n;
        }
    return sum / double(n);
}

}  // namespace


// A static camera: every frame is the same scene with other noise. The
// light averaged over 2K+1 frames has 1/(2K+1) of the noise before the
// filter; the filter's error and the frame-to-frame flicker fall with K.
TEST(Temporal, StaticSceneNoiseAndFlickerFallWithK)
{
    std::vector<synth::Scene> frames;
    for (int seed = 1; seed <= 6; ++seed)
        frames.push_back(synth::staircase(96, 96, 8, { 8, uint32_t(100 + seed) }));
    const ImageBuf& clean = frames[2].clean;
    ImageBuf combined;
    const ImageBuf alone = denoise_static(frames, 2, 0);
    const ImageBuf k1    = denoise_static(frames, 2, 1);
    const ImageBuf k2    = denoise_static(frames, 2, 2, &combined);
    const double e0 = synth::rel_mse(alone, clean);
    const double e1 = synth::rel_mse(k1, clean);
    const double e2 = synth::rel_mse(k2, clean);
    const double noisy = synth::rel_mse(frames[2].noisy, clean);
    std::printf("  relMSE noisy %.5f, combined (K=2) %.5f; denoised K=0 %.5f, "
                "K=1 %.5f, K=2 %.5f\n",
                noisy, synth::rel_mse(combined, clean), e0, e1, e2);
    EXPECT_LT(synth::rel_mse(combined, clean), 0.3 * noisy)
        << "five frames averaged keep a fifth of the noise";
    EXPECT_LT(e1, e0);
    EXPECT_LT(e2, 0.7 * e0);
    // Flicker: frames 2 and 3 share four of their five frames.
    const double flicker0 = mean_square_difference(alone, denoise_static(frames, 3, 0));
    const double flicker2 = mean_square_difference(k2, denoise_static(frames, 3, 2));
    std::printf("  flicker K=0 %.3g, K=2 %.3g (%.2fx)\n", flicker0, flicker2,
                flicker2 / flicker0);
    EXPECT_LT(flicker2, 0.3 * flicker0);
}


// A bright square moves 6 pixels a frame over a darker background. Its
// pixels follow it through the flow, and where it was in the neighbours
// (its trail ahead of and behind it) the background is seen in frame t:
// the id and depth guides keep its light out of the background.
TEST(Temporal, MovingSquareLeavesNoTrail)
{
    const int W = 96, H = 64, side = 16, step = 6, K = 2, nframes = 2 * K + 1;
    const float bg_light = 0.2f, square_light = 2.0f;
    struct Frame {
        ImageBuf clean, noisy, albedo, normal, depth, id, flow;
    };
    auto square_x = [&](int f) { return 30 + step * f; };
    std::vector<Frame> frames(static_cast<size_t>(nframes));
    for (int f = 0; f < nframes; ++f) {
        std::mt19937 rng(uint32_t(7 + f));
        std::normal_distribution<float> noise(0.0f, 0.35f);
        std::vector<float> clean, noisy, albedo, normal, depth, id;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const bool sq = x >= square_x(f) && x < square_x(f) + side
                                && y >= 24 && y < 24 + side;
                const float a = sq ? 0.7f : 0.5f;
                const float l = sq ? square_light : bg_light;
                for (int c = 0; c < 3; ++c) {
                    clean.push_back(a * l);
                    noisy.push_back(std::max(0.0f, a * l * (1.0f + noise(rng))));
                    albedo.push_back(a);
                }
                normal.insert(normal.end(), { 0.0f, 0.0f, 1.0f });
                depth.push_back(sq ? 5.0f : 10.0f);
                id.push_back(sq ? 2.0f : 1.0f);
            }
        Frame& fr = frames[size_t(f)];
        fr.clean  = synth::make_image(W, H, 3, clean);
        fr.noisy  = synth::make_image(W, H, 3, noisy);
        fr.albedo = synth::make_image(W, H, 3, albedo);
        fr.normal = synth::make_image(W, H, 3, normal);
        fr.depth  = synth::make_image(W, H, 1, depth);
        fr.id     = synth::make_image(W, H, 1, id);
    }
    const int t = K;
    // Where frame t's pixels show in frame f: the square moves, the
    // background stays.
    for (int f = 0; f < nframes; ++f) {
        std::vector<float> flow;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const bool sq = x >= square_x(t) && x < square_x(t) + side
                                && y >= 24 && y < 24 + side;
                flow.push_back(sq ? float(step * (f - t)) : 0.0f);
                flow.push_back(0.0f);
            }
        frames[size_t(f)].flow = synth::make_image(W, H, 2, flow);
    }
    auto as_frame = [](const Frame& fr) {
        zdenoise::TemporalFrame tf;
        tf.radiance         = &fr.noisy;
        tf.albedo           = &fr.albedo;
        tf.guides.normal    = &fr.normal;
        tf.guides.depth     = &fr.depth;
        tf.guides.object_id = &fr.id;
        tf.flow             = &fr.flow;
        return tf;
    };
    std::vector<zdenoise::TemporalFrame> neighbours;
    for (int f = 0; f < nframes; ++f)
        if (f != t)
            neighbours.push_back(as_frame(frames[size_t(f)]));
    zdenoise::TemporalCombined c;
    ASSERT_TRUE(zdenoise::temporal_combine(c, as_frame(frames[size_t(t)]),
                                           neighbours))
        << c.radiance.geterror();
    const Frame& ft = frames[size_t(t)];
    zdenoise::Guides g;
    g.normal    = &ft.normal;
    g.depth     = &ft.depth;
    g.object_id = &ft.id;
    const ImageBuf with = zdenoise::denoise(c.radiance, ft.albedo, g);
    const ImageBuf alone = zdenoise::denoise(ft.noisy, ft.albedo, g);
    // The trail: where the square is in the other frames, not in frame t.
    const int x0 = square_x(0), x1 = square_x(nframes - 1) + side;
    const double bg = 0.5 * bg_light;
    double trail = 0.0;
    int n = 0;
    for (int y = 24; y < 24 + side; ++y)
        for (int x = x0; x < x1; ++x) {
            if (x >= square_x(t) && x < square_x(t) + side)
                continue;
            trail += synth::luminance(with, x, y);
            ++n;
        }
    trail /= n;
    std::printf("  trail mean %.4f (background %.4f); square relMSE %.5f "
                "alone, %.5f with K=2\n",
                trail, bg,
                synth::rel_mse(alone, ft.clean, square_x(t), square_x(t) + side, 24, 40),
                synth::rel_mse(with, ft.clean, square_x(t), square_x(t) + side, 24, 40));
    EXPECT_NEAR(trail, bg, 0.05 * bg) << "the square's light trails into the background";
    // The square itself gains from its reprojected neighbours.
    EXPECT_LT(synth::rel_mse(c.radiance, ft.clean, square_x(t), square_x(t) + side, 24, 40),
              0.35 * synth::rel_mse(ft.noisy, ft.clean, square_x(t), square_x(t) + side, 24, 40));
    // Each pixel counts the frames that agree: nearly all of them on the
    // square and far from it (the light test rejects a few by chance at 3
    // standard errors), fewer in the trail.
    auto mean_frames = [&](int x0, int x1, int y0, int y1) {
        double sum = 0.0;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x)
                sum += c.frames.getchannel(x, y, 0, 0);
        return sum / double((x1 - x0) * (y1 - y0));
    };
    EXPECT_GT(mean_frames(square_x(t) + 2, square_x(t) + side - 2, 26, 38), 4.8);
    EXPECT_GT(mean_frames(0, W, 0, 16), 4.8);
    EXPECT_LT(c.frames.getchannel(square_x(t) - 2, 30, 0, 0), float(nframes));
}


TEST(Temporal, ChainFlowAddsTheSecondStepWhereTheFirstLands)
{
    const int W = 8, H = 4;
    std::vector<float> a, b;
    for (int i = 0; i < W * H; ++i) {
        a.insert(a.end(), { 2.0f, 0.0f });
        b.insert(b.end(), { float(i % W), 1.0f });  // depends on the column
    }
    ImageBuf chained;
    ASSERT_TRUE(zdenoise::chain_flow(chained, synth::make_image(W, H, 2, a),
                                     synth::make_image(W, H, 2, b)));
    // Pixel (1, 2) lands on (3, 2), whose step is (3, 1).
    EXPECT_EQ(chained.getchannel(1, 2, 0, 0), 5.0f);
    EXPECT_EQ(chained.getchannel(1, 2, 0, 1), 1.0f);
    // Pixel (6, 0) lands outside the frame: no correspondence.
    EXPECT_TRUE(std::isnan(chained.getchannel(6, 0, 0, 0)));
}


TEST(Temporal, RefusesANeighbourOfAnotherSize)
{
    const synth::Scene s = synth::fine_texture(32, 32, { 8, 3 });
    const synth::Scene small = synth::fine_texture(16, 16, { 8, 4 });
    zdenoise::TemporalFrame t, n;
    t.radiance = &s.noisy;
    t.albedo   = &s.albedo;
    n.radiance = &small.noisy;
    n.albedo   = &s.albedo;  // not the neighbour's size
    zdenoise::TemporalCombined c;
    EXPECT_FALSE(zdenoise::temporal_combine(c, t, { n }));
    EXPECT_NE(c.radiance.geterror().find("neighbour 0"), std::string::npos)
        << c.radiance.geterror();
}


// Per pixel, in a fixed order of neighbours: any thread count and any ROI
// give the whole-image pixels bit for bit (the light test's box reads
// around the ROI). The albedo and normals vary from pixel to pixel, so that
// a ROI's planes read at the wrong offset would show.
TEST(Temporal, ThreadsAndRoiGiveTheWholeImagePixels)
{
    std::vector<synth::Scene> frames;
    for (int seed = 1; seed <= 3; ++seed) {
        frames.push_back(synth::staircase(64, 48, 8, { 8, uint32_t(200 + seed) }));
        synth::vary_guides(frames.back(), false);
    }
    const std::vector<zdenoise::TemporalFrame> neighbours = { scene_frame(frames[0]),
                                                              scene_frame(frames[2]) };
    zdenoise::TemporalCombined whole;
    ASSERT_TRUE(zdenoise::temporal_combine(whole, scene_frame(frames[1]), neighbours,
                                           {}, {}, 1));
    for (int nthreads : { 2, 3 }) {
        zdenoise::TemporalCombined c;
        ASSERT_TRUE(zdenoise::temporal_combine(c, scene_frame(frames[1]), neighbours, {},
                                               {}, nthreads));
        EXPECT_TRUE(synth::same_pixels(c.radiance, whole.radiance)) << nthreads;
        EXPECT_TRUE(synth::same_pixels(c.frames, whole.frames)) << nthreads;
    }
    const OIIO::ROI part(9, 40, 7, 30, 0, 3);
    zdenoise::TemporalCombined c;
    ASSERT_TRUE(zdenoise::temporal_combine(c, scene_frame(frames[1]), neighbours, {}, part, 2));
    for (int y = part.ybegin; y < part.yend; ++y)
        for (int x = part.xbegin; x < part.xend; ++x)
            for (int ch = 0; ch < 3; ++ch)
                ASSERT_EQ(c.radiance.getchannel(x, y, 0, ch),
                          whole.radiance.getchannel(x, y, 0, ch))
                    << x << "," << y;
}


// A neighbour whose flow chains another's counts only where that one
// shows the same surface: here the nearer frame shows another object over
// the left half, so the farther frame's pixels there (the same surface as
// frame t's) are not used either.
TEST(Temporal, AChainedNeighbourCountsOnlyWhereItsViaDoes)
{
    const int W = 32, H = 16;
    auto frame = [&](float left_id) {
        std::vector<float> rgb, albedo, id;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                rgb.insert(rgb.end(), { 0.4f, 0.4f, 0.4f });
                albedo.insert(albedo.end(), { 0.5f, 0.5f, 0.5f });
                id.push_back(x < W / 2 ? left_id : 1.0f);
            }
        return std::array<ImageBuf, 3> { synth::make_image(W, H, 3, rgb),
                                          synth::make_image(W, H, 3, albedo),
                                          synth::make_image(W, H, 1, id) };
    };
    const auto t = frame(1.0f), near = frame(2.0f), far = frame(1.0f);
    const ImageBuf zero = synth::make_image(W, H, 2, std::vector<float>(2 * W * H, 0.0f));
    auto as_frame = [&](const std::array<ImageBuf, 3>& f) {
        zdenoise::TemporalFrame tf;
        tf.radiance         = &f[0];
        tf.albedo           = &f[1];
        tf.guides.object_id = &f[2];
        tf.flow             = &zero;
        return tf;
    };
    std::vector<zdenoise::TemporalFrame> neighbours = { as_frame(near), as_frame(far) };
    neighbours[1].via = 0;
    zdenoise::TemporalCombined c;
    ASSERT_TRUE(zdenoise::temporal_combine(c, as_frame(t), neighbours));
    EXPECT_EQ(c.frames.getchannel(4, 8, 0, 0), 1.0f) << "left: neither neighbour";
    EXPECT_EQ(c.frames.getchannel(W - 5, 8, 0, 0), 3.0f) << "right: both";
    neighbours[1].via = 1;  // itself
    EXPECT_FALSE(zdenoise::temporal_combine(c, as_frame(t), neighbours));
}


// A soft shadow that lies on the neighbours but not on frame t (it moved
// away): the light there is 10 % lower, less than the noise of a 5x5 box
// can show. The test's larger boxes see it, so frame t keeps its own light
// there; with the 5x5 box alone the shadow is averaged in.
TEST(Temporal, ABroadDimmerLightInTheNeighboursIsNotAveragedIn)
{
    const int W = 96, H = 96, K = 2, t = K;
    const float albedo = 0.5f, light = 1.0f, shadow = 0.9f;
    auto in_shadow = [](int x, int y) { return x >= 24 && x < 72 && y >= 24 && y < 72; };
    // Flat frames, one object facing the camera: only the light differs.
    std::vector<synth::Scene> frames(2 * K + 1);
    for (int f = 0; f <= 2 * K; ++f) {
        std::mt19937 rng(uint32_t(91 + f));
        std::normal_distribution<float> noise(0.0f, 0.3f);
        std::vector<float> noisy, alb, normal, depth, id;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const float l = f != t && in_shadow(x, y) ? shadow : light;
                for (int c = 0; c < 3; ++c) {
                    noisy.push_back(albedo * l * (1.0f + noise(rng)));
                    alb.push_back(albedo);
                }
                normal.insert(normal.end(), { 0.0f, 0.0f, 1.0f });
                depth.push_back(10.0f);
                id.push_back(1.0f);
            }
        synth::Scene& fr = frames[size_t(f)];
        fr.noisy     = synth::make_image(W, H, 3, noisy);
        fr.albedo    = synth::make_image(W, H, 3, alb);
        fr.normal    = synth::make_image(W, H, 3, normal);
        fr.depth     = synth::make_image(W, H, 1, depth);
        fr.object_id = synth::make_image(W, H, 1, id);
    }
    std::vector<zdenoise::TemporalFrame> neighbours;
    for (int f = 0; f <= 2 * K; ++f)
        if (f != t)
            neighbours.push_back(scene_frame(frames[size_t(f)]));
    // The mean light over the shadow's inside (its edges are found by the
    // small box anyway), relative to frame t's true light.
    auto inside_light = [&](const zdenoise::TemporalOptions& options) {
        zdenoise::TemporalCombined c;
        EXPECT_TRUE(zdenoise::temporal_combine(c, scene_frame(frames[size_t(t)]), neighbours,
                                               options))
            << c.radiance.geterror();
        double sum = 0.0;
        int n      = 0;
        for (int y = 32; y < 64; ++y)
            for (int x = 32; x < 64; ++x, ++n)
                sum += synth::luminance(c.radiance, x, y);
        return sum / n / double(albedo * light);
    };
    zdenoise::TemporalOptions small_box_only;
    small_box_only.test_scales = 1;
    const double with_scales = inside_light({}), small_box = inside_light(small_box_only);
    std::printf("  light inside the shadow, relative to frame t's: %.3f with every "
                "scale, %.3f with the 5x5 box only\n",
                with_scales, small_box);
    EXPECT_LT(small_box, 0.95) << "the 5x5 box alone lets the shadow in (else this proves nothing)";
    EXPECT_NEAR(with_scales, 1.0, 0.02);
    // What -v reports per neighbour: the guides match everywhere; the light
    // test takes out the square (a quarter of the frame).
    zdenoise::TemporalCombined c;
    ASSERT_TRUE(zdenoise::temporal_combine(c, scene_frame(frames[size_t(t)]), neighbours));
    ASSERT_EQ(c.same_surface.size(), neighbours.size());
    for (size_t k = 0; k < neighbours.size(); ++k) {
        EXPECT_EQ(c.same_surface[k], 1.0);
        EXPECT_GT(c.counted[k], 0.6);
        EXPECT_LT(c.counted[k], 0.8);
    }
}
