// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "shared.h"

#include <climits>
#include <cstdlib>
#include <cstring>

#include <OpenImageIO/strutil.h>

namespace zdenoise {
namespace cli {

bool
same_file(const std::string& a, const std::string& b)
{
    char ra[PATH_MAX], rb[PATH_MAX];
    if (!realpath(a.c_str(), ra) || !realpath(b.c_str(), rb))
        return false;
    return std::strcmp(ra, rb) == 0;
}


std::string
output_is_input(const job::Job& job, const std::string& output, bool force)
{
    if (!force)
        for (const std::string& in : job::input_paths(job))
            if (same_file(in, output))
                return OIIO::Strutil::fmt::format(
                    "the output '{}' is also an input; use --force to "
                    "replace it",
                    output);
    return "";
}

}  // namespace cli
}  // namespace zdenoise
