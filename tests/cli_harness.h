// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Running the zdenoise command from a test: a fresh folder per test, the
// exit status, stdout and stderr of a run.

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

namespace cli_harness {

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

/// Single-quote `s` for the shell.
inline std::string
quoted(const std::string& s)
{
    std::string q = "'";
    for (char c : s)
        q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// A program not built with the sanitizers of a sanitized build (Debian's
/// oiiotool, iinfo, idiff, python3), as the start of a shell command: it
/// then runs with the sanitizer runtime preloaded, as it must be to load
/// our instrumented plugin (tests/CMakeLists.txt, ZDENOISE_HOST_ENV).
inline std::string
host_program(const std::string& program)
{
    const std::string env = ZDENOISE_HOST_ENV;
    return (env.empty() ? "" : env + " ") + quoted(program);
}

/// Run a shell command line, capturing its output in `scratch` files.
inline RunResult
run_command(const std::string& command, const std::string& scratch)
{
    RunResult r;
    std::string cmd = command + " >" + quoted(scratch + ".out") + " 2>"
                      + quoted(scratch + ".err");
    int rc   = std::system(cmd.c_str());
    r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
    r.out    = slurp(scratch + ".out");
    r.err    = slurp(scratch + ".err");
    OIIO::Filesystem::remove(scratch + ".out");
    OIIO::Filesystem::remove(scratch + ".err");
    return r;
}

/// A test with its own empty folder, removed afterwards.
class FolderTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir = OIIO::Filesystem::temp_directory_path() + "/zdenoise_"
              + info->test_suite_name() + "_" + info->name() + "_"
              + std::to_string(::getpid());
        OIIO::Filesystem::remove_all(dir);
        OIIO::Filesystem::create_directory(dir);
    }
    void TearDown() override { OIIO::Filesystem::remove_all(dir); }

    std::string path(const std::string& name) const { return dir + "/" + name; }

    /// Run zdenoise with `args` (already shell-quoted where needed).
    RunResult zdenoise(const std::string& args) const
    {
        return run_command(quoted(ZDENOISE_CLI) + " " + args, path(".run"));
    }

    std::vector<std::string> files() const
    {
        std::vector<std::string> names;
        OIIO::Filesystem::get_directory_entries(dir, names);
        for (auto& n : names)
            n = OIIO::Filesystem::filename(n);
        std::sort(names.begin(), names.end());
        return names;
    }

    std::string dir;
};

}  // namespace cli_harness
