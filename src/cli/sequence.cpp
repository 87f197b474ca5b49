// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// run_batch(): a job frame by frame over a sequence (docs/FARM.md,
// docs/TEMPORAL.md "Frames at the ends"), or over one image. Stages:
//   parse_batch_frames()  --frames or a file name's list; names that agree
//   shot_bounds()         the shot the --temporal neighbours lie in
//                         (--shot-range, else the frames')
//   --print-chunks        job::frame_chunks() printed, and nothing run
//   frames_to_denoise()   what the input pattern must name (the frames
//                         whose output is missing, with --skip-existing)
//   run_frames()          each frame's job, with its neighbours: skipped,
//                         done or failed, and the progress line
//   summary_line(), write_report()  the summary and --report's JSON

#include "sequence.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include "job/atomic_write.h"
#include "job/frames.h"
#include "job/options.h"
#include "job/validate.h"

namespace zdenoise {
namespace cli {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// What became of one frame, for the summary and the report.
struct FrameRecord {
    int frame = 0;
    bool has_number = true;
    std::string output;
    enum class Status { Done, Skipped, Failed } status = Status::Done;
    std::string error;
    double seconds = 0.0, read_seconds = 0.0, denoise_seconds = 0.0,
           write_seconds = 0.0;
    FilterStats stats;
};

const char*
status_name(FrameRecord::Status s)
{
    switch (s) {
    case FrameRecord::Status::Done: return "done";
    case FrameRecord::Status::Skipped: return "skipped";
    default: return "failed";
    }
}


std::string
seconds_text(double s)
{
    if (s < 60.0)
        return format("{:.1f}s", s);
    const int whole = int(s + 0.5);
    return format("{}:{:02d}:{:02d}", whole / 3600, whole / 60 % 60,
                  whole % 60);
}


/// The per-frame progress: on a terminal one line updated in place, else
/// one line per frame (farm logs).
class Progress {
public:
    explicit Progress(size_t total)
        : m_total(total)
        , m_tty(isatty(fileno(stderr)))
    {
    }

    void starting(const FrameRecord& r, size_t done, double eta)
    {
        std::string line = format("zdenoise: [{}/{} done] {}", done, m_total,
                                  r.has_number
                                      ? format("frame {}", r.frame)
                                      : std::string("the image"));
        if (done > 0)
            line += ", ETA " + seconds_text(eta);
        if (m_tty) {
            fprintf(stderr, "\r%-78s", line.c_str());
            m_open = true;
        } else {
            fprintf(stderr, "%s\n", line.c_str());
        }
        fflush(stderr);
    }

    /// A line of its own (an error, the summary), after the updating line.
    void line(const std::string& text)
    {
        if (m_open)
            fputc('\n', stderr);
        m_open = false;
        fprintf(stderr, "%s\n", text.c_str());
    }

private:
    size_t m_total;
    bool m_tty;
    bool m_open = false;
};


void
run_frame(const job::Job& job, FrameRecord& r, const SequenceOptions& o)
{
    Timer wall;
    auto failed = [&](const std::string& why) {
        r.status  = FrameRecord::Status::Failed;
        r.error   = why;
        r.seconds = wall();
    };
    const std::string refused = job::output_is_input(
        job, r.output, o.force, job::Spelling::CommandLine);
    if (!refused.empty())
        return failed(refused);
    job::JobResult result;
    std::string err;
    const bool ok = job::run_job_to_file(job, r.output, result, err);
    if (o.verbose)
        for (const std::string& line : result.log)
            printf("zdenoise: %s\n", line.c_str());
    if (!ok)
        return failed(err);
    r.read_seconds    = result.read_seconds;
    r.denoise_seconds = result.denoise_seconds;
    r.write_seconds   = result.write_seconds;
    r.stats           = result.stats;
    r.seconds         = wall();
}


nlohmann::ordered_json
stats_json(const FilterStats& s)
{
    const double w = double(std::max<int64_t>(s.windows, 1));
    const double n = double(std::max<int64_t>(s.pixels, 1));
    nlohmann::ordered_json j;
    j["pixels"]             = s.pixels;
    j["windows"]            = s.windows;
    j["mean_radius"]        = s.mean_radius;
    j["stop_quality_share"] = double(s.stop_quality) / w;
    j["stop_size_share"]    = double(s.stop_size) / w;
    j["stop_edge_share"]    = double(s.stop_edge) / w;
    j["passthrough_pixels"] = s.passthrough_pixels;
    j["passthrough_share"]  = double(s.passthrough_pixels) / n;
    j["nonfinite_pixels"]   = s.nonfinite_pixels;
    return j;
}


bool
write_report(const std::string& path, const job::Job& job,
             const std::vector<FrameRecord>& records, double seconds,
             std::string& error)
{
    nlohmann::ordered_json report;
    report["zdenoise"]   = ZDENOISE_VERSION_STRING;
    report["parameters"] = describe(job.filter);
    nlohmann::ordered_json colour;
    colour["colorconfig"]        = job.colour.config;
    colour["iscolorspace"]       = job.colour.input_space;
    colour["albedo-colorspace"]  = job.colour.albedo_space;
    colour["ocolorspace"]        = job.colour.output_space;
    colour["working-colorspace"] = job.colour.working_space;
    report["colour"]             = colour;
    report["threads"]            = job.threads;
    size_t done = 0, skipped = 0, failed = 0;
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    for (const FrameRecord& r : records) {
        nlohmann::ordered_json f;
        if (r.has_number)
            f["frame"] = r.frame;
        f["output"] = r.output;
        f["status"] = status_name(r.status);
        if (r.status == FrameRecord::Status::Failed)
            f["error"] = r.error;
        f["seconds"] = r.seconds;
        if (r.status == FrameRecord::Status::Done) {
            f["read_seconds"]    = r.read_seconds;
            f["denoise_seconds"] = r.denoise_seconds;
            f["write_seconds"]   = r.write_seconds;
            f["stats"]           = stats_json(r.stats);
        }
        frames.push_back(f);
        done += r.status == FrameRecord::Status::Done;
        skipped += r.status == FrameRecord::Status::Skipped;
        failed += r.status == FrameRecord::Status::Failed;
    }
    report["frames"]  = frames;
    report["summary"] = { { "frames", records.size() },
                          { "done", done },
                          { "skipped", skipped },
                          { "failed", failed },
                          { "seconds", seconds } };
    const std::string text = report.dump(2) + "\n";
    return job::write_text_atomically(path, text, error);
}

/// The frames of a batch: a sequence's (a frame pattern in an input or the
/// output) and the shot their --temporal neighbours lie in, or none (one
/// image).
struct BatchFrames {
    bool patterned_in = false;
    bool sequence     = false;
    std::vector<int> frames;
    int first = 0, last = 0;  ///< the shot
};

/// The frames: --frames, else a list in a file name ("s.1-10#.exr"), and
/// names that agree with them. False, with `error`, on a usage error.
bool
parse_batch_frames(const job::Job& job, const std::string& output,
                   const SequenceOptions& o, BatchFrames& b, std::string& error)
{
    std::string frames_in_name;
    b.patterned_in           = job::job_has_frame_pattern(job, &frames_in_name);
    const bool patterned_out = job::has_frame_pattern(output, &frames_in_name);
    const std::string list   = o.frames.empty() ? frames_in_name : o.frames;
    b.sequence = b.patterned_in || patterned_out;
    if (b.sequence) {
        if (list.empty()) {
            error = "a frame pattern (#, @ or %0Nd) needs --frames, e.g. "
                    "--frames 1001-1100";
            return false;
        }
        if (!job::parse_frame_list(list, b.frames)) {
            error = format("--frames: '{}' is not a frame list (e.g. "
                           "1001-1100, 1-99x2, 1,5,9)",
                           list);
            return false;
        }
        if (b.patterned_in && !patterned_out && !output.empty()) {
            error = format("-o '{}' has no frame pattern: every frame would "
                           "write it; use e.g. clean.#.exr",
                           output);
            return false;
        }
        if (!job.diagnostics_png.empty()
            && !job::has_frame_pattern(job.diagnostics_png)) {
            error = format("--diagnostics-png '{}' has no frame pattern: "
                           "every frame would write it; use e.g. error.#.png",
                           job.diagnostics_png);
            return false;
        }
    } else if (!o.frames.empty() || o.print_chunks > 0
               || !job.shot_range.empty()) {
        error = format("{} needs a frame pattern (#, @ or %0Nd) in the "
                       "input and output names, e.g. --in shot.#.exr -o "
                       "clean.#.exr",
                       !o.frames.empty()    ? "--frames"
                       : o.print_chunks > 0 ? "--print-chunks"
                                            : "--shot-range");
        return false;
    }
    return true;
}

/// The shot the neighbours of --temporal lie in: --shot-range, which must
/// hold the frames (a farm chunk's --frames is part of it), else the
/// frames' own first and last. False, with `error`, on a usage error.
bool
shot_bounds(const job::Job& job, BatchFrames& b, std::string& error)
{
    if (b.sequence) {
        b.first = *std::min_element(b.frames.begin(), b.frames.end());
        b.last  = *std::max_element(b.frames.begin(), b.frames.end());
    }
    if (b.sequence && !job.shot_range.empty()) {
        if (!job::frame_bounds(job.shot_range, b.first, b.last)) {
            error = format("--shot-range: '{}' is not a frame list (e.g. "
                           "1001-1100)",
                           job.shot_range);
            return false;
        }
        for (int f : b.frames)
            if (f < b.first || f > b.last) {
                error = format("--shot-range {} does not hold frame {} of "
                               "--frames",
                               job.shot_range, f);
                return false;
            }
    }
    return true;
}

/// The frames to denoise: all, or with --skip-existing those whose output
/// is missing.
std::vector<int>
frames_to_denoise(const BatchFrames& b, const std::string& output,
                  const SequenceOptions& o)
{
    std::vector<int> wanted;
    for (int f : b.frames)
        if (!o.skip_existing || !Filesystem::exists(job::frame_path(output, f)))
            wanted.push_back(f);
    return wanted;
}

/// One record a frame, its output named; one for the image outside a
/// sequence.
std::vector<FrameRecord>
frame_records(const BatchFrames& b, const std::string& output)
{
    std::vector<FrameRecord> records;
    if (b.sequence) {
        for (int f : b.frames) {
            FrameRecord r;
            r.frame  = f;
            r.output = job::frame_path(output, f);
            records.push_back(r);
        }
    } else {
        FrameRecord r;
        r.has_number = false;
        r.output     = output;
        records.push_back(r);
    }
    return records;
}

/// What the frames came to, counted as they ran.
struct BatchTally {
    size_t done = 0, skipped = 0, failed = 0;
    std::string failed_frames;  ///< their numbers (or the image's name)
};

/// Run the records' frames in order (each with its neighbours in the shot):
/// an existing output skipped with --skip-existing, a failed frame
/// reported and the rest run, unless --fail-fast.
BatchTally
run_frames(const job::Job& job, const BatchFrames& b, const SequenceOptions& o,
           std::vector<FrameRecord>& records, Progress& progress)
{
    BatchTally t;
    double work_seconds = 0.0;  // of frames denoised, for the ETA
    for (FrameRecord& r : records) {
        const size_t finished = t.done + t.failed;
        const size_t left     = records.size() - t.done - t.failed - t.skipped;
        if (o.skip_existing && Filesystem::exists(r.output)) {
            r.status = FrameRecord::Status::Skipped;
            ++t.skipped;
            if (o.verbose)
                progress.line(format("zdenoise: frame {}: '{}' exists, "
                                     "skipped",
                                     r.frame, r.output));
            continue;
        }
        progress.starting(r, t.done + t.failed + t.skipped,
                          finished ? work_seconds / double(finished)
                                         * double(left)
                                   : 0.0);
        run_frame(b.sequence ? job::job_with_neighbours(job, r.frame, b.first,
                                                        b.last)
                             : job,
                  r, o);
        work_seconds += r.seconds;
        if (r.status == FrameRecord::Status::Failed) {
            ++t.failed;
            t.failed_frames += (t.failed_frames.empty() ? "" : ",")
                               + (r.has_number ? std::to_string(r.frame)
                                               : r.output);
            if (r.has_number)  // a single image's error is the last line
                progress.line(format("zdenoise: error: frame {}: {}", r.frame,
                                     r.error));
            if (o.fail_fast)
                break;
        } else {
            ++t.done;
        }
    }
    return t;
}

/// The summary line: the frames denoised, skipped, failed (and not
/// started, after --fail-fast), and the time.
std::string
summary_line(size_t nrecords, const BatchTally& t, const SequenceOptions& o,
             double seconds)
{
    return format("zdenoise: {} frame{}: {} denoised, {} skipped, {} "
                  "failed{} in {}",
                  nrecords, nrecords == 1 ? "" : "s", t.done, t.skipped,
                  t.failed,
                  (o.fail_fast && t.failed)
                      ? format(", {} not started",
                               nrecords - t.done - t.skipped - t.failed)
                      : std::string(),
                  seconds_text(seconds));
}

}  // namespace


bool
is_batch(const job::Job& job, const std::string& output,
         const SequenceOptions& o)
{
    return job::job_has_frame_pattern(job) || job::has_frame_pattern(output)
           || !o.frames.empty() || !o.report.empty() || o.skip_existing
           || o.fail_fast || o.print_chunks > 0 || !job.shot_range.empty();
}


int
run_batch(const job::Job& job, const std::string& output,
          const SequenceOptions& o, std::string& error)
{
    BatchFrames b;
    if (!parse_batch_frames(job, output, o, b, error)
        || !shot_bounds(job, b, error))
        return kExitUsage;
    if (o.print_chunks > 0) {
        for (const std::string& chunk : job::frame_chunks(b.frames,
                                                          o.print_chunks))
            printf("%s\n", chunk.c_str());
        return 0;
    }
    // A pattern that names no file of the frames to denoise fails up front,
    // not frame by frame.
    if (b.patterned_in) {
        error = job::unmatched_frame_pattern(job,
                                             frames_to_denoise(b, output, o));
        if (!error.empty())
            return kExitError;
    }
    std::vector<FrameRecord> records = frame_records(b, output);
    Timer total;
    Progress progress(records.size());
    const BatchTally t   = run_frames(job, b, o, records, progress);
    const double seconds = total();
    progress.line(summary_line(records.size(), t, o, seconds));
    if (!o.report.empty() && !write_report(o.report, job, records, seconds,
                                           error))
        return kExitError;
    if (t.failed) {
        error = b.sequence ? format("{} of {} frames failed: {}", t.failed,
                                    records.size(), t.failed_frames)
                           : records.front().error;
        return kExitError;
    }
    return 0;
}

}  // namespace cli
}  // namespace zdenoise
