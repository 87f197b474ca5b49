// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// --temporal over one strip (docs/TEMPORAL.md): what run_strip() calls to
// combine frame t with its neighbours before the filter.

#pragma once

#include <zdenoise/temporal.h>

#include "strip_plan.h"

namespace zdenoise {
namespace job {

/// What --temporal combines frames with: the library's defaults, at the
/// filter's albedo_eps.
TemporalOptions
temporal_options(const Job& j);

/// Rows frame t is read with beyond what the filter reads: with
/// --temporal, the light test's box.
int
temporal_reach(const Job& j);

/// --temporal (docs/TEMPORAL.md): frame t's radiance (and albedo, variance
/// or halves) averaged with its neighbours' light where they show the same
/// surface and light, over what the filter reads of the strip. Frame t's
/// images come over that and the light test's box around it; each
/// neighbour is read over the rows its flow reaches (and the albedo
/// prefilter's halo), converted and prefiltered as frame t. A flow chains
/// the motion vectors of the frames between, nearest first.
void
combine_neighbours(const Job& j, const Plan& p, InputFiles& files,
                   const Strip& strip, RoleImages& img, JobResult& result);

}  // namespace job
}  // namespace zdenoise
