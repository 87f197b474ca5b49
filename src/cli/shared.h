// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// What the command's two ways of running share, in one place: a single
// image (main.cpp) and a batch of frames (sequence.cpp) exit with the same
// codes and refuse an output that is one of the inputs the same way.

#pragma once

#include <string>

#include "../job/job.h"

namespace zdenoise {
namespace cli {

constexpr int kExitError = 1;  ///< the job failed
constexpr int kExitUsage = 2;  ///< the command line is wrong

/// Whether two paths name the same existing file.
bool
same_file(const std::string& a, const std::string& b);

/// Unless `force`: the error for an `output` that is also an input of
/// `job`, else "".
std::string
output_is_input(const job::Job& job, const std::string& output, bool force);

}  // namespace cli
}  // namespace zdenoise
