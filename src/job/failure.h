// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// How a job's steps fail: they throw, and run_job() turns what they threw
// into its one-line error. Internal to the job's files (src/job/*.cpp).

#pragma once

#include <string>

namespace zdenoise {
namespace job {

/// A job's failure: the message is the error run_job() reports.
struct Failure {
    std::string message;
};

[[noreturn]] inline void
fail(const std::string& message)
{
    throw Failure { message };
}

/// Thrown when the OutputSink fails: its message is reported as it is.
struct SinkFailure {
    std::string message;
};

}  // namespace job
}  // namespace zdenoise
