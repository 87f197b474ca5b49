// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// filter_decoded(): today's filter over inputs already decoded
// (decode_filter_inputs()), the stages in order:
//   build_pyramid_level()   the fit points averaged 2x2, when
//                           large radii fit on them           (5.1)
//   fit_centres()           every centre's window fitted and
//                           splatted, in blocks and phases    (5, 6, 8)
//   spread_outliers()       the outliers' light spread        (3a)
//   normalise_output()      acc / wsum, pass-through, holes   (7)
//   write_diagnostics()     the maps of FilterOptions::diagnostics

#include "decoded_filter.h"

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
#include "window_fitter.h"

namespace zdenoise {

using namespace OIIO;
using namespace detail;

namespace {

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
/// so that every pixel receives its contributions in one fixed order; none
/// once opt.cancel is set (the splats are then no result). Returns the
/// statistics of the windows centred in `counted`, summed in block order.
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
        // Cancelled: every remaining block returns at once, on every thread.
        if (cancel_requested(opt))
            return;
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
detail::finish_filtered_light(ImageBuf& dst, const ImageBuf& quotient,
                              const FilterInputs& in, const FilterOptions& opt,
                              ROI roi, const ROI& counted, int nthreads,
                              FilterStats& totals, std::vector<double>&& acc,
                              std::vector<double>&& wsum)
{
    Splats splats(size_t(roi.width()) * size_t(roi.height()), false, false);
    splats.acc  = std::move(acc);
    splats.wsum = std::move(wsum);
    spread_outliers(in, opt, roi, splats.spread, nthreads);
    if (cancel_requested(opt))
        return false;
    return normalise_output(dst, quotient, in, opt, splats, roi, counted,
                            nthreads, totals);
}


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
    if (cancel_requested(opt))
        return false;
    spread_outliers(in, opt, roi, splats.spread, nthreads);
    if (cancel_requested(opt))
        return false;
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


}  // namespace zdenoise
