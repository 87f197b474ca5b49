// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "frames.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

namespace zdenoise {
namespace job {

using namespace OIIO;

bool
has_frame_pattern(const std::string& path, std::string* frames_in_name)
{
    std::string printf_pattern, frames;
    if (!Filesystem::parse_pattern(path.c_str(), 0, printf_pattern, frames))
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
    if (!Filesystem::parse_pattern(path.c_str(), 0, printf_pattern, frames)
        || !Filesystem::enumerate_file_sequence(printf_pattern, { frame },
                                                names)
        || names.size() != 1)
        return path;
    return names[0];
}


bool
parse_frame_list(const std::string& list, std::vector<int>& frames)
{
    frames.clear();
    return !Strutil::strip(list).empty()
           && Filesystem::enumerate_sequence(list, frames) && !frames.empty();
}


std::string
frame_list_text(const std::vector<int>& frames)
{
    std::string text;
    for (size_t i = 0; i < frames.size();) {
        size_t j = i;
        while (j + 1 < frames.size() && frames[j + 1] == frames[j] + 1)
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
             &Job::id,    &Job::variance, &Job::half_a, &Job::half_b };
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
job_for_frame(const Job& job, int frame)
{
    Job j = job;
    for (InputArg Job::*m : input_members())
        if ((j.*m).given)
            (j.*m).path = frame_path((j.*m).path, frame);
    return j;
}

}  // namespace job
}  // namespace zdenoise
