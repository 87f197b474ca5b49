// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Layered denoising's plan and its reading: which channel sums are each
// layer's radiance and albedo, what is the residual (given, or the beauty
// minus the layers, or a layer of its own with its negligible parts
// masked), and, per strip, those images read. Kept apart from job.cpp
// because layers are a job of their own inside the job: only --mode layers
// reaches this file.

#pragma once

#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/zdenoise.h>

#include "input_files.h"
#include "layer_conventions.h"
#include "strips.h"

namespace zdenoise {
namespace job {

/// The layers of a layered denoise as channel selections: each layer's
/// radiance and albedo sums, and the residual.
struct LayersPlan {
    struct One {
        std::string name;
        std::vector<Selection> radiance, albedo;
        /// A cleaner colour of the layer (the --aux file's), or none.
        std::vector<Selection> remodulation;
        bool divided = false, reflected = false;
        /// Direct light (zdenoise::Layer::direct); where it is not kept
        /// apart the residual layer takes it (route_direct_light()).
        bool direct = false;
        /// Samples a pixel of its colour, the render's own AOV, which
        /// load_layers() prefilters (plan_layer_colours()); 0: as it is.
        int prefilter = 0;
        /// A Cycles glossy or transmission lobe beside the diffuse lobe
        /// `diffuse` (its index in `layers`) and the residual layer: where
        /// the diffuse colour is 0 and this lobe's is not, the first hit is
        /// a mirror or clear glass, and the residual's albedo (Cycles'
        /// Denoising Albedo, which passes through such a hit) is the albedo
        /// of what is seen in it. load_layers() divides the lobe's light by
        /// that there (divide_through_specular()). -1: not such a lobe.
        int diffuse = -1;
    };
    std::vector<One> layers;  ///< the given ones, then the residual's
    /// The residual's terms; none: the beauty minus the given layers.
    std::vector<Selection> residual;
    /// The residual is denoised as the last layer (residual_albedo), but for
    /// these terms, added as they are (residual_unfiltered).
    bool residual_is_layer = false;
    std::vector<Selection> residual_unfiltered;
    /// How far mask_negligible_residual() looks (0 without a residual
    /// layer).
    int mask_reach = 0;
    /// Rows a strip reads beyond the filter's halo: the mask's reach, and
    /// with a direct layer also how far its routing looks
    /// (route_direct_light()), which writes the residual the mask reads.
    int reach = 0;
};

/// Which layers job `j` filters, and whether it is layered and by path:
/// the convention's direct layers in path mode, else the user's (--layer)
/// or the convention's. With no --mode, path mode where the file has the
/// direct light apart and `auto_path_blocker` (what the user asked for
/// that path mode does not do, auto_path_blocker()) is empty; else beauty
/// mode, or layers mode with --layer. Fails, naming the file, when the
/// mode asks for layers the file does not have.
const std::vector<LayerArg>&
choose_layers(const Job& j, const Convention& conv,
              const std::string& auto_path_blocker, bool& path, bool& layered);

/// Why job `j`, as the user gave it (before the convention's defaults),
/// is not filtered by path when no --mode is given: an option whose
/// meaning is the beauty's (--albedo, --aux, --variance, --halves,
/// --temporal, --layer, a colour space); empty when none is given.
std::string
auto_path_blocker(const Job& j);

/// Choose the layers and the residual; the residual is, unless selected,
/// the beauty minus the sum of the unfiltered layers, so that nothing of
/// the beauty is lost (in Cycles: Emit + Env, and any lobe whose passes
/// were not written). With `residual_albedo`, the residual becomes one
/// more layer, denoised with that albedo (see Convention::residual_albedo).
LayersPlan
plan_layers(InputFiles& files, const Job& j,
            const std::vector<LayerArg>& args, const std::string& residual,
            const std::string& residual_albedo,
            const std::string& residual_layer,
            const std::string& residual_unfiltered, const OIIO::ROI& noisy,
            std::vector<std::string>& log);


/// --aux in layers mode (docs/AUX.md): each layer whose lobe the auxiliary
/// image has a colour for (AuxConvention::lobe_colours; the residual layer:
/// its albedo) takes that colour as its own where it divides the radiance
/// (`j.aux_demodulation`, as in beauty mode) and as the remodulation colour
/// where the radiance came divided (Cycles' Dir/Ind). `args` are the layers
/// plan_layers() was given, in its order.
void
use_aux_colours(LayersPlan& plan, InputFiles& files, const Job& j,
                const std::vector<LayerArg>& args, const AuxConvention& aux,
                const OIIO::ROI& noisy, std::vector<std::string>& log);


/// The layers of one strip, read.
struct LoadedLayers {
    std::vector<OIIO::ImageBuf> radiance, albedo, remodulation, denoised;
    std::vector<FilterStats> stats;
    OIIO::ImageBuf residual;
};

/// Read the strip's layers and residual as `plan` says.
std::vector<Layer>
load_layers(const Strip& strip, const LayersPlan& plan, const Job& j,
            const OIIO::ImageBuf& beauty, LoadedLayers& l);

}  // namespace job
}  // namespace zdenoise
