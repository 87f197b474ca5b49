// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Batch production: a job over a frame sequence (src/job/frames.h), one
// progress line per frame, a summary, a JSON report. A failed frame is
// reported and the others continue, unless --fail-fast.

#pragma once

#include <string>

#include "job/job.h"
#include "shared.h"

namespace zdenoise {
namespace cli {

struct SequenceOptions {
    std::string frames;       ///< --frames LIST
    std::string report;       ///< --report FILE.json
    bool fail_fast     = false;
    bool skip_existing = false;
    int print_chunks   = 0;   ///< --print-chunks N: print the chunks, exit
    bool verbose       = false;
    bool force         = false;  ///< allow an output that is an input
};

/// Whether the command runs frame by frame: a frame pattern in an input or
/// the output, or an option only a batch has.
bool
is_batch(const job::Job& job, const std::string& output,
         const SequenceOptions& options);

/// Run the batch. Returns the exit status; on failure `error` is the last
/// (summary) line to print.
int
run_batch(const job::Job& job, const std::string& output,
          const SequenceOptions& options, std::string& error);

}  // namespace cli
}  // namespace zdenoise
