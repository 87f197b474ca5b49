// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// What plan() (job.cpp) decides before the first pixel is read, and the
// images of one strip's roles: shared by run_strip() and the steps it
// calls in files of their own (temporal_strip.cpp, albedo_plan.cpp).

#pragma once

#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/temporal.h>
#include <zdenoise/zdenoise.h>

#include "albedo_plan.h"
#include "aov_plan.h"
#include "diagnostics_picture.h"
#include "input_files.h"
#include "job_types.h"
#include "layers_plan.h"
#include "light_groups_plan.h"
#include "output.h"
#include "strips.h"
#include "ocio/colour.h"

namespace zdenoise {
namespace job {

/// Everything decided before the first pixel is read.
struct Plan {
    bool layered = false;
    /// Light by path (--mode path, or its default): layered, with the
    /// direct light as its layers (Convention::direct_layers).
    bool path = false;
    /// With no --mode: the option that keeps the file from being filtered
    /// by path (auto_path_blocker()); empty when none does.
    std::string path_blocker;
    OIIO::ROI noisy;  ///< the --in file's pixels
    RoleSelections roles;
    colour::ColourConfig config;
    colour::JobSpaces spaces;
    bool managed = false;  ///< colour spaces are converted
    /// The radiance (and halves) and the albedo need no conversion: their
    /// images may be the files' rows.
    bool radiance_as_is = true, albedo_as_is = true;
    LayersPlan layers;
    LightGroupPlan groups;  ///< split from the denoised beauty
    AovPlan aovs;           ///< --aov
    Output output;
    int around = 0;  ///< rows a strip reads above and below its own
    /// The filter's diagnostic maps are computed (--diagnostics, or
    /// --diagnostics-png, whose error and stop maps of the whole frame are
    /// kept here).
    bool maps = false;
    ErrorPicture picture;
    AlbedoPlan albedo;  ///< beauty mode
    AuxAlbedoStats pooled;  ///< over the strips, when albedo.pool
};


/// The images of one strip's roles (those unused stay empty).
struct RoleImages {
    OIIO::ImageBuf radiance, albedo, normal, depth, id, variance, half_a, half_b,
        remodulation, own_albedo, motion;
    /// The halves' own albedos (their files' Denoising Albedo), which
    /// measure the albedo's noise (albedo_plan.h).
    OIIO::ImageBuf half_a_albedo, half_b_albedo;
};


/// May the optional role's image be the file's rows (no conversion)?
inline bool
role_as_is(const OptionalRole& o, const Plan& p)
{
    return o.role == Role::Radiance ? p.radiance_as_is
           : o.role == Role::Albedo ? p.albedo_as_is
                                    : true;
}


/// Strip `strip`'s role images (the files' rows held): those converted to
/// the working space are copies, the others the files' rows themselves.
RoleImages
read_role_images(const Job& j, const Plan& p, const Strip& strip);

/// Convert an image of `arg`'s file between colour spaces (when it is
/// there and the job manages colour).
void
convert_role(const Plan& p, OIIO::ImageBuf& image, const std::string& from,
             const std::string& to, const InputArg& arg);

}  // namespace job
}  // namespace zdenoise
