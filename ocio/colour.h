// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Colour management of a denoise job, over OpenColorIO 2.1.
//
// Demodulation divides radiance by albedo channel by channel, and the
// filter fits each channel separately: neither commutes with a change of
// primaries, and an encoded (sRGB) signal is not a sum of light at all. So
// the noisy radiance and the albedo are converted into one scene-linear
// working space before filtering (by default the config's scene_linear
// role; the renderer's rendering space is the right choice), and the result
// into the output space after. Only the radiance and albedo RGB are
// converted: guides and every other channel are data.

#pragma once

#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

namespace zdenoise {
namespace colour {

/// What the user asked for; empty means "the default" for each.
struct ColourOptions {
    std::string config;         ///< --colorconfig; else $OCIO, else bundled
    std::string input_space;    ///< --iscolorspace; else guessed from file
    std::string albedo_space;   ///< --albedo-colorspace; else guessed
    std::string output_space;   ///< --ocolorspace; else the input's
    std::string working_space;  ///< --working-colorspace; else scene_linear

    bool any_given() const
    {
        return !(config.empty() && input_space.empty() && albedo_space.empty()
                 && output_space.empty() && working_space.empty());
    }
};

/// The bundled config: share/zdenoise/ocio/config.ocio in a parent folder
/// of the program or plugin running this code, else in the installed data
/// folder; empty when neither exists.
std::string
bundled_config_path();

/// A loaded OCIO config. Never throws.
class ColourConfig {
public:
    ColourConfig();
    ~ColourConfig();

    /// Load `explicit_path` if given, else $OCIO, else the bundled config.
    /// `source` says which (for -v).
    bool load(const std::string& explicit_path, std::string& error);
    const std::string& source() const { return m_source; }

    /// The canonical name of a colour space, role or alias; on failure an
    /// error naming `option` and listing the config's colour spaces.
    bool resolve(const std::string& name, const std::string& option,
                 std::string& canonical, std::string& error) const;
    /// The canonical name of the colour space of `role`; empty if none.
    std::string role(const std::string& role) const;

    /// The colour space of an image file's RGB when the user did not say,
    /// and why (one line). See guess_rule in colour.cpp.
    std::string guess(const OIIO::ImageBuf& file, std::string& why) const;

    /// Convert channels 0-2 of the float image `image` in place.
    bool convert_rgb(OIIO::ImageBuf& image, const std::string& from,
                     const std::string& to, std::string& error) const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
    std::string m_source;
};


/// The resolved colour spaces of one job.
struct JobSpaces {
    std::string input, albedo, working, output;
};

/// Resolve the spaces of a job from the options and the input files
/// (`albedo_file` may be `noisy_file`); appends what was assumed and why to
/// `log`.
bool
resolve_job_spaces(const ColourConfig& config, const ColourOptions& options,
                   const OIIO::ImageBuf& noisy_file,
                   const OIIO::ImageBuf& albedo_file, bool albedo_is_input,
                   JobSpaces& spaces, std::vector<std::string>& log,
                   std::string& error);

/// Record `space` as the colour space of `spec`: oiio:ColorSpace and
/// zdenoise.colorspace (which OpenEXR files keep), and the
/// OpenEXR `chromaticities` when the primaries are known (OIIO's EXR reader
/// ignores oiio:ColorSpace) when converted from `input_space`; stale
/// chromaticities are removed.
void
tag_colour_space(OIIO::ImageSpec& spec, const std::string& space,
                 const std::string& input_space);

}  // namespace colour
}  // namespace zdenoise
