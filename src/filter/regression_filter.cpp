// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// regression_filter(): the adaptive-radius five-plane regression with
// splatting (docs/FILTER.md sections 2-8), the public entry point. It
// checks its arguments and filters the output in tiles; each tile runs
// the stages in src/filter/ in order:
//   decode_filter_inputs()  pixel classes, guides, noise     (sections 2-4)
//   build_pyramid_level()   the fit points averaged 2x2, when
//                           large radii fit on them           (5.1)
//   fit_centres()           every centre's window fitted and
//                           splatted, in blocks and phases    (5, 6, 8)
//   normalise_output()      acc / wsum, pass-through, holes   (7)
//   write_diagnostics()     the maps of FilterOptions::diagnostics

#include <zdenoise/zdenoise.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>

#include <OpenImageIO/imagebufalgo_util.h>

#include "centre_blocks.h"
#include "filter_inputs.h"
#include "hole_fill.h"
#include "checks.h"
#include "internal.h"
#include "outliers.h"
#include "regression_filter.h"
#include "selected_filter.h"
#include "window_fitter.h"

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
    if (o.stride_edges != 0 && o.stride_edges != 1)
        return bad("stride_edges", o.stride_edges, "needs 0 or 1");
    if (o.value_noise != 0 && o.value_noise != 1)
        return bad("value_noise", o.value_noise, "needs 0 or 1");
    if (o.outlier_spread != 0 && o.outlier_spread != 1)
        return bad("outlier_spread", o.outlier_spread, "needs 0 or 1");
    if (o.select != 0 && o.select != 1)
        return bad("select", o.select, "needs 0 or 1");
    if (!finite_nonneg(o.quadrant_power))
        return bad("quadrant_power", o.quadrant_power,
                   "needs a finite number >= 0");
    return true;
}


/// What the centres' splats add up at each output pixel: sum s A_c and
/// sum s (section 6).
struct Splats {
    std::vector<double> acc, wsum;
    std::vector<double> spread;  ///< outliers' spread light, z (section 3a)
    /// kDiagnosticSums a pixel when diagnostics are asked for, else empty.
    std::vector<double> diagnostics;
    /// kHatSums a pixel when the hat diagonal is asked for, else empty.
    std::vector<double> hat;
    Splats(size_t npix, bool with_diagnostics, bool with_hat)
        : acc(3 * npix, 0.0)
        , wsum(npix, 0.0)
        , spread(3 * npix, 0.0)
        , diagnostics(with_diagnostics ? kDiagnosticSums * npix : 0, 0.0)
        , hat(with_hat ? kHatSums * npix : 0, 0.0)
    {
    }
};

/// Fit and splat every centre the output pixels `roi` depend on (sections
/// 5, 6 and 8): the blocks of one phase in parallel, the phases in order,
/// so that every pixel receives its contributions in one fixed order.
/// Returns the statistics of the windows centred in `counted`, summed in
/// block order.
FilterStats
fit_centres(const FilterInputs& in, const FilterOptions& opt, const ROI& roi,
            const ROI& counted, int nthreads, Splats& splats)
{
    // Level 1 of the pyramid when some trial radius fits on it (5.1).
    PyramidLevel pyramid;
    const bool on_pyramid = opt.pyramid_radius > 0
                            && opt.pyramid_radius <= opt.r_max;
    if (on_pyramid)
        build_pyramid_level(pyramid, in, opt, nthreads);
    const CentreBlocks blocks(opt, opt.frame, roi);
    const int nblocks = blocks.count();
    std::vector<FilterStats> block_stats(static_cast<size_t>(nblocks));
    std::atomic<int64_t> blocks_done { 0 };
    std::mutex progress_mutex;
    auto run_block = [&](int b) {
        WindowFitter fitter(in, opt, roi, splats.acc, splats.wsum,
                            opt.diagnostics ? &splats.diagnostics : nullptr,
                            splats.hat.empty() ? nullptr : &splats.hat,
                            on_pyramid ? &pyramid : nullptr);
        fit_block(blocks, b, in, opt, counted, fitter, block_stats[size_t(b)]);
        const int64_t done = ++blocks_done;
        if (opt.progress) {
            std::lock_guard<std::mutex> lock(progress_mutex);
            opt.progress(float(done) / float(nblocks));
        }
    };
    for (int phase = 0; phase < 4; ++phase) {
        std::vector<int> of_phase;
        for (int b = 0; b < nblocks; ++b)
            if (blocks.phase(b) == phase)
                of_phase.push_back(b);
        parallel_for(int64_t(0), int64_t(of_phase.size()),
                     [&](int64_t j) { run_block(of_phase[size_t(j)]); },
                     paropt_any_length(nthreads));
    }
    FilterStats total;
    for (const FilterStats& s : block_stats)
        total.merge(s);
    return total;
}

/// The output pixels `roi` into dst (section 7): RGB from acc / wsum where
/// a channel receives and something was splatted, else passed through (0
/// if not finite); other channels copied from the quotient. Counts the
/// output, passed-through and non-finite pixels in `counted` into st.
bool
normalise_output(ImageBuf& dst, const ImageBuf& quotient,
                 const FilterInputs& in, const FilterOptions& opt,
                 const Splats& splats, ROI roi, const ROI& counted,
                 int nthreads, FilterStats& st)
{
    const size_t npix_out = size_t(roi.width()) * size_t(roi.height());
    ROI all_ch = roi;
    all_ch.chbegin = 0;
    all_ch.chend   = quotient.nchannels();
    const int nch  = all_ch.nchannels();
    std::vector<float> out(npix_out * size_t(nch));
    quotient.get_pixels(all_ch, TypeFloat, out.data());
    std::atomic<int64_t> passthrough { 0 }, nonfinite { 0 };
    parallel_for(int64_t(roi.ybegin), int64_t(roi.yend), [&](int64_t y) {
        int64_t pt = 0, nf = 0;
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t i   = in.index(x, int(y));
            const size_t o   = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            const uint8_t cl = in.cls[i];
            bool passed      = false;
            float hole[3];
            int hole_found   = -1;  ///< not looked for yet; then 0 or 1
            for (int ch = 0; ch < 3; ++ch) {
                float& v = out[o * nch + ch];
                // A splat of s A can overflow the float where A is at its
                // bound (section 6): such a sum is no value; pass through.
                const double filtered =
                    (cl & (kReceiveR << ch)) && splats.wsum[o] > 0.0
                        ? splats.acc[3 * o + ch] / splats.wsum[o] + splats.spread[3 * o + ch]
                        : std::numeric_limits<double>::quiet_NaN();
                if (std::isfinite(filtered)) {
                    v = saturated_float(filtered);
                } else {
                    passed = true;
                    // A hole: no window reached a non-finite value.
                    if (!std::isfinite(v) && (cl & (kReceiveR << ch)) && hole_found < 0)
                        hole_found = hole_light(in, opt, x, int(y), hole);
                    if (!std::isfinite(v))
                        v = (cl & (kReceiveR << ch)) && hole_found > 0 ? hole[ch] : 0.0f;
                }
            }
            const bool c = counted.contains(x, int(y));
            pt += c && passed;
            nf += c && (cl & kNonFinite) != 0;
        }
        passthrough += pt;
        nonfinite += nf;
    }, paropt_any_length(nthreads));
    if (!dst.set_pixels(all_ch, TypeFloat, out.data())) {
        if (!dst.has_error())
            dst.errorfmt("regression_filter: could not store the result");
        return false;
    }
    st.pixels += int64_t(roi_intersection(roi, counted).npixels());
    st.passthrough_pixels += passthrough;
    st.nonfinite_pixels += nonfinite;
    return true;
}

/// The maps of FilterOptions::diagnostics over `roi` (zdenoise.h,
/// diagnostic_channels()) from the splats' sums and the noise estimate.
bool
write_diagnostics(ImageBuf& dst, const FilterInputs& in, const Splats& splats,
                  ROI roi, int nthreads)
{
    const size_t npix = size_t(roi.width()) * size_t(roi.height());
    std::vector<float> maps(4 * npix, 0.0f);
    parallel_for(int64_t(roi.ybegin), int64_t(roi.yend), [&](int64_t y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t o = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            const double* d = &splats.diagnostics[kDiagnosticSums * o];
            float* m        = &maps[4 * o];
            const size_t i  = in.index(x, int(y));
            if (in.cls[i] & kFitPoint)
                m[2] = in.sigma[i];
            const double w = splats.wsum[o];
            if (!(w > 0.0))
                continue;
            m[0] = float(d[kSumRadius] / w);
            m[3] = float(d[kSumEta] / w);
            // The reason that carries most of the splat weight; ties go
            // to the first, so the map does not depend on rounding order.
            StopCode code = StopCode::Quality;
            double most   = d[kSumQuality];
            if (d[kSumSize] > most) {
                code = StopCode::Size;
                most = d[kSumSize];
            }
            if (d[kSumEdge] > most)
                code = StopCode::Edge;
            m[1] = float(int(code));
        }
    }, paropt_any_length(nthreads));
    ROI maps_roi    = roi;
    maps_roi.chbegin = 0;
    maps_roi.chend   = 4;
    return dst.set_pixels(maps_roi, TypeFloat, maps.data());
}

/// The hat diagonal D = d out_l / d z_l over `roi` (docs/SELECTION.md 2.5,
/// 2.6) from the splats' sums, 1 where nothing was splatted.
bool
write_hat_diagonal(ImageBuf& dst, const Splats& splats, ROI roi, int nthreads)
{
    const size_t npix = size_t(roi.width()) * size_t(roi.height());
    std::vector<float> d(npix, 1.0f);
    parallel_for(int64_t(0), int64_t(npix), [&](int64_t o) {
        const double w = splats.wsum[size_t(o)];
        if (!(w > 0.0))
            return;
        const double* a = &splats.acc[3 * size_t(o)];
        const double out_l = (double(kLumaWeights[0]) * a[0]
                              + double(kLumaWeights[1]) * a[1]
                              + double(kLumaWeights[2]) * a[2]) / w;
        const double* h = &splats.hat[kHatSums * size_t(o)];
        d[size_t(o)] = float((h[kHatOwn] - h[kHatValueA] + out_l * h[kHatValue]) / w);
    }, paropt_any_length(nthreads));
    roi.chbegin = 0;
    roi.chend   = 1;
    return dst.set_pixels(roi, TypeFloat, d.data());
}

}  // namespace


bool
detail::filter_decoded(ImageBuf& dst, const ImageBuf& quotient,
                       const FilterInputs& in, const FilterOptions& opt,
                       ROI roi, const ROI& counted, int nthreads,
                       FilterStats& totals, ImageBuf* hat,
                       std::vector<double>* spread_light)
{
    Splats splats(size_t(roi.width()) * size_t(roi.height()),
                  opt.diagnostics != nullptr, hat != nullptr);
    FilterStats tile = fit_centres(in, opt, roi, counted, nthreads, splats);
    spread_outliers(in, opt, roi, splats.spread, nthreads);
    if (!normalise_output(dst, quotient, in, opt, splats, roi, counted, nthreads,
                          tile))
        return false;
    if (opt.diagnostics
        && !write_diagnostics(*opt.diagnostics, in, splats, roi, nthreads)) {
        dst.errorfmt("regression_filter: could not store the diagnostics: {}",
                     opt.diagnostics->geterror());
        return false;
    }
    if (hat && !write_hat_diagonal(*hat, splats, roi, nthreads)) {
        dst.errorfmt("regression_filter: could not store the hat diagonal: {}",
                     hat->geterror());
        return false;
    }
    totals.merge(tile);
    if (spread_light)
        *spread_light = std::move(splats.spread);
    return true;
}

namespace {

/// Filter the output pixels `roi` (sections 2-7), reading the inputs over
/// roi plus the halo everything depends on. `opt.frame` is the image's data
/// window. `hat`, if not null, receives the hat diagonal.
bool
filter_tile(ImageBuf& dst, const ImageBuf& quotient, const ImageBuf& albedo,
            const Guides& guides, const FilterOptions& opt, ROI roi,
            int nthreads, FilterStats& totals, ImageBuf* hat)
{
    const ROI region = halo_region(roi, opt.frame, filter_halo(opt));
    FilterInputs in;
    return decode_filter_inputs(in, dst, quotient, albedo, guides, opt, region,
                                nthreads)
           && filter_decoded(dst, quotient, in, opt, roi, roi, nthreads,
                             totals, hat);
}

}  // namespace


int
filter_halo(const FilterOptions& options)
{
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
    // Tiles bound the working memory whatever the frame size; the result
    // is exactly the whole-image one (section 8), so the tile size is not
    // a parameter.
    const int side = options.select ? detail::kSelectionTile : detail::kFilterTile;
    const int ntx  = (roi.width() + side - 1) / side;
    const int nty  = (roi.height() + side - 1) / side;
    const int ntiles = ntx * nty;
    FilterStats totals;
    for (int t = 0; t < ntiles; ++t) {
        ROI tile(roi.xbegin + (t % ntx) * side, 0, roi.ybegin + (t / ntx) * side, 0,
                 roi.zbegin, roi.zend, roi.chbegin, roi.chend);
        tile.xend = std::min(tile.xbegin + side, roi.xend);
        tile.yend = std::min(tile.ybegin + side, roi.yend);
        if (options.progress)
            tile_opt.progress = [&](float f) {
                options.progress((float(t) + f) / float(ntiles));
            };
        const bool done
            = options.select
                  ? detail::selected_regression_filter(dst, quotient, albedo, guides,
                                                       tile_opt, tile, nthreads, totals)
                  : filter_tile(dst, quotient, albedo, guides, tile_opt, tile,
                                nthreads, totals, hat);
        if (!done)
            return false;
    }
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
