// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// resolve_colour() (colour_plan.h).

#include "colour_plan.h"

#include <cstdlib>

#include "failure.h"

namespace zdenoise {
namespace job {

bool
resolve_colour(const Job& j, InputFiles& files, colour::ColourConfig& config,
               colour::JobSpaces& spaces, std::vector<std::string>& log)
{
    std::string err;
    // Layers may come without an albedo of the beauty: then the input's.
    const InputArg& albedo = j.albedo.given ? j.albedo : j.in;
    if (!j.colour.any_given() && !std::getenv("OCIO")
        && colour::bundled_config_path().empty()) {
        log.push_back("no colour config found: pixels filtered as they are");
        return false;
    }
    if (!config.load(j.colour.config, err)
        || !colour::resolve_job_spaces(config, j.colour,
                                       *files.header(j.in.path).first,
                                       *files.header(albedo.path).first,
                                       albedo.path == j.in.path, spaces,
                                       log, err))
        fail(err);
    return true;
}

}  // namespace job
}  // namespace zdenoise
