// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// What the command's two ways of running share, in one place: a single
// image (main.cpp) and a batch of frames (sequence.cpp) exit with the same
// codes. (Both refuse an output that is one of the inputs with
// job::output_is_input(), which the Python module shares.)

#pragma once

namespace zdenoise {
namespace cli {

constexpr int kExitError = 1;  ///< the job failed
constexpr int kExitUsage = 2;  ///< the command line is wrong

}  // namespace cli
}  // namespace zdenoise
