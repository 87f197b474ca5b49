// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The types the job's files share: a job as the command line (and the OIIO
// plugin, and recipes) describe it, what running it gives back, and where
// its output rows go. The bottom of src/job: it includes nothing of
// src/job but the layer conventions' LayerArg.

#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/zdenoise.h>

#include "layer_conventions.h"
#include "ocio/colour.h"

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
/// Path: layers of the direct light apart from the rest (docs/LAYERS.md,
/// "Light by path"). Auto: layers when --layer gives them, else beauty.
enum class Mode { Auto, Beauty, Layers, Path };

/// What the render's radiance is divided by when an auxiliary image
/// (--aux) is given: the render's own albedo (sharing the radiance's
/// samples, so their quotient cancels much of the albedo's noise) or the
/// auxiliary one. Either way the auxiliary albedo remodulates. An internal
/// switch for measurement (docs/AUX.md), read from ZDENOISE_AUX_DEMODULATE
/// (render|aux); no option sets it.
enum class AuxDemodulation { Render, Aux };

struct Job {
    InputArg in, albedo, normal, depth, id, variance, half_a, half_b;
    /// The deterministic auxiliary image of the same shot (docs/AUX.md):
    /// its albedo remodulates, its guides replace the --in file's.
    InputArg aux;
    AuxDemodulation aux_demodulation = AuxDemodulation::Aux;
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
    /// Copy the beauty's alpha as it is (--no-alpha); by default a
    /// fractional alpha is denoised (alpha_plan.h).
    bool no_alpha = false;
    /// Copy the light groups as they are (--no-light-groups); by default
    /// they are split from the denoised beauty (light_groups_plan.h).
    bool no_light_groups = false;
    /// Other radiance AOVs denoised with the beauty's guides (--aov NAME,
    /// repeatable; aov_plan.h).
    std::vector<std::string> aovs;
    /// Samples per pixel of the albedo for its prefilter
    /// (prefilter_albedo(); --albedo-samples); 0: the render's count from
    /// its metadata when the albedo is the --in file's and no --aux is
    /// given. --no-albedo-prefilter turns it off.
    int albedo_samples = 0;
    bool no_albedo_prefilter = false;
    /// Add the filter's diagnostic maps to the output as the channels
    /// kDiagnosticsLayer.<name> of zdenoise::diagnostic_channels()
    /// (--diagnostics; docs/DIAGNOSTICS.md).
    bool diagnostics = false;
    /// Also write the remaining-error map as a false-colour PNG with a
    /// legend (--diagnostics-png; the command line's only: a recipe opened
    /// by another program writes no files).
    std::string diagnostics_png;
    /// Pixel type of the output channels; TypeUnknown keeps each input
    /// channel's. Cryptomatte channels are float whatever this says.
    OIIO::TypeDesc data_type = OIIO::TypeUnknown;
    int threads = 0;  ///< 0: OIIO's "threads" attribute
    /// Largest memory (bytes) a frame may need; a larger frame is refused
    /// before its pixels are read. 0: default_memory_limit().
    uint64_t mem_limit = 0;
    /// Largest image (width x height of --in) the job may denoise,
    /// refused before its pixels are read; 0: any. Recipes set it
    /// (ZDENOISE_RECIPE_LIMITS, recipe.h); the command line does not.
    uint64_t max_pixels = 0;
    /// Rows per strip (--tile); 0: automatic (the whole frame when it is
    /// small, else strips as tall as the memory budget allows).
    int tile_rows = 0;
    /// Frames on each side denoised with this one (--temporal K,
    /// docs/TEMPORAL.md); 0: the frame alone.
    int temporal = 0;
    /// With temporal: the camera and the scene do not move, so that the
    /// neighbours need no motion vectors (--static-camera).
    bool static_camera = false;
    /// The motion vectors (--motion; default: the --in file's by its
    /// convention).
    InputArg motion;
    /// The shot's frames (--shot-range, a frame list): with temporal, the
    /// neighbours lie within its first and last. Empty: a batch's --frames.
    std::string shot_range;
    /// A recipe's frame (its "frame", one frame of the --frames notation):
    /// the frame its patterned inputs (shot.#.exr) are read at. Empty: the
    /// inputs name files. read_recipe() resolves it (job_with_neighbours()).
    std::string frame;
    /// With temporal: the jobs of the neighbouring frames (their inputs'
    /// paths; the rest as this job's), and each one's frame offset.
    /// job_with_neighbours() fills them.
    std::vector<Job> neighbours;
    std::vector<int> neighbour_offsets;
};

/// The layer of the output that holds the diagnostic maps.
constexpr const char* kDiagnosticsLayer = "zdenoise";

struct JobResult {
    /// The output image, with its per-channel write formats and the
    /// zdenoise metadata set, ready for ImageBuf::write (the run_job()
    /// that has no sink only).
    OIIO::ImageBuf image;
    /// Each channel's pixel type in the output (as set for writing): the
    /// input's, or -d's, Cryptomatte float.
    std::vector<OIIO::TypeDesc> channel_formats;
    FilterStats stats;
    /// What was read and assumed, one line each (for -v).
    std::vector<std::string> log;
    /// Time spent reading (and converting the inputs), denoising, and
    /// assembling and writing the output, summed over the strips.
    double read_seconds = 0.0, denoise_seconds = 0.0, write_seconds = 0.0;
    /// How the frame was cut: `strips` strips of `strip_rows` rows (the
    /// last one may be shorter); the memory estimated for one.
    int strips = 0, strip_rows = 0;
    double estimated_bytes = 0.0;
};

/// Where run_job() puts the output image: a band of whole rows at a time,
/// top to bottom.
class OutputSink {
public:
    virtual ~OutputSink() = default;
    /// Once, before any rows: the output's spec (data window, channels and
    /// metadata as an ImageBuf holding the image in float has them) and each
    /// channel's pixel type in the output.
    virtual bool begin(const OIIO::ImageSpec& spec,
                       const std::vector<OIIO::TypeDesc>& formats,
                       std::string& error)
        = 0;
    /// Whether rows() takes every channel as float; else each channel comes
    /// in its output pixel type (`formats`), as ImageOutput's native
    /// scanlines are laid out.
    virtual bool float_rows() const { return false; }
    /// Whether the sink keeps the whole image (counted in the memory a
    /// job needs).
    virtual bool holds_image() const { return false; }
    /// Rows [ybegin, yend): pixels interleaved, channels in order.
    virtual bool rows(int ybegin, int yend, const void* data,
                      std::string& error)
        = 0;
    /// After the last rows.
    virtual bool end(std::string& error) { return true; }
};

}  // namespace job
}  // namespace zdenoise
