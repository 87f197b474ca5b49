// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The checks of a job that need no file, written once: the command line
// and recipes run them after reading their options, and run_job() before
// opening any file (a job built in code). Each check has the message of
// both front ends: the command line names --options, recipes "keys".
// Checks that need the files' headers (channels, layers, memory) are the
// job's own (job.cpp).

#include <OpenImageIO/strutil.h>

#include "options.h"

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
    if (job.albedo_samples < 0)
        return cli ? format("--albedo-samples needs a number >= 1, got {}",
                            job.albedo_samples)
                   : format("\"albedo-samples\" must be 1 or more, not {}",
                            job.albedo_samples);
    return "";
}

}  // namespace job
}  // namespace zdenoise
