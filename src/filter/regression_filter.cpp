// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// regression_filter(): the adaptive-radius five-plane regression with
// splatting (docs/FILTER.md sections 2-8), the public entry point. It
// checks its arguments and filters the output in tiles; each tile runs
// the stages in src/filter/ in order:
//   decode_filter_inputs()  pixel classes, guides, noise     (sections 2-4;
//                           decode_inputs.cpp)
//   filter_decoded()        the windows fitted and splatted,
//                           the output normalised (5-8;
//                           decoded_filter.cpp)
// With select = 1 it hands the tile to selected_regression_filter()
// (selected_filter.cpp), whose candidate 0 is filter_decoded() too.

#include <zdenoise/zdenoise.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <OpenImageIO/imagebufalgo_util.h>

#include "box_core.h"
#include "centre_blocks.h"
#include "decode_inputs.h"
#include "filter_inputs.h"
#include "checks.h"
#include "internal.h"
#include "decoded_filter.h"
#include "energy_correction.h"
#include "selected_filter.h"

namespace zdenoise {

using namespace OIIO;
using namespace detail;

namespace {

bool
check_options(ImageBuf& dst, const FilterOptions& o)
{
    auto bad = [&](const char* name, double value, const char* need) {
        dst.errorfmt("regression_filter: option {} = {} is invalid: {}", name,
                     value, need);
        return false;
    };
    if (o.r_min < 1)
        return bad("r_min", o.r_min, "needs >= 1");
    if (o.r_max < o.r_min || o.r_max > 256)
        return bad("r_max", o.r_max, "needs r_min <= r_max <= 256");
    auto finite_nonneg = [](float v) { return std::isfinite(v) && v >= 0.0f; };
    if (!finite_nonneg(o.eta_target))
        return bad("eta_target", o.eta_target, "needs a finite number >= 0");
    if (!finite_nonneg(o.edge_k))
        return bad("edge_k", o.edge_k, "needs a finite number >= 0");
    if (!finite_nonneg(o.tau_min))
        return bad("tau_min", o.tau_min, "needs a finite number >= 0");
    if (!finite_nonneg(o.value_k))
        return bad("value_k", o.value_k, "needs a finite number >= 0");
    if (!(o.sigma_good >= 0.0f))
        return bad("sigma_good", o.sigma_good, "needs a number >= 0");
    if (!(o.albedo_eps > 0.0f) || !std::isfinite(o.albedo_eps))
        return bad("albedo_eps", o.albedo_eps, "needs a finite number > 0");
    if (!finite_nonneg(o.depth_tolerance))
        return bad("depth_tolerance", o.depth_tolerance,
                   "needs a finite number >= 0");
    if (!(o.normal_cut >= -1.0f && o.normal_cut < 1.0f))
        return bad("normal_cut", o.normal_cut, "needs -1 <= normal_cut < 1");
    if (!(o.normal_power > 0.0f) || !std::isfinite(o.normal_power))
        return bad("normal_power", o.normal_power, "needs a finite number > 0");
    if (!(o.radius_growth >= 1.0f && o.radius_growth <= 4.0f))
        return bad("radius_growth", o.radius_growth, "needs 1 <= radius_growth <= 4");
    if (o.pyramid_radius != 0 && o.pyramid_radius < 4)
        return bad("pyramid_radius", o.pyramid_radius,
                   "needs 0 (off) or a radius >= 4");
    if (o.centre_stride < 1 || o.centre_stride > 64)
        return bad("centre_stride", o.centre_stride,
                   "needs 1 <= centre_stride <= 64");
    if (o.stride_edges < 0 || o.stride_edges > 2)
        return bad("stride_edges", o.stride_edges, "needs 0, 1 or 2");
    if (o.value_noise != 0 && o.value_noise != 1)
        return bad("value_noise", o.value_noise, "needs 0 or 1");
    if (o.outlier_spread != 0 && o.outlier_spread != 1)
        return bad("outlier_spread", o.outlier_spread, "needs 0 or 1");
    if (o.select != 0 && o.select != 1)
        return bad("select", o.select, "needs 0 or 1");
    if (o.directional_noise != 0 && o.directional_noise != 1)
        return bad("directional_noise", o.directional_noise, "needs 0 or 1");
    if (o.energy_radius < 0 || o.energy_radius > 64)
        return bad("energy_radius", o.energy_radius, "needs 0 <= energy_radius <= 64");
    if (o.core != 0 && o.core != 1)
        return bad("core", o.core, "needs 0 (windows) or 1 (box)");
    if (o.box_radius < 1 || o.box_radius > 128)
        return bad("box_radius", o.box_radius, "needs 1 <= box_radius <= 128");
    if (!finite_nonneg(o.quadrant_power))
        return bad("quadrant_power", o.quadrant_power,
                   "needs a finite number >= 0");
    return true;
}


}  // namespace


namespace {

/// Filter the output pixels `roi` (sections 2-7, or with core 1 the box
/// core of section 15), reading the inputs over roi plus the halo
/// everything depends on. `opt.frame` is the image's data window. `hat`,
/// if not null, receives the hat diagonal (core 0). The statistics
/// count the windows and pixels in `counted`.
bool
filter_tile(ImageBuf& dst, const ImageBuf& quotient, const ImageBuf& albedo,
            const Guides& guides, const FilterOptions& opt, ROI roi,
            const ROI& counted, int nthreads, FilterStats& totals, ImageBuf* hat)
{
    const ROI region = halo_region(roi, opt.frame, filter_halo(opt));
    FilterInputs in;
    return decode_filter_inputs(in, dst, quotient, albedo, guides, opt, region,
                                nthreads)
           && (opt.core ? box_filter_decoded(dst, quotient, in, opt, roi,
                                             counted, nthreads, totals)
                        : filter_decoded(dst, quotient, in, opt, roi, counted,
                                         nthreads, totals, hat));
}


/// The filter over `area` (select or not) into dst, in tiles: they bound
/// the working memory whatever the frame size, and the result is exactly
/// the whole-image one (section 8), so the tile size is not a parameter.
/// `progress`, if given, hears the fraction of the area done. The
/// statistics count the windows and pixels in `counted`.
bool
filter_tiles(ImageBuf& dst, const ImageBuf& quotient, const ImageBuf& albedo,
             const Guides& guides, FilterOptions tile_opt, ROI area,
             const ROI& counted, int nthreads, FilterStats& totals, ImageBuf* hat,
             const std::function<void(float)>& progress)
{
    const int side = tile_opt.core ? kBoxTile
                     : tile_opt.select ? kSelectionTile : kFilterTile;
    const int ntx  = (area.width() + side - 1) / side;
    const int nty  = (area.height() + side - 1) / side;
    const int ntiles = ntx * nty;
    for (int t = 0; t < ntiles; ++t) {
        ROI tile(area.xbegin + (t % ntx) * side, 0, area.ybegin + (t / ntx) * side, 0,
                 area.zbegin, area.zend, area.chbegin, area.chend);
        tile.xend = std::min(tile.xbegin + side, area.xend);
        tile.yend = std::min(tile.ybegin + side, area.yend);
        // Each tile counts its own centres (its filter fits those around it too).
        const ROI tile_counted = roi_intersection(tile, counted);
        if (progress)
            tile_opt.progress = [&](float f) {
                progress((float(t) + f) / float(ntiles));
            };
        const bool done
            = tile_opt.select && !tile_opt.core
                  ? selected_regression_filter(dst, quotient, albedo, guides,
                                               tile_opt, tile, tile_counted,
                                               nthreads, totals)
                  : filter_tile(dst, quotient, albedo, guides, tile_opt, tile,
                                tile_counted, nthreads, totals, hat);
        if (!done || cancel_requested(tile_opt))
            return false;
    }
    return true;
}


/// The filter and section 7b's correction over roi. The correction reads
/// the filtered light over `area`, roi and the band of energy_reach()
/// around it: one run over the area, its statistics counted for roi alone;
/// where maps are asked for (they are roi's), roi first into dst and the
/// band after.
bool
filter_keeping_energy(ImageBuf& dst, const ImageBuf& quotient,
                      const ImageBuf& albedo, const Guides& guides,
                      FilterOptions opt, int radius, ROI roi, int nthreads,
                      FilterStats& totals, ImageBuf* hat,
                      const std::function<void(float)>& progress)
{
    const ROI xy = halo_region(roi, opt.frame, energy_reach(radius));
    // All the quotient's channels: the filter writes them all.
    const ROI area(xy.xbegin, xy.xend, xy.ybegin, xy.yend, roi.zbegin, roi.zend,
                   0, quotient.nchannels());
    ImageBuf around(ImageSpec(area, TypeFloat));
    auto fail = [&] {
        if (around.has_error())
            dst.errorfmt("{}", around.geterror());
        return false;
    };
    if (!opt.diagnostics && !hat) {
        if (!filter_tiles(around, quotient, albedo, guides, opt, area, roi,
                          nthreads, totals, nullptr, progress))
            return fail();
        const std::vector<float> filtered = read_channels(around, roi, roi.chbegin,
                                                          roi.chend);
        if (!dst.set_pixels(roi, TypeFloat, filtered.data()))
            return false;
    } else {
        if (!filter_tiles(dst, quotient, albedo, guides, opt, roi, roi, nthreads,
                          totals, hat, progress))
            return false;
        opt.diagnostics = nullptr;
        const ROI bands[4] = {
            ROI(area.xbegin, area.xend, area.ybegin, roi.ybegin, roi.zbegin, roi.zend,
                roi.chbegin, roi.chend),
            ROI(area.xbegin, area.xend, roi.yend, area.yend, roi.zbegin, roi.zend,
                roi.chbegin, roi.chend),
            ROI(area.xbegin, roi.xbegin, roi.ybegin, roi.yend, roi.zbegin, roi.zend,
                roi.chbegin, roi.chend),
            ROI(roi.xend, area.xend, roi.ybegin, roi.yend, roi.zbegin, roi.zend,
                roi.chbegin, roi.chend),
        };
        FilterStats band_stats;  // the statistics stay roi's
        for (const ROI& band : bands)
            if (band.width() > 0 && band.height() > 0
                && !filter_tiles(around, quotient, albedo, guides, opt, band, band,
                                 nthreads, band_stats, nullptr, nullptr))
                return fail();
        const std::vector<float> filtered = read_channels(dst, roi, roi.chbegin,
                                                          roi.chend);
        if (!around.set_pixels(roi, TypeFloat, filtered.data()))
            return fail();
    }
    correct_energy(dst, around, quotient, albedo, opt.albedo_eps, radius, roi,
                   xy, nthreads);
    return true;
}

}  // namespace


int
filter_halo(const FilterOptions& options)
{
    if (options.energy_radius > 0) {
        FilterOptions inner = options;
        inner.energy_radius = 0;
        return filter_halo(inner) + energy_reach(options.energy_radius);
    }
    if (options.core)
        return detail::box_core_halo(options);
    if (options.select) {
        FilterOptions base = options;
        base.select        = 0;
        return detail::selected_filter_halo(base);
    }
    // Everything an output pixel depends on lies within 2*r_max (centres up
    // to r_max away, their windows r_max further) plus the footprint of the
    // noise estimate and the outlier test: the smoothing's 3x3 (1) of the
    // outlier test's 5x5 (2) of the raw variance (3x3 residual, 5x5
    // median: 3), 6 in all. With a stride, the lattice points deciding a
    // centre lie up to stride - 1 further.
    return 2 * std::max(options.r_max, 0) + 6
           + effective_stride(options) - 1;
}


bool
regression_filter(ImageBuf& dst, const ImageBuf& quotient,
                  const ImageBuf& albedo, const Guides& guides,
                  const FilterOptions& options, FilterStats* stats, ROI roi,
                  int nthreads)
{
    const char* opname = "regression_filter";
    const bool dst_was_given = dst.initialized();
    if (cancel_requested(options))
        return cancelled(dst, dst_was_given, roi, nthreads);
    if (!prepare_dst(dst, quotient, roi, opname)
        || !check_input(dst, quotient, opname, "quotient", roi, 3)
        || !check_options(dst, options))
        return false;
    // The inputs must hold what the output depends on: with the frame given,
    // roi and its halo; else their data windows are the frame.
    FilterOptions tile_opt = options;
    if (!tile_opt.frame.defined())
        tile_opt.frame = quotient.roi();
    if (!check_frame(dst, opname, roi, tile_opt.frame))
        return false;
    const ROI need = options.frame.defined()
                         ? halo_region(roi, options.frame, filter_halo(options))
                         : quotient.roi();
    if (!check_input(dst, quotient, opname, "quotient", need, 3)
        || !check_input(dst, albedo, opname, "albedo", need, 3))
        return false;
    if (!check_guides(dst, guides, opname, need))
        return false;
    if (!guides.variance && (!guides.half_a != !guides.half_b)) {
        dst.errorfmt("{}: half buffers need both A and B", opname);
        return false;
    }
    if (options.diagnostics
        && !detail::prepare_diagnostics(dst, *options.diagnostics, roi,
                                        tile_opt.frame, opname))
        return false;
    ImageBuf* hat = options.hat_diagonal;
    if (hat && options.core) {
        dst.errorfmt("{}: option hat_diagonal is invalid with core 1: the box "
                     "core's choice has no hat diagonal of its own", opname);
        return false;
    }
    if (hat && options.select) {
        dst.errorfmt("{}: option hat_diagonal is invalid with select 1: the "
                     "selection's output has no hat diagonal of its own",
                     opname);
        return false;
    }
    if (hat
        && !detail::prepare_result(dst, *hat, roi, tile_opt.frame, 1, opname,
                                    "hat diagonal"))
        return false;
    FilterStats totals;
    tile_opt.energy_radius = 0;  // the tiles' filter; the correction after
    const bool done
        = options.energy_radius > 0
              ? filter_keeping_energy(dst, quotient, albedo, guides, tile_opt,
                                      options.energy_radius, roi, nthreads,
                                      totals, hat, options.progress)
              : filter_tiles(dst, quotient, albedo, guides, tile_opt, roi, roi,
                             nthreads, totals, hat, options.progress);
    // A stage that saw the flag stops with no message of its own.
    if (cancel_requested(options))
        return cancelled(dst, dst_was_given, roi, nthreads);
    if (!done)
        return false;
    if (stats)
        *stats = totals;
    return true;
}


ImageBuf
regression_filter(const ImageBuf& quotient, const ImageBuf& albedo,
                  const Guides& guides, const FilterOptions& options,
                  FilterStats* stats, ROI roi, int nthreads)
{
    return detail::returned_image("regression_filter", [&](ImageBuf& result) {
        return regression_filter(result, quotient, albedo, guides, options, stats, roi, nthreads);
    });
}

}  // namespace zdenoise
