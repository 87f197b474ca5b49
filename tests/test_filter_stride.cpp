// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Strided centres (FilterOptions::centre_stride, 3 by default; 1 is the
// exact filter): as deterministic as the exact filter, every surface still
// filtered, and close to the exact filter's quality.

#include <cmath>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include <zdenoise/zdenoise.h>

#include "synthetic_scenes.h"

using OIIO::ImageBuf;
using OIIO::ROI;

namespace {

zdenoise::FilterOptions
strided(int stride, int edges = 1)
{
    zdenoise::FilterOptions o;
    o.centre_stride = stride;
    o.stride_edges  = edges;
    return o;
}

}  // namespace


TEST(FilterStride, SameResultForAnyThreadCountAndRoi)
{
    synth::Scene s = synth::staircase(72, 112, 8, { 8, 808 });
    zdenoise::Guides g;
    g.normal    = &s.normal;
    g.depth     = &s.depth;
    g.object_id = &s.object_id;
    for (int edges : { 1, 0, 2 }) {
    SCOPED_TRACE(testing::Message() << "stride_edges " << edges);
    const zdenoise::FilterOptions opt = strided(3, edges);
    ImageBuf one = zdenoise::denoise(s.noisy, s.albedo, g, opt, nullptr, {}, 1);
    ImageBuf two = zdenoise::denoise(s.noisy, s.albedo, g, opt, nullptr, {}, 2);
    ASSERT_FALSE(one.has_error()) << one.geterror();
    std::vector<float> a = synth::pixels(one), b = synth::pixels(two);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0)
        << "1 and 2 threads must give bit-identical output with stride 3";

    // A sub-ROI gives exactly the whole-image pixels there.
    const ROI sub(13, 50, 41, 97, 0, 1, 0, 3);
    ImageBuf part = zdenoise::denoise(s.noisy, s.albedo, g, opt, nullptr, sub, 2);
    ASSERT_FALSE(part.has_error()) << part.geterror();
    for (int y = sub.ybegin; y < sub.yend; ++y)
        for (int x = sub.xbegin; x < sub.xend; ++x)
            for (int c = 0; c < 3; ++c)
                ASSERT_EQ(part.getchannel(x, y, 0, c), one.getchannel(x, y, 0, c))
                    << "pixel " << x << "," << y;
    }
}


TEST(FilterStride, QualityCloseToTheExactFilter)
{
    synth::Scene s = synth::fine_texture(96, 96, { 8, 99 });
    ImageBuf exact = zdenoise::denoise(s.noisy, s.albedo, {}, strided(1));
    ImageBuf fast  = zdenoise::denoise(s.noisy, s.albedo, {}, strided(3, 0));
    ASSERT_FALSE(fast.has_error()) << fast.geterror();
    const double noisy_err = synth::rel_mse(s.noisy, s.clean);
    const double exact_err = synth::rel_mse(exact, s.clean);
    const double fast_err  = synth::rel_mse(fast, s.clean);
    EXPECT_LT(fast_err * 10.0, noisy_err)
        << "the stride-3 lattice must still remove the noise 10x: " << noisy_err << " -> " << fast_err;
    EXPECT_LT(fast_err, exact_err * 1.5)
        << "stride-3 lattice relMSE " << fast_err << " vs exact " << exact_err;
}


TEST(FilterStride, WithEdgesCloseToTheExactFilterWithHalfTheWindows)
{
    // Treads lit differently: next to the steps every pixel stays a centre
    // (a lattice window there stops at the edge), inside the treads only
    // every ninth one. (The public set is where the edges pay: zigzag_steps
    // loses up to 11 % relMSE with the lattice only, 2 % with the edges.)
    // stride_edges 2 fits only a checkerboard of the points beside an edge;
    // their windows' splats reach the points between, so the steps stay as
    // well filtered with fewer windows.
    synth::Scene s = synth::staircase(96, 96, 8, { 8, 31 });
    zdenoise::Guides g;
    g.normal = &s.normal;
    g.depth  = &s.depth;
    zdenoise::FilterStats exact_stats, edge_stats, lattice_stats, checker_stats;
    ImageBuf exact   = zdenoise::denoise(s.noisy, s.albedo, g, strided(1), &exact_stats);
    ImageBuf edges   = zdenoise::denoise(s.noisy, s.albedo, g, strided(3, 1), &edge_stats);
    ImageBuf lattice = zdenoise::denoise(s.noisy, s.albedo, g, strided(3, 0), &lattice_stats);
    ImageBuf checker = zdenoise::denoise(s.noisy, s.albedo, g, strided(3, 2), &checker_stats);
    ASSERT_FALSE(edges.has_error()) << edges.geterror();
    ASSERT_FALSE(checker.has_error()) << checker.geterror();
    const double exact_err   = synth::rel_mse(exact, s.clean);
    const double edges_err   = synth::rel_mse(edges, s.clean);
    EXPECT_LT(edges_err, exact_err * 1.1)
        << "stride 3 with edges " << edges_err << " vs exact " << exact_err;
    EXPECT_LT(edge_stats.windows, exact_stats.windows * 6 / 10)
        << "stride 3 must leave out windows inside the treads";
    EXPECT_LT(synth::rel_mse(lattice, s.clean) * 10.0, synth::rel_mse(s.noisy, s.clean));
    EXPECT_LT(lattice_stats.windows, exact_stats.windows / 4);
    const double checker_err = synth::rel_mse(checker, s.clean);
    EXPECT_EQ(checker_stats.passthrough_pixels, 0) << "every pixel must receive a fit";
    EXPECT_LT(checker_err, edges_err * 1.1)
        << "checkerboard edge centres " << checker_err << " vs every one " << edges_err;
    EXPECT_LT(checker_stats.windows, edge_stats.windows * 8 / 10)
        << "the checkerboard must leave out edge windows";
}


TEST(FilterStride, ThinObjectsOffTheLatticeAreStillFiltered)
{
    // Two-pixel-wide columns of alternating ids: a stride-3 lattice point is
    // often on the other object, so those pixels must become centres.
    synth::Scene s = synth::fine_texture(48, 48, { 8, 5 });
    std::vector<float> ids(48 * 48);
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x)
            ids[size_t(y * 48 + x)] = float((x / 2) % 2);
    ImageBuf id = synth::make_image(48, 48, 1, ids);
    zdenoise::Guides g;
    g.object_id = &id;
    zdenoise::FilterStats stats;
    ImageBuf out = zdenoise::denoise(s.noisy, s.albedo, g, strided(3), &stats);
    ASSERT_FALSE(out.has_error()) << out.geterror();
    EXPECT_EQ(stats.passthrough_pixels, 0) << "every pixel must receive a fit";
    EXPECT_LT(synth::rel_mse(out, s.clean) * 3.0, synth::rel_mse(s.noisy, s.clean));
}


TEST(FilterStride, SmallRMinUsesASmallerStrideNotAnError)
{
    // --rmin 1 with the default stride 3: windows of radius 1 on a stride-3
    // lattice would not overlap, so the filter uses stride 2, exactly.
    synth::Scene s = synth::fine_texture(40, 40, { 8, 12 });
    zdenoise::FilterOptions three = strided(3), two = strided(2);
    three.r_min = two.r_min = 1;
    ImageBuf a = zdenoise::denoise(s.noisy, s.albedo, {}, three);
    ImageBuf b = zdenoise::denoise(s.noisy, s.albedo, {}, two);
    ASSERT_FALSE(a.has_error()) << a.geterror();
    std::vector<float> pa = synth::pixels(a), pb = synth::pixels(b);
    EXPECT_EQ(std::memcmp(pa.data(), pb.data(), pa.size() * sizeof(float)), 0);
    EXPECT_EQ(zdenoise::filter_halo(three), zdenoise::filter_halo(two));
}
