// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Options as keyword arguments (the Python module's, python/): named by
// the recipe keys with '_' for '-', read by the recipes' own code
// (job::set_keyword_options()), with the recipes' messages in that
// spelling, but with paths as the command line takes them.

#include <cctype>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <zdenoise/zdenoise.h>

#include "job/options.h"
#include "job/recipe.h"
#include "job/validate.h"

using namespace zdenoise;
using json = nlohmann::json;

namespace {

bool
any_option(const job::Option&)
{
    return true;
}

bool
filter_option(const job::Option& o)
{
    return o.parameter || o.kind == job::Kind::Preset;
}

/// The message set_keyword_options() gives for `keywords`, "" if none.
std::string
refusal(const json& keywords, bool (*accepts)(const job::Option&) = any_option)
{
    job::Command command;
    std::string error;
    return job::set_keyword_options(keywords, accepts, command, error)
               ? ""
               : error;
}

}  // namespace


TEST(Keywords, EveryRecipeKeyIsAPythonIdentifier)
{
    // Python's reserved words: a keyword argument cannot be one ("in" is
    // denoise_file's first argument instead).
    const std::set<std::string> reserved
        = { "False", "None",   "True",    "and",      "as",     "assert",
            "async", "await",  "break",   "class",    "continue", "def",
            "del",   "elif",   "else",    "except",   "finally", "for",
            "from",  "global", "if",      "import",   "in",     "is",
            "lambda", "nonlocal", "not",  "or",       "pass",   "raise",
            "return", "try",   "while",   "with",     "yield" };
    std::set<std::string> seen;
    for (const job::Option& o : job::options()) {
        const std::string name = job::option_name(o, job::Spelling::Keyword);
        if (!o.key) {
            EXPECT_EQ(name, "") << o.flag;
            continue;
        }
        EXPECT_EQ(std::string(o.key).find('_'), std::string::npos)
            << "recipe key " << o.key << ": '_' would make two keys one keyword";
        EXPECT_TRUE(seen.insert(name).second) << name;
        for (char c : name)
            EXPECT_TRUE(std::isalnum((unsigned char)c) || c == '_') << name;
        if (name != "in") {
            EXPECT_EQ(reserved.count(name), 0u) << name;
        }
        EXPECT_EQ(job::find_option(name, job::Spelling::Keyword), &o);
    }
    EXPECT_EQ(job::find_option("value-k", job::Spelling::Keyword), nullptr);
    EXPECT_EQ(job::option_name(*job::find_key("value-k"),
                               job::Spelling::CommandLine),
              "--value-k");
}


TEST(Keywords, SetTheOptionsARecipeSets)
{
    // The preset first, whatever the order (a JSON object sorts edge_k
    // before preset), then the others on top of it.
    job::Command command;
    std::string error;
    ASSERT_TRUE(job::set_keyword_options(
        { { "preset", "spec" }, { "edge_k", 2 }, { "eta", 0.03 },
          { "stride", 2 }, { "threads", 3 }, { "mode", "layers" },
          { "no_depth", true }, { "data_type", "half" },
          { "layers", { "diff=DiffDir+DiffInd:DiffCol:divided" } } },
        any_option, command, error))
        << error;
    FilterOptions expected = FilterOptions::algorithm_defaults();
    expected.edge_k        = 2.0f;
    expected.eta_target    = 0.03f;
    expected.centre_stride = 2;
    EXPECT_EQ(describe(command.job.filter), describe(expected));
    EXPECT_EQ(command.preset, "spec");
    EXPECT_EQ(command.job.threads, 3);
    EXPECT_EQ(command.job.mode, job::Mode::Layers);
    EXPECT_TRUE(command.job.no_depth);
    EXPECT_EQ(command.job.data_type, OIIO::TypeHalf);
    ASSERT_EQ(command.job.layers.size(), 1u);
    EXPECT_TRUE(command.job.layers[0].divided);

    // The same as a recipe gives them.
    job::Job from_recipe;
    ASSERT_TRUE(job::parse_recipe(
        R"({"zdenoise-recipe": 1, "in": "x.exr", "preset": "spec", "edge-k": 2,
            "eta": 0.03, "stride": 2})",
        "r.zdn", "", {}, job::RecipeRules(), from_recipe, error))
        << error;
    EXPECT_EQ(describe(from_recipe.filter), describe(command.job.filter));
}


TEST(Keywords, PathsAreTakenAsGiven)
{
    // As on the command line, not as in a recipe: relative paths stay
    // relative to the current folder, absolute ones and '..' are not
    // confined, and nothing need exist yet.
    job::Command command;
    std::string error;
    ASSERT_TRUE(job::set_keyword_options(
        { { "albedo", "../elsewhere/albedo.exr" },
          { "normal", "/absolute/normal.exr" },
          { "aux", { { "path", "aux.exr" }, { "channels", "albedo" } } },
          { "halves", { "a.exr", "b.exr" } },
          { "colorconfig", "studio.ocio" } },
        any_option, command, error))
        << error;
    EXPECT_EQ(command.job.albedo.path, "../elsewhere/albedo.exr");
    EXPECT_TRUE(command.job.albedo.given);
    EXPECT_EQ(command.job.normal.path, "/absolute/normal.exr");
    EXPECT_EQ(command.job.aux.path, "aux.exr");
    EXPECT_EQ(command.job.aux.channels, "albedo");
    EXPECT_EQ(command.job.half_a.path, "a.exr");
    EXPECT_EQ(command.job.half_b.path, "b.exr");
    EXPECT_EQ(command.job.colour.config, "studio.ocio");
}


TEST(Keywords, MessagesAreTheRecipesInTheKeywordSpelling)
{
    EXPECT_EQ(refusal({ { "value_k", "x" } }),
              "\"value_k\" must be a number, not \"x\"");
    EXPECT_EQ(refusal({ { "rmin", 2.5 } }),
              "\"rmin\" must be a whole number, not 2.5");
    EXPECT_EQ(refusal({ { "no_normal", 1 } }),
              "\"no_normal\" must be true or false, not 1");
    EXPECT_EQ(refusal({ { "preset", "fast" } }),
              "unknown preset 'fast' (known: tuned, spec)");
    EXPECT_EQ(refusal({ { "halves", { "a.exr" } } }),
              "\"halves\" must be a list of two inputs, not [\"a.exr\"]");
    EXPECT_EQ(refusal({ { "albedo", "" } }),
              "\"albedo\" names no file (\"path\" is missing or empty)");
    // A key in the recipe's spelling is not a keyword.
    EXPECT_EQ(refusal({ { "value-k", 1 } }, filter_option).rfind(
                  "unknown key \"value-k\" (known: preset, rmin, rmax, eta, "
                  "edge_k",
                  0),
              0u);
    // Only the accepted options are known, and listed.
    const std::string unknown = refusal({ { "albedo", "a.exr" } },
                                        filter_option);
    EXPECT_EQ(unknown.rfind("unknown key \"albedo\" (known: preset, ", 0), 0u)
        << unknown;
    EXPECT_EQ(unknown.find("threads"), std::string::npos) << unknown;
    EXPECT_EQ(unknown.find("tile"), std::string::npos) << unknown;
    // One line, whatever the key holds.
    EXPECT_EQ(refusal({ { "a\nb", 1 } }).find('\n'), std::string::npos);
}


TEST(Keywords, OutputThatIsAnInputSaysHowEachFrontEndAllowsIt)
{
    job::Job j;
    j.in = { std::string(ZDENOISE_SOURCE_DIR)
                 + "/share/samples/cornell_textured_spp16_crop.exr",
             "", true };
    const std::string same = std::string(ZDENOISE_SOURCE_DIR)
                             + "/share/../share/samples/cornell_textured_spp16_crop.exr";
    EXPECT_EQ(job::output_is_input(j, same, false, job::Spelling::Keyword),
              "the output '" + same + "' is also an input; use force=True to "
              "replace it");
    EXPECT_EQ(job::output_is_input(j, same, false, job::Spelling::CommandLine),
              "the output '" + same + "' is also an input; use --force to "
              "replace it");
    EXPECT_EQ(job::output_is_input(j, same, true, job::Spelling::Keyword), "");
    EXPECT_EQ(job::output_is_input(j, same + ".out", false,
                                   job::Spelling::Keyword),
              "");
}
