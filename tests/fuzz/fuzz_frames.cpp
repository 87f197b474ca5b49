// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Fuzzing the frame patterns of file names and the frame lists (oiiotool's
// conventions, src/job/frames.h): they must never crash, never enumerate
// more than the frames allowed, and a list must survive being written back
// as text and cut into farm chunks. The limit is lowered from a million to
// 4096 here: the code paths are the same, and enumerating a million frames
// per input would make the fuzzer forty times slower.
//
// Input: "PATH\0FRAME LIST".

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "job/frames.h"

using namespace zdenoise::job;

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string input(reinterpret_cast<const char*>(data), size);
    const size_t nul = input.find('\0');
    const std::string path = input.substr(0, nul);
    const std::string list = nul == std::string::npos ? std::string()
                                                      : input.substr(nul + 1);
    std::string in_name;
    if (has_frame_pattern(path, &in_name)) {
        (void)frame_path(path, 1001);
        (void)frame_path(path, -7);
    }
    constexpr int kFuzzMaxFrames = 4096;
    std::vector<int> frames;
    if (!parse_frame_list(list, frames, kFuzzMaxFrames))
        return 0;
    if (frames.empty() || frames.size() > size_t(kFuzzMaxFrames)) {
        std::fprintf(stderr, "accepted %zu frames\n", frames.size());
        std::abort();
    }
    size_t chunked = 0;
    for (const std::string& chunk : frame_chunks(frames, 7)) {
        std::vector<int> part;
        if (!parse_frame_list(chunk, part)) {
            std::fprintf(stderr, "chunk '%s' refused\n", chunk.c_str());
            std::abort();
        }
        chunked += part.size();
    }
    if (chunked != frames.size()) {
        std::fprintf(stderr, "chunks hold %zu of %zu frames\n", chunked,
                     frames.size());
        std::abort();
    }
    return 0;
}
