// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// A denoise job as the command line (and the OIIO plugin) describe it:
// input files with channel selections, filter options. run_job() reads
// the files, picks the channels (with the defaults of the conventions in
// layer_conventions.h), denoises the beauty or its layers, and assembles
// the output image: the noisy input file with its radiance RGB replaced
// (and, on request, the denoised layers added), every other channel and the
// metadata kept.
//
// The frame streams through in horizontal strips: for each strip the
// files' rows it needs (the strip and the filter's halo around it) are
// read, the strip is denoised, and its output rows go to an OutputSink
// (a file being written, or an image in memory). Memory follows the
// strip, not the frame; the result is bit-identical for any strip height
// (zdenoise::filter_halo(), FilterOptions::frame).

#pragma once

#include <string>
#include <vector>

#include "job_types.h"

namespace zdenoise {
namespace job {

/// Run `job`, giving the output to `sink`. On failure returns false and a
/// one-line `error` naming the file, channel or option at fault (a sink's
/// error as the sink gave it). Never throws.
bool
run_job(const Job& job, OutputSink& sink, JobResult& result,
        std::string& error);

/// The spec of `job`'s output as a file holds it (native_spec(): each
/// channel in its pixel type, the metadata), from the input files' headers
/// alone: no pixel is read, nothing filtered. It is run_job()'s own plan up
/// to its first pixel, so the two cannot disagree, and it fails as run_job()
/// would for anything a header shows (a missing file or channel, a bad
/// option, a frame too large for the memory of `sink`'s strips). On
/// failure returns false and run_job()'s one-line `error`. Never throws.
bool
output_spec(const Job& job, const OutputSink& sink, OIIO::ImageSpec& spec,
            std::string& error);

/// Run `job` into `result.image` (the whole output in memory, float).
bool
run_job(const Job& job, JobResult& result, std::string& error);

/// Run `job` and write its output to `path` as it is computed, through a
/// temporary file renamed into place once complete (atomic_write.h): on
/// failure `path` is untouched and no file is left behind.
bool
run_job_to_file(const Job& job, const std::string& path, JobResult& result,
                std::string& error);

}  // namespace job
}  // namespace zdenoise
