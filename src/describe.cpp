// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// describe(): the filter parameters as one line of text.

#include <zdenoise/zdenoise.h>

#include <OpenImageIO/strutil.h>

namespace zdenoise {

std::string
describe(const FilterOptions& o)
{
    return OIIO::Strutil::fmt::format(
        "rmin={} rmax={} eta={} edge-k={} tau-min={} value-k={} "
        "value-noise={} sigma-good={} albedo-eps={} depth-tol={} normal-cut={} "
        "normal-power={} quadrant-power={} stride={} stride-edges={} "
        "radius-growth={} pyramid={} outlier-spread={} select={} "
        "energy-radius={} core={} box-radius={}",
        o.r_min, o.r_max, o.eta_target, o.edge_k, o.tau_min, o.value_k,
        o.value_noise, o.sigma_good, o.albedo_eps, o.depth_tolerance, o.normal_cut,
        o.normal_power, o.quadrant_power, o.centre_stride, o.stride_edges,
        o.radius_growth, o.pyramid_radius, o.outlier_spread, o.select,
        o.energy_radius, o.core, o.box_radius);
}

}  // namespace zdenoise
