// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Frame sequences with oiiotool's conventions (OIIO's Filesystem pattern
// functions, so that both programs read a name the same way): in a file
// name `#` is a frame number of 4 digits (`##` of 8), `@` one digit per `@`,
// `%04d` printf style; frame lists are "1001-1100", "1-10x2" (every 2nd),
// "1-10y2" (the others), and comma lists of those.

#pragma once

#include <string>
#include <vector>

#include "job_types.h"

namespace zdenoise {
namespace job {

/// Whether `path` has a frame wildcard. An oiiotool-style frame list
/// inside the name ("shot.1001-1010#.exr") goes to `frames_in_name`.
bool
has_frame_pattern(const std::string& path, std::string* frames_in_name = nullptr);

/// `path` with its frame wildcard replaced by `frame`; `path` itself when it
/// has none.
std::string
frame_path(const std::string& path, int frame);

/// A frame list may name at most this many frames: more than any sequence a
/// render farm runs, so a longer one is a typo such as "1-1000000000".
constexpr int kMaxFrameListFrames = 1000000;

/// The frames of a frame list; false when it is malformed, empty, or names
/// more than `max_frames` frames (refused before they are enumerated, so
/// a typo costs no memory; the fuzz target lowers it to stay fast).
bool
parse_frame_list(const std::string& list, std::vector<int>& frames,
                 int max_frames = kMaxFrameListFrames);

/// Frames as a frame list, runs written as ranges: "1001-1003,1007".
std::string
frame_list_text(const std::vector<int>& frames);

/// `frames` in consecutive chunks of `chunk_size` (the last may be shorter),
/// each as a frame list: what one farm task denoises.
std::vector<std::string>
frame_chunks(const std::vector<int>& frames, int chunk_size);

/// Whether any input of `job` names a frame pattern.
bool
job_has_frame_pattern(const Job& job, std::string* frames_in_name = nullptr);

/// "" when every input of `job` that names a frame pattern names an
/// existing file for at least one of `frames`; else a one-line message
/// naming the option, the pattern and the first file looked for. When the
/// pattern's `#` read as one digit each (Nuke's and Houdini's convention,
/// where `####` is 4 digits, not oiiotool's 16) would have matched, it
/// says which pattern to write.
std::string
unmatched_frame_pattern(const Job& job, const std::vector<int>& frames);

/// `job` for one frame: the frame wildcard of every input path replaced.
Job
job_for_frame(const Job& job, int frame);

/// job_for_frame(); with job.temporal K, with the jobs of frames frame-K ..
/// frame+K that lie within first .. last (the shot) as its neighbours: the
/// first and last frames use the neighbours they have, and a neighbour
/// within the shot whose file is missing fails the frame, naming it.
Job
job_with_neighbours(const Job& job, int frame, int first, int last);

/// Why `job` (a recipe's or a keyword call's) is not one frame, in the
/// recipe's spelling, or "": Job::frame is one frame, given exactly when
/// the inputs name a frame pattern; temporal needs it and shot_range, which
/// must hold it.
std::string
frame_problem(const Job& job);

/// The job of Job::frame (its inputs' files, with temporal its neighbours
/// within shot_range); `job` itself when it has no frame. After
/// frame_problem() found none.
Job
resolve_frame(const Job& job);

/// The first and last frame of frame list `list` (--shot-range), or false.
bool
frame_bounds(const std::string& list, int& first, int& last);

}  // namespace job
}  // namespace zdenoise
