// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// What a recipe may read and what it may cost (share/zdn-format.md,
// "Recipes from anywhere"): any OIIO program that opens a .zdn reads the
// files it names, so a recipe from an untrusted place is confined to its
// own folder and bounded. A part of reading recipes (recipe.cpp) of its
// own, because it is the security boundary.

#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace zdenoise {
namespace job {

/// The environment variables that widen what a recipe may do
/// (share/zdn-format.md, "Recipes from anywhere").
constexpr const char* kRecipePathVariable   = "ZDENOISE_RECIPE_PATH";
constexpr const char* kRecipeLimitsVariable = "ZDENOISE_RECIPE_LIMITS";

/// What a recipe may read and what it may cost. A recipe reads files in
/// its own folder only (after resolving `..` and symbolic links), or in
/// `folders`; its filter radius, its explicit layers and its image are
/// bounded (0: no bound).
struct RecipeRules {
    /// Other folders a recipe may read (canonical, absolute):
    /// ZDENOISE_RECIPE_PATH, colon-separated.
    std::vector<std::string> folders;
    /// ZDENOISE_RECIPE_LIMITS, "rmax=N,layers=N,pixels=N" (each optional;
    /// pixels may take a K, M or G suffix).
    int max_rmax          = 32;
    int max_layers        = 16;
    uint64_t max_pixels   = uint64_t(64) << 20;  ///< 8192 x 8192
};

/// The rules the values of ZDENOISE_RECIPE_PATH and ZDENOISE_RECIPE_LIMITS
/// give (null or empty: unset, the defaults). On a malformed value returns
/// false and a one-line `error` naming the variable.
bool
parse_recipe_rules(const char* path, const char* limits, RecipeRules& rules,
                   std::string& error);

/// The rules of this process's environment.
bool
recipe_rules_from_environment(RecipeRules& rules, std::string& error);

/// The file a recipe in `folder` reads for its key `key`'s path `given`:
/// into `path` its resolved path (`..` and symbolic links followed), which
/// must lie in the recipe's folder or in one of `rules.folders` and be a
/// regular file when it exists (not a FIFO a reader would hang on, not a
/// device). Otherwise false, and a one-line `error` naming the key, the
/// path and why.
bool
confine_path(const std::string& key, const std::string& given,
             const std::string& folder, const RecipeRules& rules,
             std::string& path, std::string& error);

/// `text` with its control characters escaped (\xNN): messages quote what
/// a recipe or the environment gave, and stay one line whatever it holds.
std::string
control_escaped(const std::string& text);

}  // namespace job
}  // namespace zdenoise
