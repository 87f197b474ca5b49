// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Fuzzing the recipe parser (.zdn, share/zdn-format.md) with any text,
// any REST-style overrides and any values of the variables that widen what
// a recipe may read and cost: it must never crash or throw, a refusal must
// come with a one-line message, what it accepts must lie in the recipe's
// folder (/fuzz) or a listed one, and it must write a recipe that it reads
// back, under the same rules, to the same recipe text.
//
// Input: "RECIPE TEXT\0KEY=VALUE\0KEY=VALUE...", where the keys
// ZDENOISE_RECIPE_PATH and ZDENOISE_RECIPE_LIMITS give those variables'
// values rather than overrides.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "job/job.h"
#include "job/recipe.h"
#include "job/validate.h"

using namespace zdenoise::job;

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string input(reinterpret_cast<const char*>(data), size);
    const size_t nul = input.find('\0');
    const std::string text = input.substr(0, nul);
    std::map<std::string, std::string> overrides, variables;
    for (size_t at = nul; at != std::string::npos && at < input.size();) {
        const size_t next = input.find('\0', at + 1);
        const std::string arg = input.substr(at + 1, next == std::string::npos
                                                         ? std::string::npos
                                                         : next - at - 1);
        const size_t eq = arg.find('=');
        const std::string key = arg.substr(0, eq);
        if (eq != std::string::npos)
            (key == kRecipePathVariable || key == kRecipeLimitsVariable
                 ? variables
                 : overrides)[key]
                = arg.substr(eq + 1);
        at = next;
    }
    auto variable = [&](const char* name) {
        auto it = variables.find(name);
        return it == variables.end() ? nullptr : it->second.c_str();
    };
    RecipeRules rules;
    std::string error;
    if (!parse_recipe_rules(variable(kRecipePathVariable),
                            variable(kRecipeLimitsVariable), rules, error)) {
        if (error.empty() || error.find('\n') != std::string::npos) {
            std::fprintf(stderr, "rules refused without a one-line message: "
                                 "'%s'\n",
                         error.c_str());
            std::abort();
        }
        return 0;
    }
    Job job;
    if (!parse_recipe(text, "fuzz.zdn", "/fuzz", overrides, rules, job,
                      error)) {
        if (error.empty() || error.find('\n') != std::string::npos) {
            std::fprintf(stderr, "refused without a one-line message: '%s'\n",
                         error.c_str());
            std::abort();
        }
        return 0;
    }
    // Every file accepted lies in /fuzz or a listed folder.
    auto under = [](const std::string& path, const std::string& folder) {
        return path.rfind(folder, 0) == 0
               && (folder == "/" || path.size() == folder.size()
                   || path[folder.size()] == '/');
    };
    std::vector<std::string> files = input_paths(job);
    if (!job.colour.config.empty())
        files.push_back(job.colour.config);
    for (const std::string& path : files) {
        bool inside = under(path, "/fuzz");
        for (const std::string& folder : rules.folders)
            inside = inside || under(path, folder);
        if (!inside) {
            std::fprintf(stderr, "accepted '%s', outside the folders\n",
                         path.c_str());
            std::abort();
        }
    }
    // What was accepted writes a recipe that reads back the same.
    const std::string written = recipe_text(job, "tuned", "/fuzz");
    Job again;
    if (!parse_recipe(written, "written.zdn", "/fuzz", {}, rules, again,
                      error)) {
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
