// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Fuzzing the recipe parser (.zdn, share/zdn-format.md) with any text and
// any REST-style overrides: it must never crash or throw, a refusal must
// come with a one-line message, and what it accepts must write a recipe
// that it reads back to the same recipe text.
//
// Input: "RECIPE TEXT\0KEY=VALUE\0KEY=VALUE...".

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

#include "../../src/job/job.h"
#include "../../src/job/recipe.h"

using namespace zdenoise::job;

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string input(reinterpret_cast<const char*>(data), size);
    const size_t nul = input.find('\0');
    const std::string text = input.substr(0, nul);
    std::map<std::string, std::string> overrides;
    for (size_t at = nul; at != std::string::npos && at < input.size();) {
        const size_t next = input.find('\0', at + 1);
        const std::string arg = input.substr(at + 1, next == std::string::npos
                                                         ? std::string::npos
                                                         : next - at - 1);
        const size_t eq = arg.find('=');
        if (eq != std::string::npos)
            overrides[arg.substr(0, eq)] = arg.substr(eq + 1);
        at = next;
    }
    Job job;
    std::string error;
    if (!parse_recipe(text, "fuzz.zdn", "/fuzz", overrides, job, error)) {
        if (error.empty() || error.find('\n') != std::string::npos) {
            std::fprintf(stderr, "refused without a one-line message: '%s'\n",
                         error.c_str());
            std::abort();
        }
        return 0;
    }
    // What was accepted writes a recipe that reads back the same.
    const std::string written = recipe_text(job, "tuned", "/fuzz");
    Job again;
    if (!parse_recipe(written, "written.zdn", "/fuzz", {}, again, error)) {
        std::fprintf(stderr, "written recipe refused: %s\n%s\n", error.c_str(),
                     written.c_str());
        std::abort();
    }
    if (recipe_text(again, "tuned", "/fuzz") != written) {
        std::fprintf(stderr, "recipe changed on a round trip:\n%s\n",
                     written.c_str());
        std::abort();
    }
    return 0;
}
