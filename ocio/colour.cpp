// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "colour.h"

#include <cmath>
#include <cstdlib>

#include <climits>
#include <dlfcn.h>

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

namespace OCIO = OCIO_NAMESPACE;
using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace zdenoise {
namespace colour {

namespace {

/// Scene-linear spaces whose primaries an OpenEXR file can state in its
/// `chromaticities` attribute (red, green, blue, white as x,y), with the
/// names configs commonly give them (the bundled, the ACES and CG configs).
struct KnownPrimaries {
    const char* label;
    float xy[8];
    std::vector<const char*> names;
};

const std::vector<KnownPrimaries>&
known_primaries()
{
    static const std::vector<KnownPrimaries> known = {
        { "ACEScg (AP1)",
          { 0.713f, 0.293f, 0.165f, 0.830f, 0.128f, 0.044f, 0.32168f,
            0.33767f },
          { "ACEScg", "ACES - ACEScg", "lin_ap1" } },
        { "ACES2065-1 (AP0)",
          { 0.7347f, 0.2653f, 0.0f, 1.0f, 0.0001f, -0.0770f, 0.32168f,
            0.33767f },
          { "ACES2065-1", "ACES - ACES2065-1", "aces_interchange",
            "lin_ap0" } },
        { "Rec.709",
          { 0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f },
          { "Linear Rec.709 (sRGB)", "lin_rec709", "Utility - Linear - sRGB",
            "lin_srgb" } },
    };
    return known;
}

const TypeDesc kChromaticitiesType(TypeDesc::FLOAT, 8);

}  // namespace


struct ColourConfig::Impl {
    OCIO::ConstConfigRcPtr config;

    std::string canonical(const std::string& name) const
    {
        const char* c = config->getCanonicalName(name.c_str());
        return c ? std::string(c) : std::string();
    }
    /// The first of `names` the config knows, canonical; empty if none.
    std::string first_known(const std::vector<const char*>& names) const
    {
        for (const char* n : names) {
            std::string c = canonical(n);
            if (!c.empty())
                return c;
        }
        return {};
    }
};


std::string
bundled_config_path()
{
    // The folder of the program or plugin this code is linked into, and its
    // parents: bin/ for the command, lib[/<arch>]/zdenoise/plugins/ for the
    // OIIO plugin, in the build tree and installed alike.
    std::vector<std::string> candidates;
    Dl_info info;
    if (dladdr(reinterpret_cast<void*>(&bundled_config_path), &info)
        && info.dli_fname) {
        char resolved[PATH_MAX];
        std::string folder = Filesystem::parent_path(
            realpath(info.dli_fname, resolved) ? resolved : info.dli_fname);
        for (int up = 0; up < 5 && !folder.empty(); ++up) {
            folder = Filesystem::parent_path(folder);
            candidates.push_back(folder + "/share/zdenoise/ocio/config.ocio");
        }
    }
#ifdef ZDENOISE_INSTALL_DATADIR
    candidates.push_back(std::string(ZDENOISE_INSTALL_DATADIR)
                         + "/zdenoise/ocio/config.ocio");
#endif
    for (const std::string& c : candidates)
        if (Filesystem::is_regular(c))
            return c;
    return {};
}


ColourConfig::ColourConfig()
    : m_impl(new Impl)
{
}

ColourConfig::~ColourConfig() = default;


bool
ColourConfig::load(const std::string& explicit_path, std::string& error)
{
    std::string path = explicit_path;
    if (!path.empty()) {
        m_source = format("--colorconfig '{}'", path);
    } else if (const char* env = std::getenv("OCIO"); env && *env) {
        path     = env;
        m_source = format("$OCIO '{}'", path);
    } else {
        path = bundled_config_path();
        if (path.empty()) {
            error = "no colour config: the bundled share/zdenoise/ocio/"
                    "config.ocio is missing; give --colorconfig FILE or set "
                    "$OCIO";
            return false;
        }
        m_source = format("bundled '{}'", path);
    }
    try {
        m_impl->config = OCIO::Config::CreateFromFile(path.c_str());
        return true;
    } catch (const std::exception& e) {
        error = format("colour config {}: {}", m_source, e.what());
        for (char& c : error)
            if (c == '\n')
                c = ' ';
        return false;
    }
}


bool
ColourConfig::resolve(const std::string& name, const std::string& option,
                      std::string& canonical, std::string& error) const
{
    canonical = m_impl->canonical(name);
    if (!canonical.empty())
        return true;
    std::string known;
    for (int i = 0, n = m_impl->config->getNumColorSpaces(); i < n; ++i)
        known += format("{}'{}'", known.empty() ? "" : ", ",
                        m_impl->config->getColorSpaceNameByIndex(i));
    error = format("{}: unknown colour space '{}' in {} (known: {})", option,
                   name, m_source, known);
    return false;
}


std::string
ColourConfig::role(const std::string& role) const
{
    return m_impl->config->hasRole(role.c_str()) ? m_impl->canonical(role)
                                                  : std::string();
}


// guess_rule: the colour space of a file that does not say reliably.
// OIIO 2.4's OpenEXR reader tags every EXR "Linear", which names no
// primaries; an EXR's `chromaticities` attribute does. Other formats' tags
// (PNG and JPEG: "sRGB") are what their readers found in the file.
std::string
ColourConfig::guess(const ImageBuf& file, std::string& why) const
{
    const ImageSpec& spec   = file.spec();
    const std::string name  = file.name();
    const std::string scene = role("scene_linear");
    if (std::string(file.file_format_name()) == "openexr") {
        float xy[8];
        if (spec.getattribute("chromaticities", kChromaticitiesType, xy)) {
            for (const KnownPrimaries& k : known_primaries()) {
                bool same = true;
                for (int i = 0; i < 8; ++i)
                    same = same && std::fabs(xy[i] - k.xy[i]) < 2e-3f;
                if (!same)
                    continue;
                std::string space = m_impl->first_known(k.names);
                if (!space.empty()) {
                    why = format("'{}' states {} primaries (chromaticities)",
                                 name, k.label);
                    return space;
                }
                why = format("'{}' states {} primaries, which the config "
                             "has no space for: assumed scene_linear",
                             name, k.label);
                return scene;
            }
            why = format("'{}' states primaries zdenoise does not know "
                         "(chromaticities): assumed scene_linear",
                         name);
            return scene;
        }
        why = format("'{}' is an OpenEXR without chromaticities: assumed "
                     "scene_linear",
                     name);
        return scene;
    }
    const std::string tag = spec.get_string_attribute("oiio:ColorSpace");
    if (!tag.empty()) {
        std::string space = m_impl->canonical(tag);
        if (!space.empty()) {
            why = format("'{}' is tagged '{}'", name, tag);
            return space;
        }
    }
    if (file.nativespec().format.is_floating_point()) {
        why = format("'{}' holds floating-point pixels and no known colour "
                     "space tag: assumed scene_linear",
                     name);
        return scene;
    }
    std::string srgb = m_impl->first_known({ "sRGB - Texture", "sRGB",
                                             "srgb_tx" });
    if (srgb.empty())
        srgb = role("color_picking");
    why = format("'{}' holds integer pixels and no known colour space tag: "
                 "assumed sRGB-encoded",
                 name);
    return srgb;
}


bool
ColourConfig::convert_rgb(ImageBuf& image, const std::string& from,
                          const std::string& to, std::string& error) const
{
    if (from == to)
        return true;
    const ROI all = image.roi();
    ROI rgb       = all;
    rgb.chbegin   = 0;
    rgb.chend     = 3;
    std::vector<float> pixels(size_t(rgb.npixels()) * 3);
    if (!image.get_pixels(rgb, TypeFloat, pixels.data())) {
        error = image.geterror();
        return false;
    }
    try {
        OCIO::ConstProcessorRcPtr p
            = m_impl->config->getProcessor(from.c_str(), to.c_str());
        OCIO::PackedImageDesc desc(pixels.data(), rgb.width(),
                                   long(rgb.height()) * rgb.depth(), 3);
        p->getDefaultCPUProcessor()->apply(desc);
    } catch (const std::exception& e) {
        error = format("converting '{}' to '{}': {}", from, to, e.what());
        return false;
    }
    if (!image.set_pixels(rgb, TypeFloat, pixels.data())) {
        error = image.geterror();
        return false;
    }
    return true;
}


bool
resolve_job_spaces(const ColourConfig& config, const ColourOptions& options,
                   const ImageBuf& noisy_file, const ImageBuf& albedo_file,
                   bool albedo_is_input, JobSpaces& spaces,
                   std::vector<std::string>& log, std::string& error)
{
    log.push_back("colour config " + config.source());
    auto pick = [&](const std::string& given, const char* option,
                    const char* what, auto fallback, std::string& space) {
        if (!given.empty()) {
            if (!config.resolve(given, option, space, error))
                return false;
            log.push_back(format("  {} colour space '{}' ({})", what, space,
                                 option));
            return true;
        }
        std::string why;
        space = fallback(why);
        if (space.empty()) {
            error = format("{}: {} names no colour space; give {}", what,
                           config.source(), option);
            return false;
        }
        log.push_back(format("  {} colour space '{}': {}", what, space, why));
        return true;
    };
    if (!pick(options.working_space, "--working-colorspace", "working",
              [&](std::string& why) {
                  why = "the config's scene_linear role";
                  return config.role("scene_linear");
              },
              spaces.working))
        return false;
    if (!pick(options.input_space, "--iscolorspace", "radiance",
              [&](std::string& why) { return config.guess(noisy_file, why); },
              spaces.input))
        return false;
    if (!pick(options.albedo_space, "--albedo-colorspace", "albedo",
              [&](std::string& why) {
                  if (albedo_is_input) {
                      why = "the radiance's (same file)";
                      return spaces.input;
                  }
                  return config.guess(albedo_file, why);
              },
              spaces.albedo))
        return false;
    if (!pick(options.output_space, "--ocolorspace", "output",
              [&](std::string& why) {
                  why = "the radiance's";
                  return spaces.input;
              },
              spaces.output))
        return false;
    return true;
}


void
tag_colour_space(ImageSpec& spec, const std::string& space,
                 const std::string& input_space)
{
    spec.attribute("oiio:ColorSpace", space);
    // OIIO 2.4's OpenEXR writer drops oiio:ColorSpace; this one stays.
    spec.attribute("zdenoise.colorspace", space);
    if (space == input_space)
        return;  // the input's chromaticities, if any, still hold
    for (const KnownPrimaries& k : known_primaries())
        for (const char* n : k.names)
            if (space == n) {
                spec.attribute("chromaticities", kChromaticitiesType, k.xy);
                return;
            }
    spec.erase_attribute("chromaticities");
}

}  // namespace colour
}  // namespace zdenoise
