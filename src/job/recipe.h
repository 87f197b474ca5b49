// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Recipes: a denoise job as a small JSON file (`.zdn`) that the OIIO plugin
// reads as the denoised image. The format is documented in
// share/zdn-format.md; `zdenoise --write-recipe` writes one.

#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "job_types.h"
#include "options.h"
#include "recipe_rules.h"

namespace zdenoise {
namespace job {

/// The file name extension of recipes (without the dot).
constexpr const char* kRecipeExtension = "zdn";

/// The version of the format this code reads and writes: the value of the
/// recipe's "zdenoise-recipe" key.
constexpr int kRecipeFormatVersion = 1;

/// Does `filename` (which may carry REST-style arguments, `a.zdn?eta=0.03`)
/// name a file that looks like a recipe: small, a JSON object with a
/// "zdenoise-recipe" key? Reads the file but does not check the job.
bool
looks_like_recipe(const std::string& filename);

/// Read the recipe `filename` into `job`. REST-style arguments after a `?`
/// (`shot.zdn?threads=2&eta=0.03`) override the recipe's keys of the same
/// names. Input paths are resolved against the recipe's folder and must
/// stay in it (or in a folder of ZDENOISE_RECIPE_PATH); the cost bounds of
/// ZDENOISE_RECIPE_LIMITS apply (RecipeRules). On failure returns false and
/// a one-line `error` naming the recipe and the problem. Never throws.
bool
read_recipe(const std::string& filename, Job& job, std::string& error);

/// Parse recipe text (`name` is used in messages; relative input paths are
/// resolved against `folder`, "" the current one) with `overrides` (key ->
/// text, as REST arguments give them) applied, under `rules`. The job's
/// paths are the files' canonical paths. Never throws.
bool
parse_recipe(const std::string& text, const std::string& name,
             const std::string& folder,
             const std::map<std::string, std::string>& overrides,
             const RecipeRules& rules, Job& job, std::string& error);

/// Set options of `command` from keyword arguments (the Python module's,
/// src/python): `keywords` is a JSON object of option names as
/// Spelling::Keyword spells them (value_k) with values as a recipe spells
/// them (a number, a string, true or false, an input's path or {"path",
/// "channels"}, lists for "halves" and "layers"). Each is read as a
/// recipe's key is, with its messages; "preset" first, the base the
/// others modify. Unlike a recipe's, paths are taken as they are given
/// (relative to the current folder), the recipe rules do not apply, and an
/// input may itself be a recipe, as on the command line: the caller runs
/// with its own rights, it is not a file from anywhere. Only the options
/// `accepts` are known (another name is an unknown key, and the message
/// lists the known ones). No validate(): the caller's job is not complete
/// yet. On failure returns false and a one-line `error`. Never throws.
bool
set_keyword_options(const nlohmann::json& keywords,
                    const std::function<bool(const Option&)>& accepts,
                    Command& command, std::string& error);

/// The recipe text for `job` whose filter options started from `preset`,
/// with input paths relative to `folder` (absolute when they are on
/// another root). Every filter option is written, so the recipe does not
/// change meaning if the defaults do.
std::string
recipe_text(const Job& job, const std::string& preset,
            const std::string& folder);

/// Write the recipe for `job` to `path` (through a temporary file; paths
/// relative to the recipe's folder). Refuses inputs that are recipes, and a
/// recipe that read_recipe() would refuse in this environment (an input
/// outside the recipe's folder and ZDENOISE_RECIPE_PATH, a radius beyond
/// ZDENOISE_RECIPE_LIMITS).
bool
write_recipe(const Job& job, const std::string& preset,
             const std::string& path, std::string& error);

}  // namespace job
}  // namespace zdenoise
