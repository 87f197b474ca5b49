// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Fuzzing the channel selection (`:ch=` and the Cycles defaults) and the
// layer conventions (docs/LAYERS.md) with any file's channel names, and
// --layer's parser with any argument: they must never crash, what the
// selection accepts must be a usable selection, and every selection a
// convention proposes must resolve for its role.
//
// Input: byte 0 chooses the role; the rest is "SELECTION\nNAME\nNAME...".
// A NUL also separates lines: EXR channel names and command-line arguments
// are NUL-terminated, so neither can hold one (and OIIO's string matching
// stops at one).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

#include <OpenImageIO/strutil.h>

#include "job/channel_spec.h"
#include "job/job.h"
#include "job/layer_conventions.h"
#include "job/options.h"

using namespace zdenoise::job;

namespace {

[[noreturn]] void
violated(const char* what)
{
    std::fprintf(stderr, "fuzz_channel_spec: %s\n", what);
    std::abort();
}

bool
count_ok(Role role, size_t n)
{
    switch (role) {
    case Role::Radiance: return n == 3 || n == 4;
    case Role::Albedo:
    case Role::LayerRadiance:
    case Role::Normal: return n == 3;
    case Role::Depth: return n == 1;
    case Role::Variance: return n == 1 || n == 3;
    case Role::ObjectId: return n == 1 || (n >= 2 && n % 2 == 0);
    case Role::Motion: return n == 2 || n == 4;
    }
    return false;
}

/// Does `selection` ('+' joins several) resolve in `names` for `role`?
bool
resolves(const std::vector<std::string>& names, const std::string& selection,
         Role role, bool sum)
{
    std::vector<int> indices;
    std::string error;
    for (const std::string& part :
         sum ? OIIO::Strutil::splits(selection, "+")
             : std::vector<std::string> { selection })
        if (!select_channels(names, part, role, indices, error))
            return false;
    return true;
}

/// Selections are comma lists and '+' sums of channel and layer names: a
/// name holding ',' or '+' cannot be named in one, nor one with spaces at
/// its ends (arguments are trimmed).
bool
nameable(const std::vector<std::string>& names)
{
    for (const std::string& n : names)
        if (n.find_first_of(",+") != std::string::npos
            || OIIO::Strutil::strip(n) != n)
            return false;
    return true;
}

}  // namespace


extern "C" int
LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 1)
        return 0;
    const Role role = Role(data[0] % 8);
    std::vector<std::string> lines(1);
    for (size_t i = 1; i < size; ++i) {
        if (data[i] == '\n' || data[i] == '\0')
            lines.emplace_back();
        else
            lines.back() += char(data[i]);
    }
    const std::string selection = lines[0];
    const std::vector<std::string> names(lines.begin() + 1, lines.end());

    std::vector<int> indices;
    std::string error;
    if (select_channels(names, selection, role, indices, error)) {
        if (!count_ok(role, indices.size()))
            violated("accepted a channel count the role cannot use");
        std::set<int> distinct;
        for (int i : indices) {
            if (i < 0 || size_t(i) >= names.size())
                violated("selected a channel index out of range");
            distinct.insert(i);
        }
        // The same channel twice is the user's choice with explicit names,
        // never the result of a layer or default lookup.
        if (selection.find(',') == std::string::npos
            && distinct.size() != indices.size())
            violated("a layer lookup picked one channel twice");
    } else if (error.empty()) {
        violated("refused without a message");
    } else if (error.find('\n') != std::string::npos) {
        violated("an error message of more than one line");
    }

    std::string prefix;
    if (cycles_prefix(names, prefix)) {
        bool found = false;
        for (const std::string& n : names)
            found = found || n == prefix + "Combined.R";
        if (!found)
            violated("a Cycles prefix without its Combined.R channel");
    }

    const Convention conv = detect_convention(names);
    if (nameable(names)) {
        struct {
            const std::string& selection;
            Role role;
        } proposed[] = { { conv.albedo, Role::Albedo },
                         { conv.normal, Role::Normal },
                         { conv.depth, Role::Depth },
                         { conv.id, Role::ObjectId } };
        for (const auto& p : proposed)
            if (!p.selection.empty()
                && !resolves(names, p.selection, p.role, false))
                violated("a convention proposed a guide that does not "
                         "resolve");
        for (const LayerArg& layer : conv.layers)
            if (!resolves(names, layer.radiance, Role::LayerRadiance, true)
                || !resolves(names, layer.albedo, Role::LayerRadiance, true))
                violated("a convention proposed a layer that does not resolve");
        for (const std::string* sum :
             { &conv.residual, &conv.residual_albedo })
            if (!sum->empty()
                && !resolves(names, *sum, Role::LayerRadiance, true))
                violated("a convention proposed a residual that does not "
                         "resolve");
    }

    // --layer NAME=RADIANCE:ALBEDO[:divided] reads back as it is written.
    LayerArg layer;
    if (parse_layer(selection, layer)) {
        LayerArg again;
        if (!parse_layer(layer_text(layer), again) || again.name != layer.name
            || again.radiance != layer.radiance || again.albedo != layer.albedo
            || again.divided != layer.divided)
            violated("--layer's text does not read back as the same layer");
    }
    return 0;
}
