// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Frames wider or taller than the filter's internal tile (1024 pixels, 2048
// with the selection) are processed tile by tile in bounded memory; the
// result must be exactly the one of runs over other parts of the frame. So must a run over a strip
// of rows that holds only the rows it needs (filter_halo() around them) and
// names the whole frame (FilterOptions::frame), as the job streams frames.

#include <algorithm>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/imagebufalgo.h>

#include <zdenoise/zdenoise.h>

#include "synthetic_scenes.h"

using OIIO::ImageBuf;
using OIIO::ROI;

TEST(FilterTiles, TiledFrameEqualsUntiledParts)
{
    // Two internal tiles wide (1024 pixels, 2048 with the selection); the
    // ROI parts below cut it elsewhere.
    for (const int select : { 0, 1 }) {
        SCOPED_TRACE(testing::Message() << "select " << select);
        const int tile = select ? 2048 : 1024, width = tile + 76;
        synth::Scene s = synth::shadow_edge(width, 24, { 64, 3 });
        synth::vary_guides(s, true);
        zdenoise::Guides g;
        g.variance = &s.variance;
        zdenoise::FilterOptions opt;
        opt.r_max  = 8;
        opt.select = select;
        zdenoise::FilterStats whole_stats;
        ImageBuf whole = zdenoise::denoise(s.noisy, s.albedo, g, opt, &whole_stats);
        ASSERT_FALSE(whole.has_error()) << whole.geterror();

        int64_t windows = 0;
        for (ROI part : { ROI(0, tile / 2, 0, 24, 0, 1, 0, 3),
                          ROI(tile / 2, width, 0, 24, 0, 1, 0, 3) }) {
            zdenoise::FilterStats st;
            ImageBuf piece = zdenoise::denoise(s.noisy, s.albedo, g, opt, &st, part);
            ASSERT_FALSE(piece.has_error()) << piece.geterror();
            windows += st.windows;
            for (int y = part.ybegin; y < part.yend; ++y)
                for (int x = part.xbegin; x < part.xend; ++x)
                    for (int c = 0; c < 3; ++c) {
                        const float a = whole.getchannel(x, y, 0, c);
                        const float b = piece.getchannel(x, y, 0, c);
                        ASSERT_EQ(std::memcmp(&a, &b, sizeof(float)), 0)
                            << "pixel " << x << "," << y << " channel " << c;
                    }
        }
        EXPECT_EQ(windows, whole_stats.windows) << "every centre counted once";
        EXPECT_EQ(whole_stats.pixels, int64_t(width) * 24);
    }
}


namespace {

/// `img` cut to the rows [y0, y1) (coordinates kept).
ImageBuf
rows(const ImageBuf& img, int y0, int y1)
{
    ROI r   = img.roi();
    r.ybegin = y0;
    r.yend   = y1;
    ImageBuf out;
    EXPECT_TRUE(OIIO::ImageBufAlgo::crop(out, img, r)) << out.geterror();
    return out;
}

void
expect_same_rows(const ImageBuf& whole, const ImageBuf& piece, int y0, int y1)
{
    for (int y = y0; y < y1; ++y)
        for (int x = whole.xbegin(); x < whole.xend(); ++x)
            for (int c = 0; c < 3; ++c) {
                const float a = whole.getchannel(x, y, 0, c);
                const float b = piece.getchannel(x, y, 0, c);
                ASSERT_EQ(std::memcmp(&a, &b, sizeof(float)), 0)
                    << "pixel " << x << "," << y << " channel " << c;
            }
}

}  // namespace


TEST(FilterTiles, StripsGivenTheFrameEqualTheWholeFrame)
{
    // Each strip sees only its rows and the halo around them, as a
    // streaming reader holds them; with FilterOptions::frame the result is
    // the whole-frame one, with all guides and strided centres too, for
    // today's filter alone and with the selection (the default). The
    // guides vary from row to row, so that one cut at the wrong offset
    // would show.
    synth::Scene s = synth::two_objects_cryptomatte(40, 90, { 4, 7 });
    synth::vary_guides(s, true);
    const ImageBuf noisy = synth::shifted(s.noisy, 3, -5);
    const ImageBuf albedo = synth::shifted(s.albedo, 3, -5);
    const ImageBuf normal = synth::shifted(s.normal, 3, -5);
    const ImageBuf depth = synth::shifted(s.depth, 3, -5);
    const ImageBuf ids = synth::shifted(s.object_id, 3, -5);
    // stride, edges, select, pyramid radius (docs/FILTER.md 5.1), the
    // direct light's noise estimate (section 14, directional_noise)
    const int cases[][5] = { { 1, 1, 0, 0, 0 }, { 3, 1, 0, 0, 0 }, { 3, 0, 0, 0, 0 },
                             { 3, 1, 1, 0, 0 }, { 3, 1, 1, 4, 0 }, { 3, 1, 1, 0, 1 },
                             { 3, 2, 1, 0, 0 } };
    for (const auto& [stride, edges, select, pyramid, directional] : cases) {
        SCOPED_TRACE(testing::Message() << "stride " << stride << " edges " << edges
                                        << " select " << select << " pyramid "
                                        << pyramid << " directional " << directional);
        zdenoise::FilterOptions opt;
        opt.r_max          = 6;
        opt.centre_stride  = stride;
        opt.stride_edges   = edges;
        opt.select         = select;
        opt.pyramid_radius = pyramid;
        opt.directional_noise = directional;
        zdenoise::Guides g;
        g.normal    = &normal;
        g.depth     = &depth;
        g.object_id = &ids;
        zdenoise::FilterStats whole_stats;
        ImageBuf whole = zdenoise::denoise(noisy, albedo, g, opt, &whole_stats);
        ASSERT_FALSE(whole.has_error()) << whole.geterror();

        const int halo = zdenoise::filter_halo(opt);
        if (!select) {
            // docs/FILTER.md section 8, and section 7b's blur.
            EXPECT_EQ(halo, 2 * opt.r_max + 6 + stride - 1 + 3 * opt.energy_radius + 1);
        }
        opt.frame = noisy.roi();
        int64_t windows = 0;
        const ROI f = noisy.roi();
        for (int y0 = f.ybegin; y0 < f.yend; y0 += 17) {
            const int y1 = std::min(y0 + 17, f.yend);
            const int a = std::max(y0 - halo, f.ybegin);
            const int b = std::min(y1 + halo, f.yend);
            ImageBuf n = rows(noisy, a, b), al = rows(albedo, a, b),
                     nn = rows(normal, a, b), d = rows(depth, a, b),
                     id = rows(ids, a, b);
            zdenoise::Guides sg;
            sg.normal    = &nn;
            sg.depth     = &d;
            sg.object_id = &id;
            ROI roi   = f;
            roi.ybegin = y0;
            roi.yend   = y1;
            zdenoise::FilterStats st;
            ImageBuf piece = zdenoise::denoise(n, al, sg, opt, &st, roi);
            ASSERT_FALSE(piece.has_error()) << piece.geterror();
            windows += st.windows;
            expect_same_rows(whole, piece, y0, y1);

            // One row fewer than the halo is refused, naming the input.
            if (a > f.ybegin) {
                ImageBuf short_albedo = rows(albedo, a + 1, b);
                ImageBuf bad = zdenoise::denoise(n, short_albedo, sg, opt,
                                                 nullptr, roi);
                EXPECT_TRUE(bad.has_error());
                EXPECT_NE(bad.geterror().find("albedo"), std::string::npos)
                    << bad.geterror();
            }
        }
        EXPECT_EQ(windows, whole_stats.windows) << "stride " << stride;
    }
}


TEST(FilterTiles, LayeredStripsGivenTheFrameEqualTheWholeFrame)
{
    synth::Scene s = synth::staircase(36, 70, 8, { 4, 11 });
    synth::vary_guides(s, true);
    zdenoise::Layer layer;
    layer.name     = "diffuse";
    layer.radiance = &s.noisy;
    layer.albedo   = &s.albedo;
    zdenoise::Guides g;
    g.depth = &s.depth;
    zdenoise::FilterOptions opt;
    opt.r_max      = 5;
    ImageBuf whole = zdenoise::layered_denoise({ layer }, &s.albedo, g, opt);
    ASSERT_FALSE(whole.has_error()) << whole.geterror();

    const int halo = zdenoise::filter_halo(opt);
    opt.frame      = s.noisy.roi();
    for (int y0 = 0; y0 < 70; y0 += 25) {
        const int y1 = std::min(y0 + 25, 70);
        const int a = std::max(y0 - halo, 0), b = std::min(y1 + halo, 70);
        ImageBuf n = rows(s.noisy, a, b), al = rows(s.albedo, a, b),
                 d = rows(s.depth, a, b), res = rows(s.albedo, y0, y1);
        zdenoise::Layer l = layer;
        l.radiance        = &n;
        l.albedo          = &al;
        zdenoise::Guides sg;
        sg.depth = &d;
        ImageBuf piece = zdenoise::layered_denoise({ l }, &res, sg, opt,
                                                   nullptr,
                                                   ROI(0, 36, y0, y1));
        ASSERT_FALSE(piece.has_error()) << piece.geterror();
        expect_same_rows(whole, piece, y0, y1);
    }
}
