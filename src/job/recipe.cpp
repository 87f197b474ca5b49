// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "recipe.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include <nlohmann/json.hpp>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include "atomic_write.h"
#include "failure.h"
#include "frames.h"
#include "options.h"
#include "recipe_values.h"
#include "validate.h"

namespace zdenoise {
namespace job {

using OIIO::Strutil::fmt::format;
namespace Filesystem = OIIO::Filesystem;
namespace Strutil    = OIIO::Strutil;
using json           = nlohmann::json;
using OIIO::TypeDesc;
namespace fs         = std::filesystem;

using namespace recipe_values;

namespace {

/// Recipes are small; a bigger file is something else, and is not read
/// whole just to find out.
constexpr uint64_t kMaxRecipeBytes = 1 << 20;

constexpr const char* kVersionKey = "zdenoise-recipe";

/// The keys of a recipe; `in_file_name`: those a file name's REST-style
/// arguments may override.
std::string
known_keys(bool in_file_name)
{
    std::string s = in_file_name ? "" : kVersionKey;
    for (const Option& o : options())
        if (o.key && (o.in_file_name || !in_file_name))
            s += (s.empty() ? "" : ", ") + std::string(o.key);
    return s;
}


/// Where parse_option() takes its values from, and so what it makes of
/// them: a recipe (`rules` its rules: paths resolved in `folder`, the
/// recipe's, and confined to it), or a caller's keyword arguments (null
/// `rules`: paths as given, as on the command line). `spelling`: how the
/// messages name keys.
struct Source {
    std::string folder;
    const RecipeRules* rules = nullptr;
    Spelling spelling        = Spelling::Recipe;
};


bool
is_recipe_path(const std::string& path)
{
    std::string base = path;
    std::map<std::string, std::string> args;
    Strutil::get_rest_arguments(path, base, args);
    return Strutil::iequals(Filesystem::extension(base, false),
                            kRecipeExtension);
}


/// The file a recipe in `source.folder` reads for `key`'s path `given`
/// (confine_path()), or the recipe's error; keyword arguments' `given`.
std::string
confined(const std::string& key, const std::string& given,
         const Source& source)
{
    if (!source.rules)
        return given;
    std::string path, error;
    if (!confine_path(key, given, source.folder, *source.rules, path, error))
        fail_escaped(error);
    return path;
}


/// An input: "path" or {"path": "...", "channels": "..."}; a recipe's
/// relative paths are relative to its folder, and confined() to it.
InputArg
parse_input(const std::string& key, const json& value, const Source& source)
{
    InputArg arg;
    arg.given = true;
    if (value.is_string()) {
        arg.path = value.get<std::string>();
    } else if (value.is_object()) {
        for (const auto& item : value.items()) {
            if (item.key() == "path" && item.value().is_string())
                arg.path = item.value().get<std::string>();
            else if (item.key() == "channels" && item.value().is_string())
                arg.channels = item.value().get<std::string>();
            else if (item.key() == "path" || item.key() == "channels")
                fail_escaped(format("\"{}\": \"{}\" must be a string, not {}", key,
                            item.key(), shown(item.value())));
            else
                fail_escaped(format("\"{}\": unknown key \"{}\" (known: path, "
                            "channels)",
                            key, item.key()));
        }
    } else {
        fail_escaped(format("\"{}\" must be a file name or {{\"path\": ..., "
                    "\"channels\": ...}}, not {}",
                    key, shown(value)));
    }
    if (arg.path.empty())
        fail_escaped(format("\"{}\" names no file (\"path\" is missing or empty)",
                    key));
    if (source.rules && is_recipe_path(arg.path))
        fail_escaped(format("\"{}\" is '{}', itself a recipe: a recipe's inputs must "
                    "be images, not recipes",
                    key, arg.path));
    arg.path = confined(key, arg.path, source);
    return arg;
}


/// Apply the REST-style arguments to the recipe's keys: each replaces the
/// key of its name; "preset" replaces every filter option of the recipe by
/// the preset's (then other arguments apply on top).
void
apply_overrides(json& recipe,
                const std::map<std::string, std::string>& overrides)
{
    auto preset = overrides.find("preset");
    if (preset != overrides.end()) {
        for (const Option& o : options())
            if (o.parameter)
                recipe.erase(o.key);
        recipe["preset"] = preset->second;
    }
    for (const auto& [key, text] : overrides) {
        const Option* option = find_key(key);
        double real          = 0.0;
        int whole            = 0;
        if (key == "preset")
            continue;
        // A recipe is JSON, and JSON text is UTF-8: a recipe read with such
        // an argument could not be written back (found by fuzz_recipe).
        try {
            (void)json(text).dump();
        } catch (const json::exception&) {
            fail_escaped(format("argument '{}' is not UTF-8 text", key));
        }
        if (key == kVersionKey || (option && !option->in_file_name))
            fail_escaped(format("argument '{}' cannot be given after the '?'; edit "
                        "the recipe",
                        key));
        if (!option)
            fail_escaped(format("unknown argument '{}' after the '?' (known: {})", key,
                        known_keys(true)));
        switch (option->kind) {
        case Kind::Flag:
            if (text == "1" || text == "true")
                recipe[key] = true;
            else if (text == "0" || text == "false")
                recipe[key] = false;
            else
                fail_escaped(format("argument {}={} must be 1, 0, true or false", key,
                            text));
            break;
        case Kind::Whole:
            if (!parse_whole(text, whole))
                fail_escaped(format("argument {}={} must be a whole number", key,
                            text));
            recipe[key] = whole;
            break;
        case Kind::Real:
            if (!parse_real(text, real))
                fail_escaped(format("argument {}={} must be a number", key, text));
            recipe[key] = real;
            break;
        default: recipe[key] = text;
        }
    }
}


/// Set `option` of `command` from its recipe value.
void
parse_option(const Option& option, const json& value, const Source& source,
             Command& command)
{
    const std::string key = option_name(option, source.spelling);
    switch (option.kind) {
    case Kind::Input:
        std::get<Field<InputArg>>(option.field)(command)
            = parse_input(key, value, source);
        break;
    case Kind::Halves:
        if (!value.is_array() || value.size() != 2)
            fail_escaped(format("\"halves\" must be a list of two inputs, not {}",
                        shown(value)));
        command.job.half_a = parse_input(key, value[0], source);
        command.job.half_b = parse_input(key, value[1], source);
        break;
    case Kind::Flag:
        if (!value.is_boolean())
            fail_escaped(format("\"{}\" must be true or false, not {}", key,
                        shown(value)));
        std::get<Field<bool>>(option.field)(command) = value.get<bool>();
        break;
    case Kind::Text:
    case Kind::Name:
    case Kind::Path: {
        std::string text = parse_string(key, value, option.kind != Kind::Text);
        if (option.kind == Kind::Path)
            text = confined(key, text, source);
        std::get<Field<std::string>>(option.field)(command) = text;
        break;
    }
    case Kind::Layers: {
        if (!value.is_array())
            fail_escaped(format("\"layers\" must be a list of "
                        "\"NAME=RADIANCE:ALBEDO[:divided][:reflected]\", not {}",
                        shown(value)));
        if (source.rules && source.rules->max_layers
            && value.size() > size_t(source.rules->max_layers))
            fail_escaped(format("\"layers\" lists {} layers: more than the {} a "
                        "recipe may ({}=layers=N allows more)",
                        value.size(), source.rules->max_layers,
                        kRecipeLimitsVariable));
        std::vector<LayerArg>& layers
            = std::get<Field<std::vector<LayerArg>>>(option.field)(command);
        for (const json& layer : value) {
            layers.emplace_back();
            if (!layer.is_string()
                || !parse_layer(layer.get<std::string>(), layers.back()))
                fail_escaped(format("\"layers\": each must be "
                            "\"NAME=RADIANCE:ALBEDO[:divided][:reflected]\", not {}",
                            shown(layer)));
        }
        break;
    }
    case Kind::Names: {
        if (!value.is_array())
            fail_escaped(format("\"{}\" must be a list of names, not {}", key,
                                shown(value)));
        std::vector<std::string>& names
            = std::get<Field<std::vector<std::string>>>(option.field)(command);
        for (const json& name : value)
            names.push_back(parse_string(key, name, true));
        break;
    }
    case Kind::Mode:
    case Kind::DataType: {
        const std::string text = parse_string(key, value, false);
        const bool mode        = option.kind == Kind::Mode;
        if (!(mode ? parse_mode(text,
                                std::get<Field<Mode>>(option.field)(command))
                   : parse_data_type(
                       text, std::get<Field<TypeDesc>>(option.field)(command))))
            fail_escaped(format("\"{}\" must be {}, not {}", key,
                        mode ? "\"beauty\", \"layers\" or \"path\""
                             : "\"half\" or \"float\"",
                        shown(value)));
        break;
    }
    case Kind::Whole:
        std::get<Field<int>>(option.field)(command)
            = parse_whole_number(key, value);
        break;
    case Kind::Real:
        std::get<Field<float>>(option.field)(command) = parse_float(key,
                                                                    value);
        break;
    default: break;  // the preset is applied first
    }
}


/// The "preset" key's `value`, applied to `command` (before the other
/// filter options, which modify it). `key`: the key as the messages name it.
void
parse_preset(const std::string& key, const json& value, Command& command)
{
    if (!value.is_string())
        fail_escaped(format("\"{}\" must be a string, not {}", key, shown(value)));
    if (!apply_preset(value.get<std::string>(), command.job.filter))
        fail_escaped(format("unknown preset '{}' (known: {})",
                    value.get<std::string>(), preset_names()));
    command.preset = value.get<std::string>();
}


Job
parse(const std::string& text, const std::string& folder,
      const std::map<std::string, std::string>& overrides,
      const RecipeRules& rules)
{
    json recipe;
    try {
        recipe = json::parse(text);
    } catch (const json::parse_error& e) {
        // Drop nlohmann's "[json.exception.parse_error.101] " prefix.
        std::string why = e.what();
        size_t bracket  = why.find("] ");
        if (!why.empty() && why.front() == '[' && bracket != std::string::npos)
            why = why.substr(bracket + 2);
        fail_escaped("not valid JSON: " + why);
    }
    if (!recipe.is_object())
        fail_escaped("not a zdenoise recipe: a recipe is a JSON object {...}");
    if (!recipe.contains(kVersionKey))
        fail_escaped(format("not a zdenoise recipe: it has no \"{}\": {} line",
                    kVersionKey, kRecipeFormatVersion));
    const json& version = recipe.at(kVersionKey);
    if (!version.is_number_integer() || version.get<int>() < 1)
        fail_escaped(format("\"{}\" must be {}, not {}", kVersionKey,
                    kRecipeFormatVersion, shown(version)));
    if (version.get<int>() > kRecipeFormatVersion)
        fail_escaped(format("written for a newer zdenoise (format {}; this one reads "
                    "format {})",
                    version.get<int>(), kRecipeFormatVersion));
    apply_overrides(recipe, overrides);

    Command command;
    // The preset is the base the other filter options modify, as on the
    // command line.
    if (recipe.contains("preset"))
        parse_preset("preset", recipe.at("preset"), command);
    const Source source { folder, &rules, Spelling::Recipe };
    for (const auto& item : recipe.items()) {
        if (item.key() == kVersionKey)
            continue;
        const Option* option = find_key(item.key());
        if (!option)
            fail_escaped(format("unknown key \"{}\" (known: {})", item.key(),
                        known_keys(false)));
        parse_option(*option, item.value(), source, command);
    }
    const std::string invalid = validate(command.job, Spelling::Recipe);
    if (!invalid.empty())
        fail_escaped(invalid);
    const std::string frame = frame_problem(command.job);
    if (!frame.empty())
        fail_escaped(frame);
    if (rules.max_rmax && command.job.filter.r_max > rules.max_rmax)
        fail_escaped(format("\"rmax\" is {}: more than the {} a recipe may ask for "
                    "({}=rmax=N allows more)",
                    command.job.filter.r_max, rules.max_rmax,
                    kRecipeLimitsVariable));
    command.job.max_pixels = rules.max_pixels;
    return command.job;
}


/// `path` relative to `folder`, unless their only common folder is the root
/// (then absolute). Symbolic links are resolved first so that `..` means
/// what the file system will make of it.
std::string
relative_path(const std::string& path, const std::string& folder)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::path target = fs::weakly_canonical(fs::absolute(path, ec), ec);
    if (ec)
        return path;
    fs::path base = fs::weakly_canonical(
        fs::absolute(folder.empty() ? "." : folder, ec), ec);
    if (ec)
        return target.string();
    const fs::path relative = target.lexically_relative(base);
    size_t ups = 0, depth = 0;
    for (const fs::path& part : relative)
        ups += part == "..";
    for (const fs::path& part : base.relative_path())
        depth += !part.empty();
    if (relative.empty() || ups >= depth)
        return target.generic_string();
    return relative.generic_string();
}


nlohmann::ordered_json
input_json(const InputArg& arg, const std::string& folder)
{
    if (is_recipe_path(arg.path))
        fail_escaped(format("the input '{}' is itself a recipe: a recipe's inputs "
                    "must be images, not recipes",
                    arg.path));
    nlohmann::ordered_json value = nlohmann::ordered_json::object();
    value["path"] = relative_path(arg.path, folder);
    if (!arg.channels.empty())
        value["channels"] = arg.channels;
    return value;
}

}  // namespace




bool
looks_like_recipe(const std::string& filename)
{
    std::string path = filename;
    std::map<std::string, std::string> args;
    Strutil::get_rest_arguments(filename, path, args);
    if (!Filesystem::is_regular(path)
        || Filesystem::file_size(path) > kMaxRecipeBytes)
        return false;
    std::string text;
    if (!Filesystem::read_text_file(path, text))
        return false;
    json recipe = json::parse(text, nullptr, /*allow_exceptions=*/false);
    return recipe.is_object() && recipe.contains(kVersionKey);
}


bool
parse_recipe(const std::string& text, const std::string& name,
             const std::string& folder,
             const std::map<std::string, std::string>& overrides,
             const RecipeRules& rules, Job& job, std::string& error)
{
    try {
        job = parse(text, folder, overrides, rules);
        return true;
    } catch (const Failure& f) {
        error = format("recipe '{}': {}", name, f.message);
    } catch (const std::exception& e) {
        error = format("recipe '{}': {}", name, e.what());
    }
    return false;
}


bool
read_recipe(const std::string& filename, Job& job, std::string& error)
{
    std::string path;
    std::map<std::string, std::string> overrides;
    if (!Strutil::get_rest_arguments(filename, path, overrides)) {
        error = format("recipe '{}': the arguments after '?' must be "
                       "key=value pairs joined by '&'",
                       filename);
        return false;
    }
    if (!Filesystem::exists(path)) {
        error = format("recipe '{}': no such file", path);
        return false;
    }
    if (!Filesystem::is_regular(path)
        || Filesystem::file_size(path) > kMaxRecipeBytes) {
        error = format("recipe '{}': not a zdenoise recipe (not a file of at "
                       "most {} bytes)",
                       path, kMaxRecipeBytes);
        return false;
    }
    std::string text;
    if (!Filesystem::read_text_file(path, text)) {
        error = format("recipe '{}': cannot read the file", path);
        return false;
    }
    RecipeRules rules;
    if (!recipe_rules_from_environment(rules, error)) {
        error = format("recipe '{}': {}", path, error);
        return false;
    }
    if (!parse_recipe(text, path, Filesystem::parent_path(path), overrides,
                      rules, job, error))
        return false;
    job = resolve_frame(job);
    return true;
}


bool
set_keyword_options(const json& keywords,
                    const std::function<bool(const Option&)>& accepts,
                    Command& command, std::string& error)
{
    try {
        if (!keywords.is_object())
            fail_escaped("the options must be an object of names and values");
        auto find = [&](const std::string& name) -> const Option& {
            const Option* option = find_option(name, Spelling::Keyword);
            if (!option || !accepts(*option)) {
                std::string known;
                for (const Option& o : options())
                    if (o.key && accepts(o))
                        known += (known.empty() ? "" : ", ")
                                 + option_name(o, Spelling::Keyword);
                fail_escaped(format("unknown key \"{}\" (known: {})", name, known));
            }
            return *option;
        };
        // The preset is the base the other filter options modify, as on
        // the command line and in recipes.
        for (const auto& item : keywords.items())
            if (find(item.key()).kind == Kind::Preset)
                parse_preset(item.key(), item.value(), command);
        const Source source { "", nullptr, Spelling::Keyword };
        for (const auto& item : keywords.items())
            parse_option(find(item.key()), item.value(), source, command);
        return true;
    } catch (const Failure& f) {
        error = f.message;
    } catch (const std::exception& e) {
        error = one_line(e.what());
    }
    return false;
}


std::string
recipe_text(const Job& job, const std::string& preset,
            const std::string& folder)
{
    Command command;
    command.job    = job;
    command.preset = preset;
    nlohmann::ordered_json recipe;
    recipe[kVersionKey] = kRecipeFormatVersion;
    for (const Option& o : options()) {
        if (!o.key)
            continue;
        nlohmann::ordered_json value;
        switch (o.kind) {
        case Kind::Input: {
            const InputArg& arg = std::get<Field<InputArg>>(o.field)(command);
            if (arg.given)
                value = input_json(arg, folder);
            break;
        }
        case Kind::Halves:
            if (job.half_a.given)
                value = nlohmann::ordered_json::array(
                    { input_json(job.half_a, folder),
                      input_json(job.half_b, folder) });
            break;
        case Kind::Flag:
            if (std::get<Field<bool>>(o.field)(command))
                value = true;
            break;
        case Kind::Text:
        case Kind::Name:
        case Kind::Path:
        case Kind::Preset: {
            const std::string& text = std::get<Field<std::string>>(o.field)(
                command);
            if (!text.empty() || o.always_written)
                value = o.kind == Kind::Path ? relative_path(text, folder)
                                             : text;
            break;
        }
        case Kind::Mode:
            if (job.mode != Mode::Auto)
                value = mode_name(job.mode);
            break;
        case Kind::Names: {
            const std::vector<std::string>& names
                = std::get<Field<std::vector<std::string>>>(o.field)(command);
            if (!names.empty())
                value = names;
            break;
        }
        case Kind::Layers:
            if (!job.layers.empty()) {
                value = nlohmann::ordered_json::array();
                for (const LayerArg& layer : job.layers)
                    value.push_back(layer_text(layer));
            }
            break;
        case Kind::DataType:
            if (job.data_type != OIIO::TypeUnknown)
                value = job.data_type.c_str();
            break;
        case Kind::Whole: {
            // Only when given unless always written: a recipe without
            // "tile" stays readable by a plugin that predates strips.
            const int whole = std::get<Field<int>>(o.field)(command);
            if (whole > 0 || o.always_written)
                value = whole;
            break;
        }
        case Kind::Real:
            // The shortest decimal that reads back as the same float
            // ("0.02", not 0.019999999552965164).
            value = std::stod(
                format("{}", std::get<Field<float>>(o.field)(command)));
            break;
        default: break;
        }
        if (!value.is_null())
            recipe[o.key] = value;
    }
    return recipe.dump(2) + "\n";
}


bool
write_recipe(const Job& job, const std::string& preset,
             const std::string& path, std::string& error)
{
    std::string text;
    const std::string folder = Filesystem::parent_path(path);
    try {
        text = recipe_text(job, preset, folder);
    } catch (const Failure& f) {
        error = format("cannot write recipe '{}': {}", path, f.message);
        return false;
    } catch (const std::exception& e) {
        error = format("cannot write recipe '{}': {}", path, e.what());
        return false;
    }
    // A recipe the plugin would refuse here is not written: its inputs
    // must lie in its folder or in ZDENOISE_RECIPE_PATH.
    RecipeRules rules;
    std::string refused;
    if (!recipe_rules_from_environment(rules, refused)) {
        error = format("cannot write recipe '{}': {}", path, refused);
        return false;
    }
    try {
        parse(text, folder, {}, rules);
    } catch (const Failure& f) {
        error = format("cannot write recipe '{}': it would not be read: {}; "
                       "write it in a folder that holds its inputs, or list "
                       "their folder in {}",
                       path, f.message, kRecipePathVariable);
        return false;
    }
    return write_text_atomically(path, text, error);
}

}  // namespace job
}  // namespace zdenoise
