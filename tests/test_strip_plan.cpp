// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The strip plan (src/job/memory_plan.cpp, docs/PERFORMANCE.md "Memory"):
// how tall the strips of a frame are, from the memory model alone.

#include <gtest/gtest.h>

#include "job/memory_plan.h"

using namespace zdenoise;

namespace {

/// An 8K frame with 54 passes in path mode, as the model sees it: a
/// 125-row halo (the filter's 85 and the layers' reach) and about 450
/// bytes a held pixel.
job::StripCost
wide_frame()
{
    job::StripCost c;
    c.width      = 7680;
    c.height     = 4320;
    c.halo       = 85;
    c.around     = 125;
    c.held_pixel = 400;
    c.core_pixel = 50;
    c.tile_pixel = 192;
    c.tile       = 2048;
    return c;
}

job::JobResult
plan(const job::StripCost& cost, uint64_t limit)
{
    job::Job j;
    j.mem_limit = limit;
    job::InputHeader in;
    job::JobResult r;
    job::plan_strips(j, in, cost, r);
    return r;
}

}  // namespace


// Where even a strip of 16 rows passes the comfortable 256 MiB, the halo
// is what takes the memory: thinner strips only read and filter it again
// (an 8K frame took 270 strips of 16 rows and 34 min, 6 strips of 720
// rows 6 min). The strips stay at least three halos tall.
TEST(StripPlan, AWideFrameIsNotCutThinnerThanItsHalo)
{
    const job::StripCost c = wide_frame();
    const job::JobResult r = plan(c, uint64_t(16) << 30);
    EXPECT_GE(r.strip_rows, 3 * c.around) << r.strips << " strips";
    EXPECT_LE(r.strip_rows, 6 * c.around);
    EXPECT_EQ(r.strips, (c.height + r.strip_rows - 1) / r.strip_rows);
    EXPECT_LE(r.estimated_bytes, double(uint64_t(16) << 30));
}

// The memory limit still thins them, to what fits.
TEST(StripPlan, TheMemoryLimitStillThinsAWideFrame)
{
    const job::StripCost c = wide_frame();
    const uint64_t limit   = uint64_t(1536) << 20;
    const job::JobResult r = plan(c, limit);
    EXPECT_LT(r.strip_rows, 3 * c.around);
    EXPECT_LE(r.estimated_bytes, double(limit));
    EXPECT_GT(c.bytes(r.strip_rows + 64), double(limit) * 0.9)
        << "no thinner than the limit needs";
}
