// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "layer_conventions.h"

#include <algorithm>
#include <cctype>
#include <set>

#include <OpenImageIO/strutil.h>

#include "channel_spec.h"

namespace zdenoise {
namespace job {

using OIIO::Strutil::fmt::format;

namespace {

bool
has_channel(const std::vector<std::string>& names, const std::string& name)
{
    return std::find(names.begin(), names.end(), name) != names.end();
}

/// Does the layer have all of the components, in upper or lower case?
bool
has_layer(const std::vector<std::string>& names, const std::string& layer,
          const char* comps)
{
    auto all = [&](bool lower) {
        for (const char* c = comps; *c; ++c) {
            const char comp = char(lower ? std::tolower(*c) : *c);
            if (!has_channel(names, layer + "." + comp))
                return false;
        }
        return true;
    };
    return all(false) || all(true);
}

std::string
lower(std::string s)
{
    for (char& c : s)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

/// The last '.'-separated part of a layer path.
std::string
last_part(const std::string& layer)
{
    const size_t dot = layer.rfind('.');
    return dot == std::string::npos ? layer : layer.substr(dot + 1);
}


/// Is an AOV layer (its last name part) light through a glossy or
/// specular bounce: Arnold's specular, transmission and coat lobes, and the
/// specular depth layers with at least one specular event?
bool
is_reflected_lobe(const std::string& name)
{
    static const char* const kReflected[] = { "specular", "transmission",
                                              "coat",     "spec1",
                                              "spec2",    "spec3",
                                              "spec4",    "spec5" };
    const std::string l = lower(name);
    for (const char* r : kReflected)
        if (l == r)
            return true;
    return false;
}


Convention
cycles_convention(const std::vector<std::string>& names,
                  const std::string& prefix)
{
    Convention c;
    c.name   = format("Blender Cycles multilayer EXR (layer '{}')", prefix);
    c.beauty = prefix + "Combined";
    auto pass = [&](const char* name, const char* comps) {
        return has_layer(names, prefix + name, comps) ? prefix + name
                                                      : std::string();
    };
    c.albedo = pass("Denoising Albedo", "RGB");
    c.normal = pass("Denoising Normal", "XYZ");
    c.depth  = pass("Denoising Depth", "Z");
    c.motion = pass("Vector", "XYZW");
    // The Cryptomatte ranks of this layer, not another view layer's.
    std::vector<std::string> own;
    for (const std::string& n : names)
        if (OIIO::Strutil::starts_with(n, prefix))
            own.push_back(n);
    c.id = cryptomatte_object_selection(own);
    if (c.id.empty())
        c.id = pass("IndexOB", "X");
    // Cycles writes each lobe's lighting divided by its colour:
    // Combined = DiffCol*(DiffDir+DiffInd) + GlossCol*(...) + TransCol*(...)
    //            + Emit + Env.
    for (const char* lobe : { "Diff", "Gloss", "Trans" }) {
        const std::string colour = pass((std::string(lobe) + "Col").c_str(),
                                        "RGB");
        std::string lighting;
        for (const char* part : { "Dir", "Ind" }) {
            const std::string p = pass((lobe + std::string(part)).c_str(),
                                       "RGB");
            if (!p.empty())
                lighting += (lighting.empty() ? "" : "+") + p;
        }
        // Gloss and Trans are light through a glossy bounce.
        if (!colour.empty() && !lighting.empty())
            c.layers.push_back({ prefix + lobe, lighting, colour, true,
                                 std::string(lobe) != "Diff", lobe });
    }
    // Light by path: the diffuse direct light (a sun's or a small lamp's
    // hard and thin shadows) apart; everything else (the indirect light,
    // the glossy and transmitted light) stays in the residual layer over
    // Denoising Albedo, filtered as beauty mode filters the beauty, so that
    // where the direct light is routed back the result is beauty mode's.
    // DiffInd as a layer of its own over DiffCol was measured and dropped
    // (bench/path_mode.md): worse at 4 spp on nine scenes of ten, a third
    // dearer.
    const std::string diff_dir = pass("DiffDir", "RGB");
    const std::string diff_col = pass("DiffCol", "RGB");
    if (!diff_dir.empty() && !diff_col.empty() && !c.albedo.empty())
        c.direct_layers.push_back({ prefix + "DiffDir", diff_dir, diff_col,
                                    true, false, "Diff", true });
    c.residual_albedo     = c.albedo;
    c.residual_layer      = prefix + "Residual";
    c.residual_unfiltered = pass("Env", "RGB");
    return c;
}


/// The Arnold-style names of the albedo and the guides.
void
aov_passes(const std::vector<std::string>& names, Convention& c)
{
    for (const char* albedo : { "albedo", "denoise_albedo" })
        if (c.albedo.empty() && has_layer(names, albedo, "RGB"))
            c.albedo = albedo;
    for (const char* normal : { "N", "normal" })
        if (c.normal.empty()
            && (has_layer(names, normal, "XYZ")
                || has_layer(names, normal, "RGB")))
            c.normal = normal;
    if (has_channel(names, "Z"))
        c.depth = "Z";
    for (const char* comps : { "XY", "RG" })
        if (c.motion.empty() && has_layer(names, "motionvector", comps))
            c.motion = "motionvector";
    c.id = cryptomatte_object_selection(names);
}


/// AOVs X with an X_albedo (Arnold, and our specular depth layers).
Convention
aov_convention(const std::vector<std::string>& names)
{
    Convention c;
    for (const std::string& layer : layer_paths(names)) {
        if (!OIIO::Strutil::ends_with(layer, "_albedo")
            || !has_layer(names, layer, "RGB"))
            continue;
        const std::string x = layer.substr(0, layer.size() - 7);
        if (x.empty())
            continue;
        const bool reflected = is_reflected_lobe(last_part(x));
        if (has_layer(names, x, "RGB"))
            c.layers.push_back({ x, x, layer, false, reflected, x });
        else if (has_layer(names, x + "_direct", "RGB")
                 && has_layer(names, x + "_indirect", "RGB"))
            c.layers.push_back({ x, x + "_direct+" + x + "_indirect", layer,
                                 false, reflected, x });
    }
    if (c.layers.empty())
        return c;
    const bool specular_depth = c.layers.front().name == "spec0";
    c.name = specular_depth ? "specular depth layers (spec0..spec5)"
                            : "AOVs with *_albedo (Arnold style)";
    if (has_layer(names, "residual", "RGB"))
        c.residual = "residual";
    aov_passes(names, c);
    // Light by path: the diffuse direct light apart, as radiance over its
    // albedo (Arnold's AOVs are not divided); the rest over the albedo.
    if (has_layer(names, "diffuse_direct", "RGB")
        && has_layer(names, "diffuse_albedo", "RGB") && !c.albedo.empty())
        c.direct_layers.push_back({ "diffuse_direct", "diffuse_direct",
                                    "diffuse_albedo", false, false, "diffuse",
                                    true });
    c.residual_layer = "Residual";  // its name when path mode filters it
    return c;
}

}  // namespace


/// The layer part (all but the last '.'-separated part) of each channel, in
/// order of first appearance.
std::vector<std::string>
layer_paths(const std::vector<std::string>& names)
{
    std::vector<std::string> layers;
    std::set<std::string> seen;
    for (const std::string& n : names) {
        const size_t dot = n.rfind('.');
        if (dot == std::string::npos || dot == 0)
            continue;
        std::string layer = n.substr(0, dot);
        if (seen.insert(layer).second)
            layers.push_back(layer);
    }
    return layers;
}


bool
detect_aux(const std::vector<std::string>& names, AuxConvention& aux,
           std::string& error)
{
    aux = {};
    std::string prefix;
    Convention c;
    if (cycles_prefix(names, prefix)) {
        c = cycles_convention(names, prefix);
        for (const char* lobe : { "Diff", "Gloss", "Trans" }) {
            const std::string colour = prefix + lobe + "Col";
            if (has_layer(names, colour, "RGB"))
                aux.lobe_colours.push_back({ lobe, colour });
        }
    } else {
        aov_passes(names, c);
        c.name = "AOVs (albedo, N, Z, crypto_object)";
        for (const std::string& layer : layer_paths(names))
            if (OIIO::Strutil::ends_with(layer, "_albedo") && layer.size() > 7
                && has_layer(names, layer, "RGB"))
                aux.lobe_colours.push_back(
                    { layer.substr(0, layer.size() - 7), layer });
        if (c.albedo.empty() && has_channel(names, "R")
            && has_channel(names, "G") && has_channel(names, "B")) {
            c.name   = "plain R,G,B image (an albedo)";
            c.albedo = "R,G,B";
        }
    }
    if (c.albedo.empty()) {
        error = format("no albedo: neither a Cycles 'Denoising Albedo', an "
                       "'albedo' layer nor plain R,G,B; its layers are {}",
                       layers_text(names));
        return false;
    }
    aux.name   = c.name;
    aux.albedo = c.albedo;
    aux.normal = c.normal;
    aux.depth  = c.depth;
    aux.id     = c.id;
    return true;
}


std::string
layers_text(const std::vector<std::string>& names)
{
    std::vector<std::string> parts = layer_paths(names);
    for (const std::string& n : names) {
        const size_t dot = n.rfind('.');
        if (dot == std::string::npos || dot == 0)
            parts.push_back(n);
    }
    std::string text;
    for (const std::string& p : parts)
        text += (text.empty() ? "" : ", ") + p;
    return text.empty() ? "none" : text;
}



std::string
cryptomatte_object_selection(const std::vector<std::string>& names)
{
    // The layer whose last part, lowercased and without '_', is
    // "cryptoobject00" starts the ranks; its siblings 01, 02, ... follow.
    for (const std::string& layer : layer_paths(names)) {
        std::string key = lower(last_part(layer));
        key.erase(std::remove(key.begin(), key.end(), '_'), key.end());
        if (key != "cryptoobject00")
            continue;
        const std::string base = layer.substr(0, layer.size() - 2);
        std::string selection;
        for (int rank = 0; rank < 100; ++rank) {
            const std::string l = format("{}{:02d}", base, rank);
            if (!has_layer(names, l, "RGBA"))
                break;
            // Upper case only where all four are (a stray ".R" beside
            // r, g, b, a must not switch the lower-case ones off).
            bool upper = true;
            for (const char* c = "RGBA"; *c; ++c)
                upper = upper && has_channel(names, l + "." + *c);
            for (const char* c = "RGBA"; *c; ++c)
                selection += (selection.empty() ? "" : ",") + l + "."
                             + char(upper ? *c : std::tolower(*c));
        }
        return selection;
    }
    return {};
}


bool
is_cryptomatte_channel(const std::string& channel,
                       const std::vector<std::string>& layer_names)
{
    for (const std::string& l : layer_names)
        if (!l.empty() && OIIO::Strutil::starts_with(channel, l))
            return true;
    const size_t dot = channel.rfind('.');
    return dot != std::string::npos
           && OIIO::Strutil::starts_with(lower(last_part(channel.substr(0, dot))),
                                         "crypto");
}


Convention
detect_convention(const std::vector<std::string>& names)
{
    std::string prefix;
    if (cycles_prefix(names, prefix))
        return cycles_convention(names, prefix);
    return aov_convention(names);
}

}  // namespace job
}  // namespace zdenoise
