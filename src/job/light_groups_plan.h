// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Light groups (docs/LIGHT_GROUPS.md): found beside the beauty with no
// flags (<beauty>_<group>.R,G,B: Cycles' Combined_<group>, Arnold's
// RGBA_<group>), and each strip's groups split from its denoised beauty by
// split_light_groups().

#pragma once

#include <functional>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/zdenoise.h>

#include "input_files.h"
#include "job_types.h"
#include "strips.h"

namespace zdenoise {
namespace job {

/// The light groups job `j` denoises.
struct LightGroupPlan {
    std::vector<std::string> names;     ///< the groups' (e.g. "key")
    std::vector<Selection> channels;    ///< each group's R,G,B in --in
    bool empty() const { return names.empty(); }
};

/// The groups of the --in file `in` beside the beauty `radiance` (channels
/// named as the beauty's R, G, B with "_<group>" after the beauty's layer
/// name; RGBA_<group> beside a plain R, G, B beauty, as Arnold writes
/// them), unless --no-light-groups. In every mode but temporal they are
/// split from the denoised beauty (the sum of the denoised layers in layers
/// and path modes); --temporal copies them (said in `log`).
LightGroupPlan
plan_light_groups(const Job& j, const InputHeader& in, const Selection& radiance,
                  std::vector<std::string>& log);

/// Rows beyond a strip that the groups' split reads of the denoised
/// beauty: the beauty is denoised this much further (0 without groups).
int
light_groups_reach(const LightGroupPlan& groups);

/// The normal, depth and object id of `guides`: a surface's, which the
/// splits read (the noise guides describe the beauty's noise).
Guides
surface_guides(const Guides& guides);

/// Light the beauty holds, `parts` (3 float channels each, over the
/// strip's held rows), split from the denoised beauty `denoised` over
/// `roi` by split_light_groups(), with the noisy `radiance` and the
/// normal, depth and object id of `guides`. `what` names the parts in an
/// error ("the light groups").
std::vector<OIIO::ImageBuf>
split_from_beauty(const Job& j, const OIIO::ROI& frame,
                  const OIIO::ImageBuf& denoised, const OIIO::ImageBuf& radiance,
                  const std::vector<const OIIO::ImageBuf*>& parts,
                  const Guides& guides, const OIIO::ROI& roi,
                  const std::string& what);

/// Strip `strip`'s groups (read from its files, converted like the
/// radiance by `convert`), split from the denoised beauty `denoised` (over
/// the strip widened by light_groups_reach()) and the noisy `radiance`
/// over the strip's rows (3 float channels each).
std::vector<OIIO::ImageBuf>
denoise_strip_light_groups(const Job& j, const LightGroupPlan& groups,
                           const Strip& strip, const OIIO::ROI& frame,
                           const OIIO::ImageBuf& denoised,
                           const OIIO::ImageBuf& radiance, const Guides& guides,
                           const std::function<void(OIIO::ImageBuf&)>& convert);

}  // namespace job
}  // namespace zdenoise
