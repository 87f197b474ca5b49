// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "options.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>

#include <OpenImageIO/strutil.h>

#include <zdenoise/version.h>

namespace zdenoise {
namespace job {

namespace Strutil = OIIO::Strutil;

namespace {

/// A row's member: `c.MEMBER` of the Command `c`.
#define FIELD(member) [](Command& c) -> auto& { return c.member; }

Option
parameter(Option o)
{
    o.parameter      = true;
    o.always_written = true;
    return o;
}

Option
always_written(Option o)
{
    o.always_written = true;
    return o;
}

Option
not_in_file_name(Option o)
{
    o.in_file_name = false;
    return o;
}

Option
shown_as(const char* shown, Option o)
{
    o.shown = shown;
    return o;
}


/// The help, with each option's lines where its flag stands in braces.
const char* kUsage = R"(zdenoise )" ZDENOISE_VERSION_STRING R"( -- denoise Monte Carlo renders (Zhdanov, Ershov & Voloboy 2018)

Usage: zdenoise --in NOISY -o OUTPUT [options]
       zdenoise --in NOISY --write-recipe RECIPE.zdn [options]

Inputs (each FILE may take a channel selection, oiiotool style:
--albedo:ch=R,G,B FILE, or a layer name: --albedo:ch="Denoising Albedo" FILE):
{--in}
{--albedo}
{--aux}
{--normal}
{--depth}
{--id}
{--variance}
{--halves}
{--albedo-samples}
{--no-albedo-prefilter}
{--no-normal}
  A Blender Cycles multilayer EXR (channels <layer>.Combined.R ...) needs no
  other input: Combined, Denoising Albedo, Denoising Normal, Denoising Depth
  and CryptoObject (else IndexOB) are taken from it. So are Arnold-style
  AOVs (X with X_albedo, N, Z, crypto_object) and specular depth layers
  (spec0..spec5 with spec0_albedo.., residual); see docs/LAYERS.md.

Layers (docs/LAYERS.md):
{--mode}
{--layer}
{--residual}
{--aovs}

Output:
{-o}
{-d}
{--no-alpha}
{--no-light-groups}
{--aov}
{--force}
{--write-recipe}
{--diagnostics}
{--diagnostics-png}

Colour (OpenColorIO; docs/COLOUR.md):
{--colorconfig}
{--iscolorspace}
{--albedo-colorspace}
{--ocolorspace}
{--working-colorspace}

Filter parameters (docs/FILTER.md):
{--preset}
{--rmin}
{--rmax}
{--eta}
{--edge-k}
{--tau-min}
{--value-k}
{--value-noise}
{--energy-radius}
{--sigma-good}
{--albedo-eps}
{--depth-tol}
{--normal-cut}
{--normal-power}
{--quadrant-power}
{--radius-growth}
{--stride}
{--stride-edges}
{--outlier-spread}
{--select}
{--core}
{--box-radius}
{--pyramid}

Frame sequences (oiiotool's conventions) and batches:
{--frames}
{--temporal}
{--static-camera}
{--motion}
{--shot-range}
{--skip-existing}
{--fail-fast}
{--report}
{--print-chunks}

General:
{--mem-limit}
{--tile}
{--threads}
{-v}
{--help}
{--version})";

/// The column at which the help's descriptions start.
constexpr size_t kHelpColumn = 23;

/// One option's lines of help: its flag and value, then its description
/// (on the next line when they do not leave room).
std::string
option_help(const Option& o)
{
    std::string left = "  " + std::string(o.shown ? o.shown : o.flag);
    if (!o.shown && *o.arg)
        left += std::string(" ") + o.arg;
    const std::string indent(kHelpColumn, ' ');
    std::string text = left.size() + 2 <= kHelpColumn
                           ? left + std::string(kHelpColumn - left.size(), ' ')
                           : left + "\n" + indent;
    for (char c : std::string(o.help))
        text += c == '\n' ? "\n" + indent : std::string(1, c);
    return text;
}

}  // namespace


const std::vector<Option>&
options()
{
    static const std::vector<Option> table = {
        { Kind::Input, "--in", "in", FIELD(job.in), "FILE",
          "Noisy render (radiance R,G,B and optional A)." },
        { Kind::Input, "--albedo", "albedo", FIELD(job.albedo), "FILE",
          "Noise-free albedo (R,G,B). Required unless --in is a\n"
          "Blender Cycles multilayer EXR." },
        { Kind::Input, "--aux", "aux", FIELD(job.aux), "FILE",
          "Deterministic auxiliary image of the same shot\n"
          "(share/blender/zdenoise_aux.py renders one; docs/AUX.md):\n"
          "its albedo remodulates (in --mode layers its lobe\n"
          "colours too), its normal, depth and object ids replace\n"
          "the --in file's guides. A Cycles multilayer EXR, AOVs\n"
          "(albedo, N, Z) or a plain R,G,B image (an albedo);\n"
          ":ch= names its albedo." },
        { Kind::Input, "--normal", "normal", FIELD(job.normal), "FILE",
          "Normal guide (X,Y,Z)." },
        { Kind::Input, "--depth", "depth", FIELD(job.depth), "FILE",
          "Depth guide (Z)." },
        { Kind::Input, "--id", "id", FIELD(job.id), "FILE",
          "Object id guide (one channel, or id,coverage pairs)." },
        { Kind::Input, "--variance", "variance", FIELD(job.variance), "FILE",
          "Per-pixel variance of the radiance (1 or 3 channels)." },
        not_in_file_name({ Kind::Halves, "--halves", "halves", {}, "A B",
          "Two independent half renders (radiance = (A+B)/2).\n"
          "Their own albedos, when the files have them (Cycles'\n"
          "Denoising Albedo), also measure the albedo's noise." }),
        { Kind::Whole, "--albedo-samples", "albedo-samples", FIELD(job.albedo_samples), "N",
          "Samples per pixel of the render's albedo (--mode layers:\n"
          "of its lobe colours), which is prefiltered where it is\n"
          "noisy (docs/FILTER.md section 12), and with --aux pooled\n"
          "with the aux's (docs/AUX.md). Default: a Cycles file's\n"
          "count." },
        { Kind::Flag, "--no-albedo-prefilter", "no-albedo-prefilter", FIELD(job.no_albedo_prefilter), "",
          "Take the albedo (--mode layers: the lobe colours) as it\n"
          "is (with --aux: pooled, not prefiltered)." },
        shown_as("--no-normal, --no-depth, --no-id", { Kind::Flag, "--no-normal", "no-normal", FIELD(job.no_normal), "",
          "Do not use the guide picked by default." }),
        { Kind::Flag, "--no-depth", "no-depth", FIELD(job.no_depth), "", nullptr },
        { Kind::Flag, "--no-id", "no-id", FIELD(job.no_id), "", nullptr },
        { Kind::Flag, "--aovs", "aovs", FIELD(job.write_layers), "",
          "Also write each denoised layer as NAME.R,G,B." },
        { Kind::Flag, "--no-alpha", "no-alpha", FIELD(job.no_alpha), "",
          "Copy the beauty's alpha as it is. Default: where it is\n"
          "fractional (motion blur, depth of field, transparent\n"
          "film) it is denoised with the render's guides\n"
          "(docs/ALPHA.md)." },
        { Kind::Flag, "--no-light-groups", "no-light-groups", FIELD(job.no_light_groups), "",
          "Copy the light groups (<beauty>_<group>: Cycles'\n"
          "Combined_<group>, Arnold's RGBA_<group>) as they are.\n"
          "Default: each is the denoised beauty's light times its\n"
          "share around the pixel, so that they add up to it\n"
          "(docs/LIGHT_GROUPS.md)." },
        not_in_file_name({ Kind::Names, "--aov", "aov", FIELD(job.aovs), "NAME",
          "Also denoise the radiance AOV NAME (repeatable): its\n"
          "NAME.R,G,B channels, or the beauty's layer's\n"
          "(ViewLayer.NAME.R,G,B: Emit, a volume, an LPE), as\n"
          "its share of the denoised beauty; other channels are\n"
          "copied (docs/AOVS.md)." }),
        { Kind::Flag, "--diagnostics", "diagnostics", FIELD(job.diagnostics), "",
          "Add the filter's maps to the output: zdenoise.radius,\n"
          "zdenoise.stop (1 quality, 2 size, 3 edge, 0 not\n"
          "filtered), zdenoise.noise (the input's relative noise)\n"
          "and zdenoise.error (the output's estimated remaining\n"
          "relative error: where more samples are needed);\n"
          "docs/DIAGNOSTICS.md." },
        { Kind::Path, "--diagnostics-png", nullptr, FIELD(job.diagnostics_png), "FILE",
          "Also write the remaining-error map as a false-colour\n"
          "PNG with a legend (0.1% to 10%)." },
        { Kind::Path, "--colorconfig", "colorconfig", FIELD(job.colour.config), "FILE",
          "OCIO config (default: $OCIO, else the bundled\n"
          "share/zdenoise/ocio/config.ocio)." },
        { Kind::Name, "--iscolorspace", "iscolorspace", FIELD(job.colour.input_space), "NAME",
          "Colour space of the noisy input (default: an EXR's\n"
          "chromaticities, else the config's scene_linear; a\n"
          "PNG/JPEG's tag, sRGB). -v says what was assumed." },
        { Kind::Name, "--albedo-colorspace", "albedo-colorspace", FIELD(job.colour.albedo_space), "NAME",
          "Colour space of the albedo (default: as --in when\n"
          "from the same file, else guessed the same way)." },
        { Kind::Name, "--ocolorspace", "ocolorspace", FIELD(job.colour.output_space), "NAME",
          "Colour space of the output (default: the input's)." },
        { Kind::Name, "--working-colorspace", "working-colorspace", FIELD(job.colour.working_space), "NAME",
          "Space the filter works in (default: scene_linear).\n"
          "Demodulation is per channel: use the renderer's\n"
          "rendering space." },
        { Kind::Mode, "--mode", "mode", FIELD(job.mode), "MODE",
          "'path': the direct light (Cycles' DiffDir) and the rest\n"
          "apart, the direct light's structure beyond its noise\n"
          "kept (hard and thin shadows);\n"
          "'layers': denoise each layer (lobe or specular depth)\n"
          "with its own albedo, add the residual;\n"
          "'beauty': denoise the beauty with the albedo as one.\n"
          "Default: path where the render has its direct light\n"
          "apart (Cycles' DiffDir and DiffCol, Arnold's\n"
          "diffuse_direct and diffuse_albedo) and no option\n"
          "describes the beauty (--albedo, --aux, --variance,\n"
          "--halves, --temporal, a colour space); layers when\n"
          "--layer is given; else beauty. Measured on\n"
          "twelve scenes in docs/LAYERS.md." },
        not_in_file_name({ Kind::Layers, "--layer", "layers", FIELD(job.layers), "NAME=RADIANCE:ALBEDO[:divided][:reflected]",
          "A layer of the --in file (repeatable; replaces the\n"
          "detected layers). RADIANCE and ALBEDO are channel\n"
          "selections as for :ch= (a layer name or a list of\n"
          "channels); RADIANCE may sum sets with '+'\n"
          "(DiffDir+DiffInd). 'divided': the radiance is already\n"
          "divided by the albedo (Cycles' Dir/Ind passes).\n"
          "'reflected': light through a glossy or specular bounce\n"
          "(reflection, refraction): a stricter edge test." }),
        { Kind::Text, "--residual", "residual", FIELD(job.residual), "CHANNELS",
          "What is added unfiltered (e.g. Emit+Env). Default: the\n"
          "beauty minus the layers." },
        { Kind::DataType, "-d", "data-type", FIELD(job.data_type), "TYPE",
          "Output pixel type, 'half' or 'float' (default: each\n"
          "channel's input type). Cryptomatte channels stay float." },
        always_written({ Kind::Preset, "--preset", "preset", FIELD(preset), "NAME",
          "Start from a parameter set: 'tuned' (default, tuned on\n"
          "the public benchmark) or 'spec' (the method's own,\n"
          "docs/FILTER.md section 9: edge-k 3, value-k 2,\n"
          "sigma-good 1); the options\n"
          "below override it wherever they stand." }),
        parameter({ Kind::Whole, "--rmin", "rmin", FIELD(job.filter.r_min), "N",
          "Smallest window half-size (default 2)" }),
        parameter({ Kind::Whole, "--rmax", "rmax", FIELD(job.filter.r_max), "N",
          "Largest window half-size (default 16)" }),
        parameter({ Kind::Real, "--eta", "eta", FIELD(job.filter.eta_target), "X",
          "Target relative noise at the window centre (0.02)" }),
        parameter({ Kind::Real, "--edge-k", "edge-k", FIELD(job.filter.edge_k), "X",
          "Strong-variation stop: multiple of the noise (1.5)" }),
        parameter({ Kind::Real, "--tau-min", "tau-min", FIELD(job.filter.tau_min), "X",
          "Strong-variation stop: smallest level (0.05)" }),
        parameter({ Kind::Real, "--value-k", "value-k", FIELD(job.filter.value_k), "X",
          "Strength of the value weight (1)" }),
        parameter({ Kind::Whole, "--value-noise", "value-noise", FIELD(job.filter.value_noise), "0|1",
          "1: the value weight's scale adds the centre's noise\n"
          "(t standard deviations), so that noise is not taken\n"
          "for structure; 0: the method's |<z>| alone (1)" }),
        parameter({ Kind::Whole, "--energy-radius", "energy-radius", FIELD(job.filter.energy_radius), "N",
          "Scale (px) at which the filtered light keeps the\n"
          "input's energy where the input's noise allows;\n"
          "0: off, the method's (12)" }),
        parameter({ Kind::Real, "--sigma-good", "sigma-good", FIELD(job.filter.sigma_good), "X",
          "Noisiest point taking part in fits (3)" }),
        parameter({ Kind::Real, "--albedo-eps", "albedo-eps", FIELD(job.filter.albedo_eps), "X",
          "Smallest albedo demodulated (0.001)" }),
        parameter({ Kind::Real, "--depth-tol", "depth-tol", FIELD(job.filter.depth_tolerance), "X",
          "Relative depth departure ending a surface (0.02)" }),
        parameter({ Kind::Real, "--normal-cut", "normal-cut", FIELD(job.filter.normal_cut), "X",
          "Normal weight is 0 at or below this dot product (0.5)" }),
        parameter({ Kind::Real, "--normal-power", "normal-power", FIELD(job.filter.normal_power), "X",
          "Normal weight exponent (4)" }),
        parameter({ Kind::Real, "--quadrant-power", "quadrant-power", FIELD(job.filter.quadrant_power), "X",
          "Quadrant weight exponent (8)" }),
        parameter({ Kind::Whole, "--stride", "stride", FIELD(job.filter.centre_stride), "N",
          "Fit windows at every N-th pixel, and at every pixel\n"
          "near an edge (3; 1 = the exact filter, 1.5x as slow,\n"
          "within 2% of the same relMSE; docs/PERFORMANCE.md)" }),
        parameter({ Kind::Whole, "--stride-edges", "stride-edges", FIELD(job.filter.stride_edges), "0|1|2",
          "Windows beside an edge: 1 at every pixel; 2 at every\n"
          "other pixel (0.82x the time, relMSE 1.002x, at most\n"
          "1.013x on 72 cases); 0 the lattice only (preview:\n"
          "up to 1.6x the relMSE) (1)" }),
        parameter({ Kind::Whole, "--outlier-spread", "outlier-spread", FIELD(job.filter.outlier_spread), "0|1",
          "1: fireflies keep the light around them in the fit\n"
          "and their excess is spread over their surface,\n"
          "keeping the energy; 0: the value term alone (1)" }),
        parameter({ Kind::Real, "--radius-growth", "radius-growth", FIELD(job.filter.radius_growth), "X",
          "Radius tried after R: max(R+1, R*X) (2: radii 2, 4, 8,\n"
          "16; 1 = the method's R+1, as --preset spec)" }),
        parameter({ Kind::Whole, "--pyramid", "pyramid", FIELD(job.filter.pyramid_radius), "R",
          "Fit trial radii >= R on the fit points averaged 2x2\n"
          "(a quarter of the points), splat at full resolution\n"
          "(0 = the exact filter; docs/FILTER.md 5.1) (0)" }),
        parameter({ Kind::Whole, "--select", "select", FIELD(job.filter.select), "0|1",
          "1: each pixel takes today's filter or one of two\n"
          "feature regressions, by its estimated error (SURE, or\n"
          "the halves' cross error; docs/FILTER.md section 13);\n"
          "0: today's filter alone, 1.5x faster (1)" }),
        parameter({ Kind::Whole, "--core", "core", FIELD(job.filter.core), "0|1",
          "1: the box core, experimental: regressions on\n"
          "position, normal and depth over windows of radii\n"
          "1..--box-radius from box sums, per pixel a blend of\n"
          "the input and the radii by their estimated risks\n"
          "(docs/FILTER.md section 15; on the public set\n"
          "0.95-1.16x the default's relMSE, worse on\n"
          "glass_cabin, not faster); 0: the windows of\n"
          "sections 2-13 (0)" }),
        parameter({ Kind::Whole, "--box-radius", "box-radius", FIELD(job.filter.box_radius), "R",
          "With --core 1: the largest window half-size (64)" }),
        always_written({ Kind::Whole, "--threads", "threads", FIELD(job.threads), "N",
          "Threads (default: all cores); results do not depend\n"
          "on it." }),
        { Kind::Whole, "--tile", "tile", FIELD(job.tile_rows), "N",
          "Read, denoise and write the frame in strips of N\n"
          "rows (each read with the filter's halo of\n"
          "2*rmax+4 rows around it): memory follows N, not the\n"
          "frame. Default: automatic, the whole frame when it is\n"
          "small, else strips that fit the memory. Results do\n"
          "not depend on it." },
        { Kind::Text, "-o", nullptr, FIELD(output), "FILE",
          "Output image: the --in file with its radiance channels\n"
          "denoised; every other channel and the metadata kept,\n"
          "each channel in its input pixel type. Written to a\n"
          "temporary file, then renamed." },
        { Kind::Text, "--write-recipe", nullptr, FIELD(recipe), "FILE",
          "Instead of denoising, write a recipe (.zdn) for these\n"
          "options: any OpenImageIO program with the zdenoise\n"
          "plugin reads it as the denoised image\n"
          "(share/zdn-format.md)." },
        { Kind::Flag, "--force", nullptr, FIELD(force), "",
          "Allow the output to replace one of the inputs." },
        { Kind::Whole, "--temporal", "temporal", FIELD(job.temporal), "K",
          "Denoise each frame with frames t-K..t+K as extra\n"
          "evidence: their light, reprojected through the motion\n"
          "vectors, counts where the guides agree (0; a frame\n"
          "sequence; docs/TEMPORAL.md)" },
        { Kind::Flag, "--static-camera", "static-camera", FIELD(job.static_camera), "",
          "With --temporal: the camera and the scene do not\n"
          "move, so no motion vectors are needed." },
        { Kind::Input, "--motion", "motion", FIELD(job.motion), "FILE",
          "Motion vectors for --temporal (default: a Cycles\n"
          "file's Vector pass, Arnold's motionvector)." },
        { Kind::Text, "--frames", nullptr, FIELD(frames), "LIST",
          "Frames to denoise: 1001-1100, 1-99x2 (every 2nd),\n"
          "1,5,10-20; any FILE (and -o) may then name a frame\n"
          "pattern: shot.#.exr (4 digits), shot.@@@.exr (one\n"
          "digit per @), shot.%04d.exr." },
        // A recipe's one frame of patterned inputs; the command line's is
        // --frames (docs: share/zdn-format.md).
        { Kind::Text, nullptr, "frame", FIELD(job.frame), "" },
        { Kind::Text, "--shot-range", "shot-range", FIELD(job.shot_range), "LIST",
          "With --temporal: the shot's frames (default: --frames).\n"
          "Neighbours lie within its first and last, so a farm\n"
          "chunk's frames use the frames around the chunk." },
        { Kind::Flag, "--skip-existing", nullptr, FIELD(skip_existing), "",
          "Leave frames whose output exists (re-runs)." },
        { Kind::Flag, "--fail-fast", nullptr, FIELD(fail_fast), "",
          "Stop at the first failed frame (default: report it,\n"
          "denoise the others, exit 1 at the end)." },
        { Kind::Text, "--report", nullptr, FIELD(report), "FILE.json",
          "Per-frame wall time, parameters, filter statistics." },
        { Kind::Whole, "--print-chunks", nullptr, FIELD(print_chunks), "N",
          "Print the frame list in chunks of N frames, one\n"
          "--frames list per line, and exit (farm dispatch:\n"
          "share/zdenoise/farm/zdenoise-sbatch)." },
        { Kind::Size, "--mem-limit", nullptr, FIELD(job.mem_limit), "SIZE",
          "Refuse a frame needing more memory than SIZE (bytes,\n"
          "or with a K, M, G or T suffix), before reading its\n"
          "pixels. Default: half the machine's memory." },
        { Kind::Flag, "-v", nullptr, FIELD(verbose), "",
          "Verbose: inputs, parameters, progress, timings,\n"
          "statistics." },
        { Kind::Help, "--help", nullptr, {}, "",
          "This text." },
        { Kind::Help, "-h", nullptr, {}, "", nullptr },
        { Kind::Version, "--version", nullptr, {}, "",
          "Print the version." },
    };
    return table;
}


namespace {

/// The option whose `name` (its flag or its key) is `text`, or null.
const Option*
find(const char* Option::*name, const std::string& text)
{
    for (const Option& o : options())
        if (o.*name && text == o.*name)
            return &o;
    return nullptr;
}

}  // namespace


const Option*
find_flag(const std::string& flag)
{
    return find(&Option::flag, flag);
}


std::string
option_name(const Option& option, Spelling spelling)
{
    const char* name = spelling == Spelling::CommandLine ? option.flag
                                                         : option.key;
    std::string text = name ? name : "";
    if (spelling == Spelling::Keyword)
        for (char& c : text)
            c = c == '-' ? '_' : c;
    return text;
}


const Option*
find_option(const std::string& name, Spelling spelling)
{
    if (name.empty())
        return nullptr;
    for (const Option& o : options())
        if (option_name(o, spelling) == name)
            return &o;
    return nullptr;
}


const Option*
find_key(const std::string& key)
{
    return find(&Option::key, key);
}


std::string
usage_text()
{
    std::string text;
    for (const std::string& line : Strutil::splits(kUsage, "\n")) {
        const Option* o = line.size() > 2 && line.front() == '{'
                                  && line.back() == '}'
                              ? find_flag(line.substr(1, line.size() - 2))
                              : nullptr;
        text += (o ? option_help(*o) : line) + "\n";
    }
    return text;
}


bool
parse_mode(const std::string& text, Mode& mode)
{
    if (text == "beauty")
        mode = Mode::Beauty;
    else if (text == "layers")
        mode = Mode::Layers;
    else if (text == "path")
        mode = Mode::Path;
    else
        return false;
    return true;
}


const char*
mode_name(Mode mode)
{
    return mode == Mode::Beauty   ? "beauty"
           : mode == Mode::Layers ? "layers"
           : mode == Mode::Path   ? "path"
                                  : "";
}


bool
parse_data_type(const std::string& text, OIIO::TypeDesc& type)
{
    if (text != "half" && text != "float")
        return false;
    type = OIIO::TypeDesc(text);
    return true;
}


bool
parse_layer(const std::string& text, LayerArg& layer)
{
    const size_t eq = text.find('=');
    if (eq == std::string::npos || eq == 0)
        return false;
    const std::vector<std::string> parts = Strutil::splits(text.substr(eq + 1),
                                                           ":");
    if (parts.size() < 2 || parts.size() > 4 || parts[0].empty()
        || parts[1].empty())
        return false;
    layer.name      = text.substr(0, eq);
    layer.radiance  = parts[0];
    layer.albedo    = parts[1];
    layer.divided   = false;
    layer.reflected = false;
    for (size_t k = 2; k < parts.size(); ++k) {
        bool& flag = parts[k] == "divided" ? layer.divided : layer.reflected;
        if ((parts[k] != "divided" && parts[k] != "reflected") || flag)
            return false;  // unknown or repeated
        flag = true;
    }
    return true;
}


std::string
layer_text(const LayerArg& layer)
{
    return layer.name + "=" + layer.radiance + ":" + layer.albedo
           + (layer.divided ? ":divided" : "")
           + (layer.reflected ? ":reflected" : "");
}


bool
apply_preset(const std::string& preset, FilterOptions& options)
{
    FilterOptions parameters;
    if (preset == "spec")
        parameters = FilterOptions::algorithm_defaults();
    else if (preset != "tuned")
        return false;
    parameters.progress = std::move(options.progress);
    options             = std::move(parameters);
    return true;
}


const char*
preset_names()
{
    return "tuned, spec";
}


bool
parse_real(const std::string& text, double& value)
{
    const char* s = text.c_str();
    char* end     = nullptr;
    errno         = 0;
    double v      = std::strtod(s, &end);
    if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
        return false;
    value = v;
    return true;
}


bool
parse_whole(const std::string& text, int& value)
{
    double v = 0.0;
    if (!parse_real(text, v) || v != std::floor(v) || std::fabs(v) > 1e6)
        return false;
    value = int(v);
    return true;
}

bool
parse_size(const std::string& text, uint64_t& value)
{
    std::string digits = text;
    double scale       = 1.0;
    const std::string suffixes = "KMGT";
    if (!digits.empty()) {
        size_t k = suffixes.find(char(std::toupper(digits.back())));
        if (k != std::string::npos) {
            scale = std::ldexp(1.0, 10 * int(k + 1));
            digits.pop_back();
        }
    }
    double v = 0.0;
    if (!parse_real(digits, v) || v * scale < 1.0 || v * scale > 1.8e19)
        return false;
    value = uint64_t(v * scale);
    return true;
}

}  // namespace job
}  // namespace zdenoise
