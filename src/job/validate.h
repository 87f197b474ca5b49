// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The checks of a job that need no file (validate.cpp), and the refusal of
// an output that is one of the job's inputs.

#pragma once

#include <string>
#include <vector>

#include "job_types.h"
#include "options.h"

namespace zdenoise {
namespace job {

/// Every check of a job that needs no file: "" when `job`
/// is valid, else a one-line message naming the option at fault as
/// `spelling` names it. The command line, recipes and run_job() all use it.
std::string
validate(const Job& job, Spelling spelling);

/// The library's own check of the filter options (the ranges
/// regression_filter() takes): "" or its one-line message. run_job() makes
/// it before reading a pixel, so that bad options fail where a missing
/// channel does (a recipe's open(), not its first read).
std::string
filter_options_problem(const FilterOptions& options);

/// Unless `force`: the error for an `output` that is also an input of `job`
/// (the same existing file, whatever the spelling of its path), which says
/// how `spelling` allows it (--force, force=True); else "". The command
/// (a single image and each frame of a batch) and the Python module refuse
/// such an output the same way.
std::string
output_is_input(const Job& job, const std::string& output, bool force,
                Spelling spelling);

/// Every input path of the job (to refuse an output that is an input).
std::vector<std::string>
input_paths(const Job& job);

}  // namespace job
}  // namespace zdenoise
