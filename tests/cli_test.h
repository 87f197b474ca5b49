// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The command-line tests' fixture: cli_harness.h's folder per test, with
// small input images and the check of a one-line error.

#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include "cli_harness.h"

namespace cli_test {

using namespace OIIO;
using cli_harness::RunResult;
using cli_harness::slurp;

inline const std::string kSourceDir = ZDENOISE_SOURCE_DIR;

class CliTest : public cli_harness::FolderTest {
protected:
    /// Run zdenoise with `args` (already shell-quoted where needed).
    RunResult run(const std::string& args) const { return zdenoise(args); }

    /// Write a small float image with the given channels, all set to value.
    void write_image(const std::string& name, int w, int h,
                     std::vector<std::string> channels, float value,
                     TypeDesc type = TypeFloat) const
    {
        ImageSpec spec(w, h, int(channels.size()), type);
        spec.channelnames = channels;
        spec.alpha_channel = -1;
        ImageBuf buf(spec);
        std::vector<float> v(channels.size(), value);
        ImageBufAlgo::fill(buf, v);
        ASSERT_TRUE(buf.write(path(name))) << buf.geterror();
    }
};

/// Expect a failure: non-zero exit, one line on stderr mentioning `needle`.
inline void
expect_one_line_error(const RunResult& r, const std::string& needle)
{
    EXPECT_NE(r.status, 0) << "expected failure, got success";
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1)
        << "stderr should be exactly one line:\n"
        << r.err;
    EXPECT_NE(r.err.find("zdenoise: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos)
        << "stderr should name '" << needle << "':\n"
        << r.err;
}

}  // namespace cli_test
