// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Frames wider or taller than the filter's internal tile (1024 pixels) are
// processed tile by tile in bounded memory; the result must be exactly the
// one of untiled runs over parts of the frame.

#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include <zdenoise/zdenoise.h>

#include "synthetic_scenes.h"

using OIIO::ImageBuf;
using OIIO::ROI;

TEST(FilterTiles, TiledFrameEqualsUntiledParts)
{
    // 1100 px wide: two internal tiles; each ROI part below is one tile.
    synth::Scene s = synth::shadow_edge(1100, 24, { 64, 3 });
    zdenoise::Guides g;
    g.variance = &s.variance;
    zdenoise::FilterOptions opt;
    opt.r_max  = 8;
    zdenoise::FilterStats whole_stats;
    ImageBuf whole = zdenoise::denoise(s.noisy, s.albedo, g, opt, &whole_stats);
    ASSERT_FALSE(whole.has_error()) << whole.geterror();

    int64_t windows = 0;
    for (ROI part : { ROI(0, 600, 0, 24, 0, 1, 0, 3), ROI(600, 1100, 0, 24, 0, 1, 0, 3) }) {
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
    EXPECT_EQ(whole_stats.pixels, 1100 * 24);
}
