// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "option_names.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace zdenoise {
namespace job {

const std::vector<FilterOptionName>&
filter_option_names()
{
    static const std::vector<FilterOptionName> names = {
        { "rmin", nullptr, &FilterOptions::r_min },
        { "rmax", nullptr, &FilterOptions::r_max },
        { "eta", &FilterOptions::eta_target },
        { "edge-k", &FilterOptions::edge_k },
        { "tau-min", &FilterOptions::tau_min },
        { "value-k", &FilterOptions::value_k },
        { "sigma-good", &FilterOptions::sigma_good },
        { "albedo-eps", &FilterOptions::albedo_eps },
        { "depth-tol", &FilterOptions::depth_tolerance },
        { "normal-cut", &FilterOptions::normal_cut },
        { "normal-power", &FilterOptions::normal_power },
        { "quadrant-power", &FilterOptions::quadrant_power },
        { "stride", nullptr, &FilterOptions::centre_stride },
        { "stride-edges", nullptr, &FilterOptions::stride_edges },
        { "radius-growth", &FilterOptions::radius_growth },
    };
    return names;
}


bool
apply_preset(const std::string& preset, FilterOptions& options)
{
    FilterOptions parameters;
    if (preset == "spec")
        parameters = FilterOptions::algorithm_defaults();
    else if (preset != "tuned")
        return false;
    parameters.progress = std::move(options.progress);
    options             = std::move(parameters);
    return true;
}


const char*
preset_names()
{
    return "tuned, spec";
}


bool
parse_real(const std::string& text, double& value)
{
    const char* s = text.c_str();
    char* end     = nullptr;
    errno         = 0;
    double v      = std::strtod(s, &end);
    if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
        return false;
    value = v;
    return true;
}


bool
parse_whole(const std::string& text, int& value)
{
    double v = 0.0;
    if (!parse_real(text, v) || v != std::floor(v) || std::fabs(v) > 1e6)
        return false;
    value = int(v);
    return true;
}

}  // namespace job
}  // namespace zdenoise
