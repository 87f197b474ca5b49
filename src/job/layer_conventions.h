// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The channel naming conventions zdenoise recognises with no flags: which
// channels of a file are the beauty, its albedo, the guides, and the layers
// (per-lobe or per-specular-depth radiance with its albedo) of layered
// denoising. docs/LAYERS.md lists every name.

#pragma once

#include <string>
#include <vector>

namespace zdenoise {
namespace job {

/// One layer of a layered denoise, as channel selections of the --in file
/// (each a selection as channel_spec.h's select_channels() takes it).
struct LayerArg {
    /// The layer's name; with --aovs its denoised radiance is written to the
    /// channels NAME.R, NAME.G, NAME.B.
    std::string name;
    /// The radiance: one selection, or several joined by '+' that are summed
    /// (Cycles' DiffDir+DiffInd).
    std::string radiance;
    /// The albedo (colour) selection.
    std::string albedo;
    /// The radiance is already divided by the albedo (Cycles' Dir/Ind).
    bool divided = false;
    /// Light through a glossy or specular bounce (zdenoise::Layer::reflected).
    bool reflected = false;
    /// The lobe a convention found it as ("Diff", "Gloss", "Trans" in a
    /// Cycles file), which names its colour in an auxiliary image
    /// (AuxConvention::lobe_colours); empty for --layer.
    std::string lobe;
    /// Direct light (zdenoise::Layer::direct): after the regression filter,
    /// what it smoothed beyond the layer's noise is given back.
    bool direct = false;
};

/// What a file's channel names say, by the first convention that matches.
struct Convention {
    /// e.g. "Blender Cycles multilayer EXR (layer 'ViewLayer.')"; empty when
    /// nothing was recognised.
    std::string name;
    /// Selections; empty = none found (beauty: the plain R,G,B[,A]).
    std::string beauty, albedo, normal, depth, id;
    /// Motion vectors (docs/TEMPORAL.md): Cycles' Vector pass (4
    /// channels), Arnold's motionvector (2).
    std::string motion;
    std::vector<LayerArg> layers;
    /// The layers of light by path (--mode path, docs/LAYERS.md "Light by
    /// path"): the direct light apart from the rest (Cycles: DiffDir over
    /// DiffCol); empty when the file has no such pass.
    std::vector<LayerArg> direct_layers;
    /// The residual selection ('+' joins sets); empty = the beauty minus the
    /// layers.
    std::string residual;
    /// If not empty, the residual is denoised as one more layer with this
    /// albedo instead of being added unfiltered: Cycles' Denoising Albedo
    /// holds the emission of emitters (and its anti-aliasing noise at their
    /// edges), so Emit and Env demodulated by it are smooth.
    std::string residual_albedo;
    /// The name of that layer (for --aovs and -v), also of path mode's
    /// residual layer.
    std::string residual_layer;
    /// A part of that residual which is added as it is, not filtered:
    /// Cycles' Env. The environment seen directly has no noise but the
    /// anti-aliasing of silhouettes, which filtering with the surfaces'
    /// guides only blurs (docs/LAYERS.md).
    std::string residual_unfiltered;
};

/// What an auxiliary image (--aux, docs/AUX.md) holds, by the first
/// convention its channel names match: a Blender Cycles multilayer EXR
/// (zdenoise_aux.py writes one), AOVs named as the Arnold style, or a plain
/// R,G,B image (an albedo).
struct AuxConvention {
    std::string name;  ///< as -v shows it
    /// Selections; the albedo is never empty, the others may be.
    std::string albedo, normal, depth, id;
    /// The colour of each lobe it has, by LayerArg::lobe ("Diff" ->
    /// "ViewLayer.DiffCol").
    std::vector<std::pair<std::string, std::string>> lobe_colours;
};

/// The auxiliary image's passes; false with a one-line `error` naming the
/// file's layers when it has no albedo by any convention.
bool
detect_aux(const std::vector<std::string>& names, AuxConvention& aux,
           std::string& error);

/// The layer part (all but the last '.'-separated part) of each channel
/// name, in order of first appearance.
std::vector<std::string>
layer_paths(const std::vector<std::string>& names);

/// The layers of a file's channels (all but the last '.'-separated part,
/// in order), as messages list them: "ViewLayer.Combined, ViewLayer.Depth";
/// channels of no layer are listed as themselves.
std::string
layers_text(const std::vector<std::string>& names);

/// Recognise, in order: a Blender Cycles multilayer EXR (<prefix>Combined),
/// else AOVs named X with X_albedo (Arnold style, and our specular depth
/// layers spec0..spec5 with spec0_albedo..spec5_albedo and residual).
/// The object id guide is the Cryptomatte object layer's ranks when present.
Convention
detect_convention(const std::vector<std::string>& names);

/// The channels of the Cryptomatte object layer's ranks, in rank order, as
/// an explicit selection "L00.r,L00.g,L00.b,L00.a,L01.r,..." ((id, coverage)
/// pairs: the object id guide). Empty when the file has none. Recognised
/// names: <prefix>CryptoObjectNN.{r,g,b,a} (Blender) and
/// crypto_objectNN.{R,G,B,A} (Arnold), in either letter case.
std::string
cryptomatte_object_selection(const std::vector<std::string>& names);

/// Is this channel part of a Cryptomatte layer (ids stored as float bit
/// patterns, so always written as float)? True for the channels of a layer
/// named by a `cryptomatte/<hash>/name` attribute (`layer_names`), and for
/// any channel whose layer's last part begins with "crypto".
bool
is_cryptomatte_channel(const std::string& channel,
                       const std::vector<std::string>& layer_names);

}  // namespace job
}  // namespace zdenoise
