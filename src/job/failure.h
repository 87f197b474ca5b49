// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// How a job's steps fail: they throw, and run_job() turns what they threw
// into its one-line error. The job's files and the command use it.

#pragma once

#include <string>

#include <OpenImageIO/strutil.h>

namespace zdenoise {
namespace job {

/// A job's failure: the message is the error run_job() reports. The
/// command throws it too, with the exit status it ends with
/// (cli/shared.h: 1 a failed job, 2 a wrong command line).
struct Failure {
    std::string message;
    int exit_code = 1;
};

[[noreturn]] inline void
fail(const std::string& message)
{
    throw Failure { message };
}

/// OIIO error texts can span lines; zdenoise reports one.
inline std::string
one_line(std::string s)
{
    s = OIIO::Strutil::strip(s);
    for (char& c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    return s;
}

/// Thrown when the OutputSink fails: its message is reported as it is.
struct SinkFailure {
    std::string message;
};

}  // namespace job
}  // namespace zdenoise
