// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Other radiance AOVs (--aov NAME, docs/AOVS.md): found in the --in file by
// name, and each strip's denoised with the beauty's guides.

#pragma once

#include <functional>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/zdenoise.h>

#include "input_files.h"
#include "job_types.h"
#include "light_groups_plan.h"
#include "strips.h"

namespace zdenoise {
namespace job {

/// The AOVs job `j` denoises.
struct AovPlan {
    std::vector<std::string> names;   ///< the layers' ("ViewLayer.Emit")
    std::vector<Selection> channels;  ///< each one's R,G,B in --in
    bool empty() const { return names.empty(); }
};

/// The AOVs of --aov in the --in file `in`: NAME.R,G,B, else the beauty's
/// layer's (ViewLayer.NAME.R,G,B beside ViewLayer.Combined). Fails with a
/// one-line error for a name not found, found twice, or naming the beauty
/// or a light group (`groups`: denoised already), and with --temporal.
AovPlan
plan_aovs(const Job& j, const InputHeader& in, const Selection& radiance,
          const LightGroupPlan& groups, std::vector<std::string>& log);

/// Rows beyond a strip that the AOVs' split reads of the denoised beauty
/// (0 without AOVs).
int
aovs_reach(const AovPlan& aovs);

/// Rows beyond a strip that the light groups' and the AOVs' splits read of
/// the denoised beauty: it is denoised this much further.
int
split_reach(const LightGroupPlan& groups, const AovPlan& aovs);

/// Strip `strip`'s AOVs (read from its files, converted like the radiance
/// by `convert`), each split from the denoised beauty `denoised` (over the
/// strip widened by aovs_reach()) as a light group of its own, with the
/// noisy `radiance` and the normal, depth and object id of `guides`, over
/// the strip's rows (3 float channels each).
std::vector<OIIO::ImageBuf>
denoise_strip_aovs(const Job& j, const AovPlan& aovs, const Strip& strip,
                   const OIIO::ROI& frame, const OIIO::ImageBuf& denoised,
                   const OIIO::ImageBuf& radiance, const Guides& guides,
                   const std::function<void(OIIO::ImageBuf&)>& convert);

}  // namespace job
}  // namespace zdenoise
