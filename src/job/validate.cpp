// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The checks of a job that need no file, written once: the command line
// and recipes run them after reading their options, and run_job() before
// opening any file (a job built in code). Each check has the message of
// both front ends: the command line names --options, recipes "keys".
// Checks that need the files' headers (channels, layers, memory) are the
// job's own (job.cpp). Here too: the refusal of an output that is one of the
// inputs, which the command and the Python module make before running a
// job (it asks the file system which paths name one file).

#include <climits>
#include <cstdlib>
#include <cstring>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include "failure.h"
#include "validate.h"

namespace zdenoise {
namespace job {

using OIIO::Strutil::fmt::format;

std::string
validate(const Job& job, Spelling spelling)
{
    const bool cli = spelling == Spelling::CommandLine;
    if (!job.in.given)
        return cli ? "no input: give --in FILE (see zdenoise --help)"
                   : "no noisy input: the recipe needs \"in\"";
    if (job.threads < 0)
        return cli ? format("--threads needs a number >= 0, got {}",
                            job.threads)
                   : format("\"threads\" must be 0 (automatic) or more, not "
                            "{}",
                            job.threads);
    if (job.tile_rows < 0)
        return cli ? format("--tile needs a number of rows >= 1 (or 0: "
                            "automatic), got {}",
                            job.tile_rows)
                   : format("\"tile\" must be 0 (automatic) or a number of "
                            "rows, not {}",
                            job.tile_rows);
    if (job.temporal < 0 || job.temporal > 8)
        return cli ? format("--temporal needs 0 to 8 frames on each side, "
                            "got {}",
                            job.temporal)
                   : format("\"temporal\" must be 0 to 8, not {}",
                            job.temporal);
    if (job.temporal > 0 && (job.mode == Mode::Layers || job.mode == Mode::Path))
        return "--temporal works in --mode beauty (the layers' light is "
               "not combined across frames yet; docs/TEMPORAL.md)";
    if (job.albedo_samples < 0)
        return cli ? format("--albedo-samples needs a number >= 1, got {}",
                            job.albedo_samples)
                   : format("\"albedo-samples\" must be 1 or more, not {}",
                            job.albedo_samples);
    return "";
}


std::string
filter_options_problem(const FilterOptions& options)
{
    // The library checks its options only as it filters, and that check
    // is not public (include/zdenoise/zdenoise.h): a 4x4 grey image asks
    // it, in microseconds, without the job's pixels.
    OIIO::ImageBuf grey(OIIO::ImageSpec(4, 4, 3, OIIO::TypeFloat));
    OIIO::ImageBufAlgo::fill(grey, { 0.5f, 0.5f, 0.5f });
    FilterOptions probe = options;
    probe.progress      = nullptr;
    probe.frame         = OIIO::ROI();
    probe.diagnostics   = nullptr;
    probe.hat_diagonal  = nullptr;
    OIIO::ImageBuf filtered;
    if (regression_filter(filtered, grey, grey, Guides(), probe, nullptr,
                          OIIO::ROI(), 1))
        return "";
    return one_line(filtered.geterror());
}


namespace {

/// Whether two paths name the same existing file.
bool
same_file(const std::string& a, const std::string& b)
{
    char ra[PATH_MAX], rb[PATH_MAX];
    if (!realpath(a.c_str(), ra) || !realpath(b.c_str(), rb))
        return false;
    return std::strcmp(ra, rb) == 0;
}

}  // namespace


std::string
output_is_input(const Job& job, const std::string& output, bool force,
                Spelling spelling)
{
    if (force)
        return "";
    for (const std::string& in : input_paths(job))
        if (same_file(in, output))
            return format("the output '{}' is also an input; use {} to "
                          "replace it",
                          output,
                          spelling == Spelling::Keyword ? "force=True"
                                                        : "--force");
    return "";
}

std::vector<std::string>
input_paths(const Job& j)
{
    std::vector<std::string> paths;
    for (const InputArg* a : { &j.in, &j.albedo, &j.normal, &j.depth, &j.id,
                               &j.variance, &j.half_a, &j.half_b, &j.aux,
                               &j.motion })
        if (a->given)
            paths.push_back(a->path);
    return paths;
}

}  // namespace job
}  // namespace zdenoise
