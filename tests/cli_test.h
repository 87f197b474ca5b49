// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Running the zdenoise command in the tests: a fixture with a scratch
// folder per test, and the check of a one-line error.

#pragma once

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

namespace cli_test {

using namespace OIIO;

inline const std::string kCli       = ZDENOISE_CLI;
inline const std::string kSourceDir = ZDENOISE_SOURCE_DIR;

struct RunResult {
    int status = -1;
    std::string out, err;
};

inline std::string
slurp(const std::string& path)
{
    std::ifstream f(path);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

class CliTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir = Filesystem::temp_directory_path() + "/zdenoise_cli_"
              + info->name() + "_" + std::to_string(::getpid());
        Filesystem::remove_all(dir);
        Filesystem::create_directory(dir);
    }
    void TearDown() override { Filesystem::remove_all(dir); }

    std::string path(const std::string& name) const { return dir + "/" + name; }

    /// Run zdenoise with `args` (already shell-quoted where needed).
    RunResult run(const std::string& args) const
    {
        RunResult r;
        std::string cmd = "'" + kCli + "' " + args + " >'" + path("stdout.txt")
                          + "' 2>'" + path("stderr.txt") + "'";
        int rc   = std::system(cmd.c_str());
        r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
        r.out    = slurp(path("stdout.txt"));
        r.err    = slurp(path("stderr.txt"));
        Filesystem::remove(path("stdout.txt"));
        Filesystem::remove(path("stderr.txt"));
        return r;
    }

    /// Files in the test folder (to see that nothing was left behind).
    std::vector<std::string> files() const
    {
        std::vector<std::string> names;
        Filesystem::get_directory_entries(dir, names);
        for (auto& n : names)
            n = Filesystem::filename(n);
        std::sort(names.begin(), names.end());
        return names;
    }

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

    std::string dir;
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
