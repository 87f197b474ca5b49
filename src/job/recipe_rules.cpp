// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// What a recipe may read and cost (recipe_rules.h).

#include "recipe_rules.h"

#include <cstdlib>
#include <filesystem>

#include <OpenImageIO/strutil.h>

#include "options.h"

namespace zdenoise {
namespace job {

using OIIO::Strutil::fmt::format;
namespace Strutil = OIIO::Strutil;
namespace fs      = std::filesystem;

namespace {

/// Set the one-line `error` and return false.
bool
refuse(std::string& error, const std::string& message)
{
    error = control_escaped(message);
    return false;
}

/// `path` made absolute with its symbolic links and `..` resolved as far
/// as it exists (the rest lexically); empty when that fails.
fs::path
resolved(const fs::path& path)
{
    std::error_code ec;
    fs::path absolute = fs::absolute(path, ec);
    if (ec)
        return {};
    fs::path canonical = fs::weakly_canonical(absolute, ec);
    return ec ? fs::path() : canonical;
}


/// Whether `path` is `folder` or lies under it (both resolved).
bool
inside(const fs::path& path, const fs::path& folder)
{
    const fs::path relative = path.lexically_relative(folder);
    return !relative.empty() && *relative.begin() != "..";
}

}  // namespace


std::string
control_escaped(const std::string& text)
{
    std::string line;
    for (unsigned char c : text) {
        if (c < 0x20 || c == 0x7f)
            line += format("\\x{:02x}", unsigned(c));
        else
            line += char(c);
    }
    return line;
}


bool
confine_path(const std::string& key, const std::string& given,
             const std::string& folder, const RecipeRules& rules,
             std::string& path, std::string& error)
{
    if (given.find('\0') != std::string::npos)
        return refuse(error, format("\"{}\" holds a NUL character", key));
    const fs::path home = resolved(folder.empty() ? "." : folder);
    if (home.empty())
        return refuse(error, format("cannot resolve the recipe's folder '{}'", folder));
    const fs::path joined = home / given;  // an absolute `given` replaces it
    const fs::path target = resolved(joined);
    if (target.empty())
        return refuse(error, format("\"{}\": cannot resolve '{}'", key, given));
    bool allowed = inside(target, home);
    for (const std::string& other : rules.folders)
        allowed = allowed || inside(target, other);
    if (!allowed) {
        const char* why = fs::path(given).is_absolute()
                              ? "an absolute path outside"
                          : !inside(joined.lexically_normal(), home)
                              ? "'..' leads out of"
                              : "a symbolic link leads out of";
        return refuse(error, format("\"{}\" is '{}': {} the recipe's folder '{}' (a recipe "
                    "reads files in its folder only, or in the folders {} "
                    "lists)",
                    key, given, why, home.string(), kRecipePathVariable));
    }
    std::error_code ec;
    const fs::file_status status = fs::status(target, ec);
    if (fs::exists(status) && !fs::is_regular_file(status))
        return refuse(error, format("\"{}\" is '{}': not a regular file", key, given));
    path = target.string();
    return true;
}


bool
parse_recipe_rules(const char* path, const char* limits, RecipeRules& rules,
                   std::string& error)
{
    rules = RecipeRules();
    {
        for (const std::string& folder :
             Strutil::splits(path ? path : "", ":")) {
            if (folder.empty())
                continue;
            const fs::path canonical = resolved(folder);
            if (!fs::path(folder).is_absolute() || canonical.empty())
                return refuse(error, format("{}: '{}' is not an absolute folder",
                            kRecipePathVariable, folder));
            // A folder as one spelling: "/studio/" is "/studio" (a trailing
            // separator, kept by weakly_canonical for a folder that does not
            // exist, would make it a different string; found by fuzz_recipe).
            fs::path folder_path = canonical;
            if (!folder_path.has_filename() && folder_path != folder_path.root_path())
                folder_path = folder_path.parent_path();
            rules.folders.push_back(folder_path.string());
        }
        for (const std::string& item :
             Strutil::splits(limits ? limits : "", ",")) {
            const std::string setting(Strutil::strip(item));
            if (setting.empty())
                continue;
            const size_t eq         = setting.find('=');
            const std::string key = Strutil::strip(setting.substr(0, eq));
            const std::string value
                = eq == std::string::npos
                      ? std::string()
                      : std::string(Strutil::strip(setting.substr(eq + 1)));
            int whole      = 0;
            uint64_t size  = 0;
            const bool off = value == "0";
            if ((key == "rmax" || key == "layers") && parse_whole(value, whole)
                && whole >= 0)
                (key == "rmax" ? rules.max_rmax : rules.max_layers) = whole;
            else if (key == "pixels" && (off || parse_size(value, size)))
                rules.max_pixels = off ? 0 : size;
            else
                return refuse(error, format("{}: '{}' must be rmax=N, layers=N or pixels=N "
                            "(pixels may end in K, M or G; 0: no bound), "
                            "joined by ','",
                            kRecipeLimitsVariable, setting));
        }
    }
    return true;
}


bool
recipe_rules_from_environment(RecipeRules& rules, std::string& error)
{
    return parse_recipe_rules(std::getenv(kRecipePathVariable),
                              std::getenv(kRecipeLimitsVariable), rules,
                              error);
}

}  // namespace job
}  // namespace zdenoise
