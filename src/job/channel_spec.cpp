// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "channel_spec.h"

#include <algorithm>

#include <OpenImageIO/strutil.h>

namespace zdenoise {
namespace job {

using OIIO::Strutil::fmt::format;

namespace {

/// What each role takes, in one row: its name in messages, the component
/// names tried (in order of preference; each entry one complete naming,
/// e.g. R,G,B or X,Y,Z), and how many channels an explicit list may give.
struct RoleFacts {
    Role role;
    const char* name;
    std::vector<std::vector<std::string>> components;
    std::vector<size_t> counts;  ///< the channel counts allowed
    bool pairs;                  ///< also any even number (id, coverage)
    const char* counts_text;     ///< the counts, for messages
};

const std::vector<RoleFacts>&
role_table()
{
    static const std::vector<RoleFacts> table = {
        { Role::Radiance, "radiance", { { "R", "G", "B" }, { "r", "g", "b" } },
          { 3, 4 }, false, "3 (R,G,B) or 4 (R,G,B,A)" },
        { Role::Albedo, "albedo", { { "R", "G", "B" }, { "r", "g", "b" } },
          { 3 }, false, "3" },
        { Role::Normal, "normal",
          { { "X", "Y", "Z" }, { "x", "y", "z" }, { "R", "G", "B" } }, { 3 },
          false, "3" },
        { Role::Depth, "depth", { { "Z" }, { "z" }, { "V" }, { "R" }, { "Y" } },
          { 1 }, false, "1" },
        { Role::ObjectId, "object id",
          { { "X" }, { "x" }, { "R" }, { "V" }, { "Y" } }, { 1 }, true,
          "1, or (id, coverage) pairs" },
        { Role::Variance, "variance",
          { { "R", "G", "B" }, { "r", "g", "b" }, { "V" }, { "Y" } }, { 1, 3 },
          false, "1 or 3" },
        { Role::LayerRadiance, "layer radiance",
          { { "R", "G", "B" }, { "r", "g", "b" } }, { 3 }, false, "3" },
        { Role::Motion, "motion vectors",
          { { "X", "Y", "Z", "W" }, { "x", "y", "z", "w" }, { "X", "Y" },
            { "x", "y" }, { "R", "G" } },
          { 2, 4 }, false, "2 or 4" },
    };
    return table;
}

const RoleFacts&
facts(Role role)
{
    for (const RoleFacts& f : role_table())
        if (f.role == role)
            return f;
    return role_table().front();  // not reached: every role has a row
}

/// The index of the channel called `want`, or the unique channel ending in
/// "." + want; -1 if none, -2 if ambiguous.
int
find_channel(const std::vector<std::string>& names, const std::string& want)
{
    int found = -1;
    for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == want)
            return int(i);
    for (size_t i = 0; i < names.size(); ++i)
        if (OIIO::Strutil::ends_with(names[i], "." + want)) {
            if (found >= 0)
                return -2;
            found = int(i);
        }
    return found;
}

bool
count_fits(Role role, size_t n)
{
    const RoleFacts& f = facts(role);
    return std::find(f.counts.begin(), f.counts.end(), n) != f.counts.end()
           || (f.pairs && n >= 2 && n % 2 == 0);
}

/// Try one naming of the role's components, with an optional layer prefix.
bool
try_components(const std::vector<std::string>& names, const std::string& layer,
               const std::vector<std::string>& comps, std::vector<int>& idx)
{
    idx.clear();
    for (const std::string& c : comps) {
        int i = find_channel(names, layer.empty() ? c : layer + "." + c);
        if (i < 0)
            return false;
        idx.push_back(i);
    }
    return true;
}

}  // namespace


const char*
role_name(Role role)
{
    return facts(role).name;
}


bool
select_channels(const std::vector<std::string>& names, const std::string& selection,
                Role role, std::vector<int>& indices, std::string& error)
{
    indices.clear();
    std::vector<std::string> parts = OIIO::Strutil::splits(selection, ",");
    for (std::string& p : parts)
        p = OIIO::Strutil::strip(p);

    if (parts.size() > 1) {
        // Explicit channel names.
        for (const std::string& p : parts) {
            int i = find_channel(names, p);
            if (i == -2) {
                error = format("channel '{}' is ambiguous", p);
                return false;
            }
            if (i < 0) {
                error = format("no channel '{}'", p);
                return false;
            }
            indices.push_back(i);
        }
        if (!count_fits(role, indices.size())) {
            error = format("{} channels given for the {}; it needs {}",
                           indices.size(), role_name(role), facts(role).counts_text);
            return false;
        }
        return true;
    }

    // A layer name, or the role's plain names when empty. A single channel
    // name is accepted for one-channel roles.
    const std::string layer = parts.empty() ? std::string() : parts[0];
    for (const auto& comps : facts(role).components) {
        if (try_components(names, layer, comps, indices)) {
            if (role == Role::Radiance) {
                int a = find_channel(names, layer.empty() ? "A" : layer + ".A");
                if (a >= 0)
                    indices.push_back(a);
            }
            return true;
        }
    }
    if (!layer.empty() && (role == Role::Depth || role == Role::ObjectId
                           || role == Role::Variance)) {
        int i = find_channel(names, layer);
        if (i >= 0) {
            indices = { i };
            return true;
        }
    }
    std::string wanted;
    const auto namings = facts(role).components;
    for (const std::string& c : namings.front())
        wanted += (wanted.empty() ? "" : ",")
                  + (layer.empty() ? c : layer + "." + c);
    error = layer.empty()
                ? format("no {} channels {} (choose them with :ch=)",
                         role_name(role), wanted)
                : format("no channels {} for the {} layer '{}'", wanted,
                         role_name(role), layer);
    return false;
}


bool
cycles_prefix(const std::vector<std::string>& names, std::string& prefix)
{
    // The first layer with a Combined pass and a Denoising Albedo, else the
    // first with a Combined pass. Blender writes the compositor's output as a
    // layer of its own ("Composite.Combined", no other pass), which EXR's
    // sorted channel list puts before "ViewLayer.": it is not the render.
    bool found = false;
    for (const std::string& n : names) {
        std::string p;
        if (n == "Combined.R")
            p.clear();
        else if (OIIO::Strutil::ends_with(n, ".Combined.R"))
            p = n.substr(0, n.size() - std::string("Combined.R").size());
        else
            continue;
        if (std::find(names.begin(), names.end(), p + "Denoising Albedo.R")
            != names.end()) {
            prefix = p;
            return true;
        }
        if (!found)
            prefix = p;
        found = true;
    }
    return found;
}

}  // namespace job
}  // namespace zdenoise
