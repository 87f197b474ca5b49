// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// A denoise job as the command line (and the OIIO plugin) describe it:
// input files with channel selections, filter options. run_job() reads
// the files, picks the channels (with the defaults of the conventions in
// layer_conventions.h), denoises the beauty or its layers, and assembles
// the output image: the noisy input file with its radiance RGB replaced
// (and, on request, the denoised layers added), every other channel and the
// metadata kept.

#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/zdenoise.h>

#include "../../ocio/colour.h"
#include "layer_conventions.h"

namespace zdenoise {
namespace job {

/// One input file and its channel selection (see channel_spec.h).
struct InputArg {
    std::string path;
    std::string channels;  ///< the :ch= selection; empty = the default
    bool given = false;
};

/// Beauty: denoise the beauty with the albedo. Layers: denoise each layer
/// with its albedo and sum them with the residual (layered_denoise()).
/// Auto: layers when --layer gives them, else beauty (measured on the
/// public benchmark, docs/LAYERS.md: layers win on cornell_textured but
/// lose slightly on newspaper and zigzag_steps).
enum class Mode { Auto, Beauty, Layers };

struct Job {
    InputArg in, albedo, normal, depth, id, variance, half_a, half_b;
    bool no_normal = false, no_depth = false, no_id = false;
    FilterOptions filter;
    colour::ColourOptions colour;
    Mode mode = Mode::Auto;
    /// Layers of the --in file (--layer); when given they replace the
    /// detected ones.
    std::vector<LayerArg> layers;
    /// The residual selection of the --in file ('+' sums sets); empty: the
    /// convention's, else the beauty minus the layers.
    std::string residual;
    /// Also write each denoised layer as NAME.R,G,B (--aovs).
    bool write_layers = false;
    /// Pixel type of the output channels; TypeUnknown keeps each input
    /// channel's. Cryptomatte channels are float whatever this says.
    OIIO::TypeDesc data_type = OIIO::TypeUnknown;
    int threads = 0;  ///< 0: OIIO's "threads" attribute
    /// Largest memory (bytes) a frame may need; a larger frame is refused
    /// before its pixels are read. 0: default_memory_limit().
    uint64_t mem_limit = 0;
};

struct JobResult {
    /// The output image, with its per-channel write formats and the
    /// zdenoise metadata set: ready for ImageBuf::write.
    OIIO::ImageBuf image;
    /// Each channel's pixel type in the output (as set for writing): the
    /// input's, or -d's, Cryptomatte float.
    std::vector<OIIO::TypeDesc> channel_formats;
    FilterStats stats;
    /// What was read and assumed, one line each (for -v).
    std::vector<std::string> log;
    double read_seconds = 0.0, denoise_seconds = 0.0;
};

/// The spellings of the command line and recipes: "beauty", "layers" (Auto
/// has none); "half", "float" for the output type;
/// "NAME=RADIANCE:ALBEDO[:divided][:reflected]" for a layer. Each parse returns false
/// for anything else.
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

/// Run `job`. On failure returns false and a one-line `error` naming the
/// file, channel or option at fault. Never throws.
bool
run_job(const Job& job, JobResult& result, std::string& error);

/// Half of the machine's memory (MemTotal, or the cgroup's memory.max when
/// lower): room for the frame and whatever else runs on a render node.
uint64_t
default_memory_limit();

/// Every input path of the job (to refuse an output that is an input).
std::vector<std::string>
input_paths(const Job& job);

/// OIIO error texts can span lines; zdenoise reports one.
std::string
one_line(std::string s);

}  // namespace job
}  // namespace zdenoise
