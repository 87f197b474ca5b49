// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// One strip of a job (job.cpp's plan decided it): its rows read, the
// filter run, the alpha and the light groups denoised, the output rows
// written.

#pragma once

#include <vector>

#include <zdenoise/zdenoise.h>

#include "input_files.h"
#include "job_types.h"
#include "strip_plan.h"

namespace zdenoise {
namespace job {

/// Read, denoise and write strip `s` of the plan `p`; its statistics (and
/// each layer's) are added to `result` and `layer_stats`.
void
run_strip(const Job& j, Plan& p, InputFiles& files, int s,
          JobResult& result, std::vector<FilterStats>& layer_stats);

}  // namespace job
}  // namespace zdenoise
