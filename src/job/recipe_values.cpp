// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "recipe_values.h"

#include <cmath>
#include <limits>

#include <OpenImageIO/strutil.h>

#include "failure.h"
#include "recipe_rules.h"

namespace zdenoise {
namespace job {
namespace recipe_values {

using OIIO::Strutil::fmt::format;
using json = nlohmann::json;

[[noreturn]] void
fail_escaped(const std::string& message)
{
    fail(control_escaped(message));
}


std::string
shown(const json& value)
{
    std::string s = value.dump();
    return s.size() > 40 ? s.substr(0, 37) + "..." : s;
}


double
parse_number(const std::string& key, const json& value)
{
    if (!value.is_number())
        fail_escaped(format("\"{}\" must be a number, not {}", key, shown(value)));
    return value.get<double>();
}

float
parse_float(const std::string& key, const json& value)
{
    const double v = parse_number(key, value);
    if (!(std::fabs(v) <= double(std::numeric_limits<float>::max())))
        fail_escaped(format("\"{}\" is out of range: {}", key, shown(value)));
    return float(v);
}

int
parse_whole_number(const std::string& key, const json& value)
{
    double v = parse_number(key, value);
    if (v != std::floor(v) || std::fabs(v) > 1e6)
        fail_escaped(format("\"{}\" must be a whole number, not {}", key,
                    shown(value)));
    return int(v);
}


std::string
parse_string(const std::string& key, const json& value, bool name)
{
    if (!value.is_string() || (name && value.get<std::string>().empty()))
        fail_escaped(format(name ? "\"{}\" must be a name in a string, not {}"
                         : "\"{}\" must be a string, not {}",
                    key, shown(value)));
    return value.get<std::string>();
}


}  // namespace recipe_values
}  // namespace job
}  // namespace zdenoise
