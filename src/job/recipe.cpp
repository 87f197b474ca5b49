// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "recipe.h"

#include <cerrno>
#include <cmath>
#include <limits>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include "atomic_write.h"
#include "option_names.h"

namespace zdenoise {
namespace job {

using OIIO::Strutil::fmt::format;
namespace Filesystem = OIIO::Filesystem;
namespace Strutil    = OIIO::Strutil;
using json           = nlohmann::json;

namespace {

/// Recipes are small; a bigger file is something else, and is not read
/// whole just to find out.
constexpr uint64_t kMaxRecipeBytes = 1 << 20;

constexpr const char* kVersionKey = "zdenoise-recipe";

/// Thrown inside this file only and turned into the callers' error.
struct Failure {
    std::string message;
};

/// Throw `message` with its control characters escaped: it quotes keys
/// and values the recipe or its REST arguments gave, and an error stays
/// one line whatever they hold (a newline in a key; found by
/// tests/fuzz/fuzz_recipe).
[[noreturn]] void
fail(const std::string& message)
{
    std::string line;
    for (unsigned char c : message) {
        if (c < 0x20 || c == 0x7f)
            line += format("\\x{:02x}", unsigned(c));
        else
            line += char(c);
    }
    throw Failure { line };
}


/// The single-file inputs, by recipe key (the command-line option names).
struct InputKey {
    const char* key;
    InputArg Job::*arg;
};

const InputKey kInputs[] = {
    { "in", &Job::in },         { "albedo", &Job::albedo },
    { "normal", &Job::normal }, { "depth", &Job::depth },
    { "id", &Job::id },         { "variance", &Job::variance },
};

struct FlagKey {
    const char* key;
    bool Job::*flag;
};

const FlagKey kFlags[] = { { "no-normal", &Job::no_normal },
                           { "no-depth", &Job::no_depth },
                           { "no-id", &Job::no_id },
                           { "aovs", &Job::write_layers } };

/// Keys whose value is one string of the command line's spelling.
bool
is_text_key(const std::string& key)
{
    return key == "mode" || key == "residual" || key == "data-type";
}

/// The colour options (ocio/colour.h), by recipe key (the option names).
struct ColourKey {
    const char* key;
    std::string colour::ColourOptions::*value;
    bool is_path;  ///< a file, relative to the recipe's folder
};
const ColourKey kColourKeys[]
    = { { "colorconfig", &colour::ColourOptions::config, true },
        { "iscolorspace", &colour::ColourOptions::input_space, false },
        { "albedo-colorspace", &colour::ColourOptions::albedo_space, false },
        { "ocolorspace", &colour::ColourOptions::output_space, false },
        { "working-colorspace", &colour::ColourOptions::working_space,
          false } };

const ColourKey*
find_colour(const std::string& key)
{
    for (const ColourKey& k : kColourKeys)
        if (key == k.key)
            return &k;
    return nullptr;
}

const InputKey*
find_input(const std::string& key)
{
    for (const InputKey& k : kInputs)
        if (key == k.key)
            return &k;
    return nullptr;
}

const FlagKey*
find_flag(const std::string& key)
{
    for (const FlagKey& k : kFlags)
        if (key == k.key)
            return &k;
    return nullptr;
}

const FilterOptionName*
find_filter_option(const std::string& key)
{
    for (const FilterOptionName& o : filter_option_names())
        if (key == o.name)
            return &o;
    return nullptr;
}

/// The keys of a recipe; `in_file_name`: those a file name's REST-style
/// arguments may override.
std::string
known_keys(bool in_file_name)
{
    std::string s = in_file_name ? "" : kVersionKey;
    for (const InputKey& k : kInputs)
        s += (s.empty() ? "" : ", ") + std::string(k.key);
    if (!in_file_name)
        s += ", halves";
    for (const FlagKey& k : kFlags)
        s += std::string(", ") + k.key;
    for (const ColourKey& k : kColourKeys)
        s += std::string(", ") + k.key;
    if (!in_file_name)
        s += ", layers";
    s += ", mode, residual, data-type, preset";
    for (const FilterOptionName& o : filter_option_names())
        s += std::string(", ") + o.name;
    return s + ", threads, tile";
}

/// A value as the recipe spells it, cut short for messages.
std::string
shown(const json& value)
{
    std::string s = value.dump();
    return s.size() > 40 ? s.substr(0, 37) + "..." : s;
}


bool
is_recipe_path(const std::string& path)
{
    std::string base = path;
    std::map<std::string, std::string> args;
    Strutil::get_rest_arguments(path, base, args);
    return Strutil::iequals(Filesystem::extension(base, false),
                            kRecipeExtension);
}


/// An input: "path" or {"path": "...", "channels": "..."}; relative paths
/// are relative to the recipe's folder.
InputArg
parse_input(const std::string& key, const json& value,
            const std::string& folder)
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
                fail(format("\"{}\": \"{}\" must be a string, not {}", key,
                            item.key(), shown(item.value())));
            else
                fail(format("\"{}\": unknown key \"{}\" (known: path, "
                            "channels)",
                            key, item.key()));
        }
    } else {
        fail(format("\"{}\" must be a file name or {{\"path\": ..., "
                    "\"channels\": ...}}, not {}",
                    key, shown(value)));
    }
    if (arg.path.empty())
        fail(format("\"{}\" names no file (\"path\" is missing or empty)",
                    key));
    if (is_recipe_path(arg.path))
        fail(format("\"{}\" is '{}', itself a recipe: a recipe's inputs must "
                    "be images, not recipes",
                    key, arg.path));
    if (!folder.empty() && !Filesystem::path_is_absolute(arg.path))
        arg.path = folder + "/" + arg.path;
    return arg;
}


double
parse_number(const std::string& key, const json& value)
{
    if (!value.is_number())
        fail(format("\"{}\" must be a number, not {}", key, shown(value)));
    return value.get<double>();
}

/// A filter option's number: it must fit a float (1e50 would become
/// infinity, which a recipe cannot even be written back with).
float
parse_float(const std::string& key, const json& value)
{
    const double v = parse_number(key, value);
    if (!(std::fabs(v) <= double(std::numeric_limits<float>::max())))
        fail(format("\"{}\" is out of range: {}", key, shown(value)));
    return float(v);
}

int
parse_whole_number(const std::string& key, const json& value)
{
    double v = parse_number(key, value);
    if (v != std::floor(v) || std::fabs(v) > 1e6)
        fail(format("\"{}\" must be a whole number, not {}", key,
                    shown(value)));
    return int(v);
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
        for (const FilterOptionName& o : filter_option_names())
            recipe.erase(o.name);
        recipe["preset"] = preset->second;
    }
    for (const auto& [key, text] : overrides) {
        const FilterOptionName* option = find_filter_option(key);
        double real                    = 0.0;
        int whole                      = 0;
        if (key == "preset") {
            continue;
        } else if (find_input(key) || find_colour(key)) {
            recipe[key] = text;
        } else if (find_flag(key)) {
            if (text == "1" || text == "true")
                recipe[key] = true;
            else if (text == "0" || text == "false")
                recipe[key] = false;
            else
                fail(format("argument {}={} must be 1, 0, true or false", key,
                            text));
        } else if (key == "threads" || key == "tile"
                   || (option && option->whole)) {
            if (!parse_whole(text, whole))
                fail(format("argument {}={} must be a whole number", key,
                            text));
            recipe[key] = whole;
        } else if (option) {
            if (!parse_real(text, real))
                fail(format("argument {}={} must be a number", key, text));
            recipe[key] = real;
        } else if (is_text_key(key)) {
            recipe[key] = text;
        } else if (key == "halves" || key == "layers" || key == kVersionKey) {
            fail(format("argument '{}' cannot be given after the '?'; edit "
                        "the recipe",
                        key));
        } else {
            fail(format("unknown argument '{}' after the '?' (known: {})", key,
                        known_keys(true)));
        }
    }
}


Job
parse(const std::string& text, const std::string& folder,
      const std::map<std::string, std::string>& overrides)
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
        fail("not valid JSON: " + why);
    }
    if (!recipe.is_object())
        fail("not a zdenoise recipe: a recipe is a JSON object {...}");
    if (!recipe.contains(kVersionKey))
        fail(format("not a zdenoise recipe: it has no \"{}\": {} line",
                    kVersionKey, kRecipeFormatVersion));
    const json& version = recipe.at(kVersionKey);
    if (!version.is_number_integer() || version.get<int>() < 1)
        fail(format("\"{}\" must be {}, not {}", kVersionKey,
                    kRecipeFormatVersion, shown(version)));
    if (version.get<int>() > kRecipeFormatVersion)
        fail(format("written for a newer zdenoise (format {}; this one reads "
                    "format {})",
                    version.get<int>(), kRecipeFormatVersion));
    apply_overrides(recipe, overrides);

    Job job;
    // The preset is the base the other filter options modify, as on the
    // command line.
    if (recipe.contains("preset")) {
        const json& preset = recipe.at("preset");
        if (!preset.is_string())
            fail(format("\"preset\" must be a string, not {}", shown(preset)));
        if (!apply_preset(preset.get<std::string>(), job.filter))
            fail(format("unknown preset '{}' (known: {})",
                        preset.get<std::string>(), preset_names()));
    }
    for (const auto& item : recipe.items()) {
        const std::string& key = item.key();
        const json& value      = item.value();
        if (key == kVersionKey || key == "preset") {
            continue;
        } else if (const InputKey* input = find_input(key)) {
            job.*(input->arg) = parse_input(key, value, folder);
        } else if (key == "halves") {
            if (!value.is_array() || value.size() != 2)
                fail(format("\"halves\" must be a list of two inputs, not {}",
                            shown(value)));
            job.half_a = parse_input("halves", value[0], folder);
            job.half_b = parse_input("halves", value[1], folder);
        } else if (const FlagKey* flag = find_flag(key)) {
            if (!value.is_boolean())
                fail(format("\"{}\" must be true or false, not {}", key,
                            shown(value)));
            job.*(flag->flag) = value.get<bool>();
        } else if (const ColourKey* colour = find_colour(key)) {
            if (!value.is_string() || value.get<std::string>().empty())
                fail(format("\"{}\" must be a name in a string, not {}", key,
                            shown(value)));
            std::string text = value.get<std::string>();
            if (colour->is_path && !folder.empty()
                && !Filesystem::path_is_absolute(text))
                text = folder + "/" + text;
            job.colour.*(colour->value) = text;
        } else if (key == "layers") {
            if (!value.is_array())
                fail(format("\"layers\" must be a list of "
                            "\"NAME=RADIANCE:ALBEDO[:divided][:reflected]\", not {}",
                            shown(value)));
            for (const json& layer : value) {
                job.layers.emplace_back();
                if (!layer.is_string()
                    || !parse_layer(layer.get<std::string>(),
                                    job.layers.back()))
                    fail(format("\"layers\": each must be "
                                "\"NAME=RADIANCE:ALBEDO[:divided][:reflected]\", not {}",
                                shown(layer)));
            }
        } else if (is_text_key(key)) {
            if (!value.is_string())
                fail(format("\"{}\" must be a string, not {}", key,
                            shown(value)));
            const std::string text = value.get<std::string>();
            if (key == "residual")
                job.residual = text;
            else if (key == "mode" && !parse_mode(text, job.mode))
                fail(format("\"mode\" must be \"beauty\" or \"layers\", not "
                            "{}",
                            shown(value)));
            else if (key == "data-type"
                     && !parse_data_type(text, job.data_type))
                fail(format("\"data-type\" must be \"half\" or \"float\", not "
                            "{}",
                            shown(value)));
        } else if (key == "threads") {
            job.threads = parse_whole_number(key, value);
            if (job.threads < 0)
                fail(format("\"threads\" must be 0 (automatic) or more, not "
                            "{}",
                            job.threads));
        } else if (key == "tile") {
            job.tile_rows = parse_whole_number(key, value);
            if (job.tile_rows < 0)
                fail(format("\"tile\" must be 0 (automatic) or a number of "
                            "rows, not {}",
                            job.tile_rows));
        } else if (const FilterOptionName* option = find_filter_option(key)) {
            if (option->whole)
                job.filter.*(option->whole) = parse_whole_number(key, value);
            else
                job.filter.*(option->real) = parse_float(key, value);
        } else {
            fail(format("unknown key \"{}\" (known: {})", key,
                        known_keys(false)));
        }
    }
    if (!job.in.given)
        fail("no noisy input: the recipe needs \"in\"");
    return job;
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
        fail(format("the input '{}' is itself a recipe: a recipe's inputs "
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
             const std::map<std::string, std::string>& overrides, Job& job,
             std::string& error)
{
    try {
        job = parse(text, folder, overrides);
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
    return parse_recipe(text, path, Filesystem::parent_path(path), overrides,
                        job, error);
}


std::string
recipe_text(const Job& job, const std::string& preset,
            const std::string& folder)
{
    nlohmann::ordered_json recipe;
    recipe[kVersionKey] = kRecipeFormatVersion;
    for (const InputKey& k : kInputs)
        if ((job.*(k.arg)).given)
            recipe[k.key] = input_json(job.*(k.arg), folder);
    if (job.half_a.given)
        recipe["halves"] = nlohmann::ordered_json::array(
            { input_json(job.half_a, folder), input_json(job.half_b, folder) });
    for (const FlagKey& k : kFlags)
        if (job.*(k.flag))
            recipe[k.key] = true;
    for (const ColourKey& k : kColourKeys) {
        const std::string& text = job.colour.*(k.value);
        if (!text.empty())
            recipe[k.key] = k.is_path ? relative_path(text, folder) : text;
    }
    if (job.mode != Mode::Auto)
        recipe["mode"] = mode_name(job.mode);
    if (!job.layers.empty()) {
        recipe["layers"] = nlohmann::ordered_json::array();
        for (const LayerArg& layer : job.layers)
            recipe["layers"].push_back(layer_text(layer));
    }
    if (!job.residual.empty())
        recipe["residual"] = job.residual;
    if (job.data_type != OIIO::TypeUnknown)
        recipe["data-type"] = job.data_type.c_str();
    recipe["preset"] = preset;
    for (const FilterOptionName& o : filter_option_names()) {
        if (o.whole) {
            recipe[o.name] = job.filter.*(o.whole);
        } else {
            // The shortest decimal that reads back as the same float
            // ("0.02", not 0.019999999552965164).
            recipe[o.name] = std::stod(format("{}", job.filter.*(o.real)));
        }
    }
    recipe["threads"] = job.threads;
    // Only when given: a recipe without it stays readable by a plugin that
    // predates strips.
    if (job.tile_rows > 0)
        recipe["tile"] = job.tile_rows;
    return recipe.dump(2) + "\n";
}


bool
write_recipe(const Job& job, const std::string& preset,
             const std::string& path, std::string& error)
{
    std::string text;
    try {
        text = recipe_text(job, preset, Filesystem::parent_path(path));
    } catch (const Failure& f) {
        error = format("cannot write recipe '{}': {}", path, f.message);
        return false;
    } catch (const std::exception& e) {
        error = format("cannot write recipe '{}': {}", path, e.what());
        return false;
    }
    return write_text_atomically(path, text, error);
}

}  // namespace job
}  // namespace zdenoise
