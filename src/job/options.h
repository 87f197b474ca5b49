// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Every option of zdenoise, described once: one table of its name on the
// command line and in recipes, its kind, the member it sets and its help
// (as oiiotool's declarative argument table). The command line
// (src/cli/main.cpp), recipes (recipe.cpp: reading, writing and the
// `?key=value` overrides) and `zdenoise --help` all read the table, so an
// option means the same thing everywhere and a new one is added in one row.
// The spellings of the values (modes, pixel types, layers, numbers) live
// here too.

#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "job_types.h"

namespace zdenoise {
namespace job {

/// Everything a command line says: the job, and what to do with it.
struct Command {
    Job job;
    std::string preset = "tuned";  ///< the base of the filter options
    std::string output;            ///< -o
    std::string recipe;            ///< --write-recipe
    bool force   = false;
    bool verbose = false;
    /// Frame sequences and batches (src/cli/sequence.h).
    std::string frames, report;
    bool fail_fast = false, skip_existing = false;
    int print_chunks = 0;
};

/// What an option's value is, and so how each front end reads and writes it.
enum class Kind {
    Input,     ///< a file with a channel selection (`:ch=`; a recipe's
               ///< "path" or {"path", "channels"})
    Halves,    ///< two inputs (Job::half_a, Job::half_b)
    Flag,      ///< on when given (a recipe's true or false)
    Text,      ///< any string
    Name,      ///< a name that may not be empty (a colour space)
    Path,      ///< a file a recipe names relative to its folder
    Real,      ///< a finite number (a recipe's must fit a float)
    Whole,     ///< a whole number of at most 1e6 in magnitude
    Size,      ///< bytes, with a K, M, G or T suffix
    Mode,      ///< parse_mode()
    DataType,  ///< parse_data_type()
    Layers,    ///< parse_layer(); repeatable
    Names,     ///< a non-empty name; repeatable (a recipe's list)
    Preset,    ///< apply_preset(): the base the filter options modify
    Help,      ///< prints the help and exits
    Version    ///< prints the version and exits
};

/// An option's member, reached from the Command it belongs to.
template<class T> using Field = T& (*)(Command&);

struct Option {
    Kind kind;
    const char* flag;  ///< on the command line ("--albedo", "-o"), or null
    const char* key;   ///< in recipes ("albedo", "data-type"), or null
    std::variant<std::monostate, Field<InputArg>, Field<bool>,
                 Field<std::string>, Field<float>, Field<int>,
                 Field<uint64_t>, Field<Mode>, Field<OIIO::TypeDesc>,
                 Field<std::vector<LayerArg>>,
                 Field<std::vector<std::string>>>
        field;
    const char* arg  = "";       ///< the value in the help ("FILE")
    const char* help = nullptr;  ///< lines of help; null: not listed
    /// A parameter of the filter (set by a preset).
    bool parameter = false;
    /// May follow a recipe's name after '?' (`shot.zdn?eta=0.03`).
    bool in_file_name = true;
    /// Always written to a recipe; else only when set (not empty, not 0).
    bool always_written = false;
    /// The help lists the option under this name instead of flag + arg.
    const char* shown = nullptr;
};

/// Every option, in the order recipes are written.
const std::vector<Option>&
options();

/// The option spelled `flag` on the command line, or null.
const Option*
find_flag(const std::string& flag);

/// The option of recipe key `key`, or null.
const Option*
find_key(const std::string& key);

/// `zdenoise --help`.
std::string
usage_text();

/// The spellings of the command line and recipes: "beauty", "layers" (Auto
/// has none); "half", "float" for the output type;
/// "NAME=RADIANCE:ALBEDO[:divided][:reflected]" for a layer. Each parse
/// returns false for anything else.
bool
parse_mode(const std::string& text, Mode& mode);
const char*
mode_name(Mode mode);
bool
parse_data_type(const std::string& text, OIIO::TypeDesc& type);
bool
parse_layer(const std::string& text, LayerArg& layer);
std::string
layer_text(const LayerArg& layer);

/// The named parameter sets: "tuned" (FilterOptions' defaults) and "spec"
/// (FilterOptions::algorithm_defaults()). Sets the parameters of `options`
/// (leaving its progress callback alone); false for an unknown name.
bool
apply_preset(const std::string& preset, FilterOptions& options);

/// The preset names, for messages: "tuned, spec".
const char*
preset_names();

/// Parse all of `text` as a finite number; false for anything else
/// ("", "1x", "nan", out of range).
bool
parse_real(const std::string& text, double& value);

/// Parse all of `text` as a whole number of at most 1e6 in magnitude.
bool
parse_whole(const std::string& text, int& value);

/// Parse all of `text` as a size of at least 1 with an optional binary
/// suffix: "1048576", "512M", "8G" (K, M, G, T: 2^10, 2^20, 2^30, 2^40).
bool
parse_size(const std::string& text, uint64_t& value);

/// How a front end names options, in its messages and (Keyword) when it
/// looks them up.
enum class Spelling {
    CommandLine,  ///< the flag: --value-k
    Recipe,       ///< the recipe key: "value-k"
    Keyword       ///< a Python keyword argument (src/python): the recipe
                  ///< key with '_' for '-', value_k
};

/// `option`'s name as `spelling` names it; "" when it has none there (-o
/// has no recipe key, so no keyword either).
std::string
option_name(const Option& option, Spelling spelling);

/// The option `spelling` names `name`, or null.
const Option*
find_option(const std::string& name, Spelling spelling);

}  // namespace job
}  // namespace zdenoise
