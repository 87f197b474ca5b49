// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The job's colour spaces (docs/COLOUR.md): which OCIO config and which
// spaces the radiance and the albedo are filtered in. A step of plan()
// (job.cpp).

#pragma once

#include <string>
#include <vector>

#include "input_files.h"
#include "job_types.h"

namespace zdenoise {
namespace job {

/// The job's colour spaces into `config` and `spaces`, or false when no
/// config is found and the user asked for nothing (the OIIO plugin outside
/// an installation): then the pixels are filtered as they are. What it
/// decided goes to `log`; a bad space or config fails the job.
bool resolve_colour(const Job& j, InputFiles& files, colour::ColourConfig& config,
                    colour::JobSpaces& spaces, std::vector<std::string>& log);

}  // namespace job
}  // namespace zdenoise
