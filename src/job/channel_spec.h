// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Choosing channels of an input file for a role (radiance, albedo, guide):
// the `:ch=` selection of the command line and the defaults for Blender
// Cycles multilayer EXR files.

#pragma once

#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

namespace zdenoise {
namespace job {

/// What a set of channels is for; decides the channel names looked for.
enum class Role {
    Radiance,
    Albedo,
    Normal,
    Depth,
    ObjectId,
    Variance,
    LayerRadiance,  ///< a layer's or the residual's R,G,B (no alpha)
    Motion          ///< motion vectors (docs/TEMPORAL.md): 2 or 4 channels
};

const char*
role_name(Role role);

/// Resolve a channel selection against a file's channel names.
///
/// `selection` is one of
///   - ""            : the role's plain names (R,G,B[,A]; X,Y,Z; Z; ...);
///   - "A,B,C"       : exact channel names, or suffixes after a '.'
///                     ("Denoising Albedo.R") matching exactly one channel;
///   - "LAYER"       : a layer/pass name: LAYER.R, LAYER.G, ... (the role's
///                     component names), matched as a suffix after a '.'.
/// Radiance takes 3 channels plus an optional alpha (A) after them; albedo,
/// layer radiance and normal 3; depth 1; variance 1 or 3; object id 1 or an even number
/// ((id, coverage) pairs); motion vectors 2 or 4.
/// On failure returns false with a message naming the channels missing.
bool
select_channels(const std::vector<std::string>& names, const std::string& selection,
                Role role, std::vector<int>& indices, std::string& error);

/// If the file is a Blender Cycles multilayer EXR (it has a
/// `<prefix>Combined.R` channel), return true and its layer prefix (e.g.
/// "ViewLayer."). When there are several, the first that also has a
/// `Denoising Albedo` (Blender's "Composite." layer, the compositor's output,
/// has none), else the first.
bool
cycles_prefix(const std::vector<std::string>& names, std::string& prefix);

}  // namespace job
}  // namespace zdenoise
