// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "frames.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include "options.h"

namespace zdenoise {
namespace job {

using namespace OIIO;

namespace {

/// Whether OIIO's printf-style pattern of a path holds exactly one frame
/// conversion (%d, %4d, %04d) and nothing else but "%%": OIIO formats it
/// with fmt, which aborts the program on any other '%' sequence (a name
/// like "100%x.####.exr"; found by tests/fuzz/fuzz_frames).
bool
one_frame_conversion(const std::string& pattern)
{
    int conversions = 0;
    for (size_t i = 0; i < pattern.size(); ++i) {
        if (pattern[i] != '%')
            continue;
        if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
            ++i;
            continue;
        }
        size_t j = i + 1;
        while (j < pattern.size() && pattern[j] >= '0' && pattern[j] <= '9')
            ++j;
        if (j >= pattern.size() || pattern[j] != 'd' || j - i > 4)
            return false;
        ++conversions;
        i = j;
    }
    return conversions == 1;
}

/// OIIO's reading of `path` as a frame pattern: its printf-style pattern
/// and any frame list in the name; false when it is not one, or not one
/// OIIO can format safely.
bool
frame_pattern(const std::string& path, std::string& printf_pattern,
              std::string& frames)
{
    return Filesystem::parse_pattern(path.c_str(), 0, printf_pattern, frames)
           && one_frame_conversion(printf_pattern);
}

}  // namespace


bool
has_frame_pattern(const std::string& path, std::string* frames_in_name)
{
    std::string printf_pattern, frames;
    if (!frame_pattern(path, printf_pattern, frames))
        return false;
    if (frames_in_name && !frames.empty())
        *frames_in_name = frames;
    return true;
}


std::string
frame_path(const std::string& path, int frame)
{
    std::string printf_pattern, frames;
    std::vector<std::string> names;
    if (!frame_pattern(path, printf_pattern, frames)
        || !Filesystem::enumerate_file_sequence(printf_pattern, { frame },
                                                names)
        || names.size() != 1)
        return path;
    return names[0];
}


namespace {

/// An upper bound on the frames `list` names, or infinity when it is not a
/// frame list: each comma item must be "A", "A-B", "A-BxN" or "A-ByN"
/// (whitespace around the parts allowed, as OIIO allows it; N >= 1) and
/// counts |B - A| + 1 (a step only makes fewer). Anything else is refused
/// here rather than left to OIIO, so that no form ("1-\t1000000000") slips
/// past the bound. A frame number beyond an int ("36377777763") is refused
/// too: OIIO would clamp it to another frame without a word.
double
frame_count_bound(const std::string& list)
{
    constexpr double refused = std::numeric_limits<double>::infinity();
    const double int_max     = std::numeric_limits<int>::max();
    double count             = 0.0;
    for (string_view item : Strutil::splitsv(list, ",")) {
        const char* p   = item.data();
        const char* end = p + item.size();
        auto skip_space = [&] {
            while (p < end && std::isspace(static_cast<unsigned char>(*p)))
                ++p;
        };
        auto number = [&](double& v) {
            skip_space();
            const char* q = p;
            if (q < end && (*q == '-' || *q == '+'))
                ++q;
            if (q == end || !std::isdigit(static_cast<unsigned char>(*q)))
                return false;
            while (q < end && std::isdigit(static_cast<unsigned char>(*q)))
                ++q;
            v = std::strtod(std::string(p, q).c_str(), nullptr);
            p = q;
            skip_space();
            return std::fabs(v) <= int_max;
        };
        double a = 0.0, b = 0.0, step = 1.0;
        if (!number(a))
            return refused;
        b = a;
        if (p < end && *p == '-') {
            ++p;
            if (!number(b))
                return refused;
            if (p < end && (*p == 'x' || *p == 'y')) {
                ++p;
                if (!number(step) || step < 1.0)
                    return refused;
            }
        }
        if (p != end)
            return refused;
        count += std::abs(b - a) + 1.0;
    }
    return count;
}

}  // namespace


bool
parse_frame_list(const std::string& list, std::vector<int>& frames,
                 int max_frames)
{
    frames.clear();
    return !Strutil::strip(list).empty()
           && frame_count_bound(list) <= static_cast<double>(max_frames)
           && Filesystem::enumerate_sequence(list, frames) && !frames.empty();
}


std::string
frame_list_text(const std::vector<int>& frames)
{
    std::string text;
    for (size_t i = 0; i < frames.size();) {
        size_t j = i;
        while (j + 1 < frames.size()
               && int64_t(frames[j + 1]) == int64_t(frames[j]) + 1)
            ++j;
        text += (text.empty() ? "" : ",") + std::to_string(frames[i]);
        if (j > i)
            text += "-" + std::to_string(frames[j]);
        i = j + 1;
    }
    return text;
}


std::vector<std::string>
frame_chunks(const std::vector<int>& frames, int chunk_size)
{
    std::vector<std::string> chunks;
    const size_t size = size_t(std::max(chunk_size, 1));
    for (size_t i = 0; i < frames.size(); i += size)
        chunks.push_back(frame_list_text(std::vector<int>(
            frames.begin() + long(i),
            frames.begin() + long(std::min(frames.size(), i + size)))));
    return chunks;
}


namespace {

std::vector<InputArg Job::*>
input_members()
{
    return { &Job::in,    &Job::albedo,   &Job::normal, &Job::depth,
             &Job::id,    &Job::variance, &Job::half_a, &Job::half_b,
             &Job::aux,   &Job::motion };
}

}  // namespace


bool
job_has_frame_pattern(const Job& job, std::string* frames_in_name)
{
    bool any = false;
    for (InputArg Job::*m : input_members())
        if ((job.*m).given && has_frame_pattern((job.*m).path, frames_in_name))
            any = true;
    return any;
}


Job
job_with_neighbours(const Job& job, int frame, int first, int last)
{
    Job j = job_for_frame(job, frame);
    for (int k = -job.temporal; k <= job.temporal; ++k)
        if (k != 0 && int64_t(frame) + k >= first
            && int64_t(frame) + k <= last) {
            j.neighbours.push_back(job_for_frame(job, frame + k));
            j.neighbour_offsets.push_back(k);
        }
    return j;
}


bool
frame_bounds(const std::string& list, int& first, int& last)
{
    std::vector<int> frames;
    if (!parse_frame_list(list, frames))
        return false;
    const auto [lo, hi] = std::minmax_element(frames.begin(), frames.end());
    first = *lo;
    last  = *hi;
    return true;
}


std::string
frame_problem(const Job& job)
{
    const bool patterned = job_has_frame_pattern(job);
    if (job.frame.empty()) {
        if (job.temporal > 0)
            return "\"temporal\" needs \"frame\" (this frame) and inputs with a "
                   "frame pattern (shot.#.exr)";
        if (patterned)
            return "the inputs name a frame pattern: \"frame\" says which frame "
                   "(e.g. \"1042\")";
        if (!job.shot_range.empty())
            return "\"shot-range\" needs \"frame\" and inputs with a frame "
                   "pattern (shot.#.exr)";
        return "";
    }
    std::vector<int> frames;
    if (!parse_frame_list(job.frame, frames) || frames.size() != 1)
        return Strutil::fmt::format(
            "\"frame\" must be one frame (\"1042\"), not '{}'",
            job.frame.substr(0, 40));
    if (!patterned)
        return "\"frame\" needs inputs with a frame pattern (shot.#.exr)";
    if (job.temporal > 0 && job.shot_range.empty())
        return "\"temporal\" needs \"shot-range\": the shot's frames "
               "(\"1001-1100\"), which the neighbours lie within";
    int first = 0, last = 0;
    if (!job.shot_range.empty()) {
        if (!frame_bounds(job.shot_range, first, last))
            return Strutil::fmt::format(
                "\"shot-range\" must be a frame list (\"1001-1100\"), not "
                "'{}'",
                job.shot_range.substr(0, 40));
        if (frames[0] < first || frames[0] > last)
            return Strutil::fmt::format(
                "\"shot-range\" '{}' does not hold \"frame\" {}",
                job.shot_range.substr(0, 40), frames[0]);
    }
    return "";
}


Job
resolve_frame(const Job& job)
{
    std::vector<int> frame;
    if (job.frame.empty() || !parse_frame_list(job.frame, frame))
        return job;
    int first = frame[0], last = frame[0];
    if (!job.shot_range.empty())
        frame_bounds(job.shot_range, first, last);
    return job_with_neighbours(job, frame[0], first, last);
}


Job
job_for_frame(const Job& job, int frame)
{
    Job j = job;
    for (InputArg Job::*m : input_members())
        if ((j.*m).given)
            (j.*m).path = frame_path((j.*m).path, frame);
    if (!j.diagnostics_png.empty())
        j.diagnostics_png = frame_path(j.diagnostics_png, frame);
    return j;
}

namespace {

/// The first of `frames` whose file `pattern` names exists, or "".
std::string
first_existing(const std::string& pattern, const std::vector<int>& frames)
{
    for (int f : frames) {
        const std::string name = frame_path(pattern, f);
        if (Filesystem::exists(name))
            return name;
    }
    return "";
}


/// Why `pattern` (the value of `flag`) matches no file of `frames`, or ""
/// when it matches one (or is no pattern).
std::string
unmatched(const char* flag, const std::string& pattern,
          const std::vector<int>& frames)
{
    std::string frames_in_name;
    if (frames.empty() || !has_frame_pattern(pattern, &frames_in_name)
        || !first_existing(pattern, frames).empty())
        return "";
    std::string list = frame_list_text(frames);
    if (list.size() > 40)
        list = list.substr(0, 37) + "...";
    std::string message = Strutil::fmt::format(
        "{} '{}' matches no file of frames {}: the first looked for is '{}'",
        flag, pattern, list, frame_path(pattern, frames.front()));
    // OIIO reads the first run of # and @ (after any frame list) as the
    // frame number: # 4 digits, @ one. Read each # as one digit instead.
    const size_t begin = pattern.find_first_of("#@");
    const size_t end   = pattern.find_first_not_of("#@", begin);
    const size_t count = (end == std::string::npos ? pattern.size() : end)
                         - begin;
    const std::string run = pattern.substr(begin, count);
    if (run.find('#') == std::string::npos)
        return message;
    auto with = [&](const std::string& spelling) {
        return pattern.substr(0, begin) + spelling
               + pattern.substr(begin + count);
    };
    const std::string digits = std::string(count, '@');
    const std::string found  = first_existing(with(digits), frames);
    if (found.empty())
        return message;
    const std::string write = with(count % 4 == 0 ? std::string(count / 4, '#')
                                                  : digits);
    return message
           + Strutil::fmt::format(
               "; '{}' exists: in oiiotool's convention, which zdenoise "
               "follows, # is 4 digits and @ one, so write '{}'{}",
               found, write,
               frames_in_name.empty()
                   ? Strutil::fmt::format(" (or '{}')",
                                          with(Strutil::fmt::format(
                                              "%0{}d", count)))
                   : std::string());
}

}  // namespace


std::string
unmatched_frame_pattern(const Job& job, const std::vector<int>& frames)
{
    Command command;
    command.job = job;
    for (const Option& o : options()) {
        std::string why;
        if (o.kind == Kind::Input) {
            const InputArg& arg = std::get<Field<InputArg>>(o.field)(command);
            if (arg.given)
                why = unmatched(o.flag, arg.path, frames);
        } else if (o.kind == Kind::Halves && job.half_a.given) {
            why = unmatched(o.flag, job.half_a.path, frames);
            if (why.empty())
                why = unmatched(o.flag, job.half_b.path, frames);
        }
        if (!why.empty())
            return why;
    }
    return "";
}

}  // namespace job
}  // namespace zdenoise
