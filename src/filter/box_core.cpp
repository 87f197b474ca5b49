// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// box_filter_decoded(): the box core (docs/FILTER.md section 15): the
// input and, for each radius 1, 2, 4, ... box_radius, box_candidate()
// (box_regression.cpp); then pooled_risks(): Stein's risk of each,
// pooled 11x11, and choose_candidates(): per pixel the least.

#include "box_core.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "box_regression.h"
#include "box_sums.h"
#include "decoded_filter.h"
#include "filter_inputs.h"
#include "internal.h"

namespace zdenoise {
namespace detail {

using namespace OIIO;

namespace {

/// Half-size of the box over which the risks are pooled before the choice:
/// 121 pixels. A pixel's risk is mostly noise; on the public set at 16 spp
/// 11x11 chose better than 7x7 or 5x5 (bench/results/2026-12-box-core-log.md).
constexpr int kRiskRadius = 5;

/// The risk's residual z - out is clipped at this many noise deviations:
/// Monte Carlo's heavy tails (a firefly below the outlier test's
/// threshold) would otherwise decide a whole pooled box for the radius
/// that follows it (the same measurement: 3 beat 2, 4 and no clip).
constexpr double kClipSigmas = 3.0;

/// The relative-error floor of relMSE (zmetrics' 0.01 on the radiance).
constexpr double kRelFloor = 1e-2;

/// The window weight's floor on its relative residual variance: windows
/// that fit better than this are weighted alike.
constexpr double kWeightFloor = 1e-3;

/// The input as a candidate: z itself, hat diagonal 1.
BoxCandidate
input_candidate(const FilterInputs& in, const ROI& rr)
{
    BoxCandidate cand;
    cand.rgb.assign(3 * rr.npixels(), NAN);
    cand.hat.assign(rr.npixels(), 1.0f);
    for (int y = rr.ybegin; y < rr.yend; ++y)
        for (int x = rr.xbegin; x < rr.xend; ++x) {
            const size_t i = in.index(x, y);
            const size_t k = size_t(y - rr.ybegin) * size_t(rr.width())
                             + size_t(x - rr.xbegin);
            for (int c = 0; c < 3; ++c)
                cand.rgb[3 * k + c] = in.zfit[c][i];
        }
    return cand;
}

/// The weight that turns an error of the light at pixel i into its share
/// of the radiance's relMSE: a^2 / (a^2 L^2 + 0.01), with a the albedo's
/// luminance and L the pilot light.
double
relative_weight(const FilterInputs& in, size_t i, double pilot)
{
    double a = 0.0;
    for (int c = 0; c < 3; ++c) {
        const float inv = in.inv_albedo[c][i];
        a += double(kLumaWeights[c]) * (inv > 0.0f ? 1.0 / double(inv) : 1.0);
    }
    return a * a / (a * a * pilot * pilot + kRelFloor);
}

/// Stein's unbiased risk of each candidate at every fit point of rr,
/// relMSE-weighted, summed over the 11x11 around each pixel (planes: one
/// per candidate, then the count of fit points).
Planes<double>
pooled_risks(const FilterInputs& in, const std::vector<BoxCandidate>& cands,
             const ROI& rr, int pilot, int nthreads)
{
    const int nc = int(cands.size());
    Planes<double> risk(rr.width(), rr.height(), nc + 1);
    for_rows(rr, nthreads, [&](int y) {
        for (int x = rr.xbegin; x < rr.xend; ++x) {
            const size_t i = in.index(x, y);
            if (!(in.cls[i] & kFitPoint))
                continue;
            const size_t k = size_t(y - rr.ybegin) * size_t(rr.width())
                             + size_t(x - rr.xbegin);
            const double v  = std::max(double(in.vs[i]), 0.0);
            const double clip = kClipSigmas * std::sqrt(v);
            const float* pl = &cands[size_t(pilot)].rgb[3 * k];
            const double wr = relative_weight(
                in, i, std::isfinite(pl[0]) ? std::max(double(luminance(pl)), 0.0)
                                            : double(in.zl[i]));
            for (int c = 0; c < nc; ++c) {
                const float* rgb = &cands[size_t(c)].rgb[3 * k];
                const double d   = std::clamp(double(luminance(rgb)) - double(in.zl[i]),
                                              -clip, clip);
                const double sure = d * d - v + 2.0 * v * double(cands[size_t(c)].hat[k]);
                risk.plane(c)[k] = std::isfinite(sure) ? wr * sure : 1e30;
            }
            risk.plane(nc)[k] = 1.0;
        }
    });
    box_sum_planes(risk, risk, rr.xbegin - in.image.xbegin,
                   rr.ybegin - in.image.ybegin, kRiskRadius, nthreads);
    return risk;
}

/// Per output pixel the candidate of least pooled risk (ties: the first),
/// its light into acc (3 a pixel of roi) and 1 into wsum; a pixel no
/// candidate reaches keeps wsum 0 (passed through). `chosen` gets the
/// radius (0: the input).
void
choose_candidates(const std::vector<BoxCandidate>& cands, const Planes<double>& risk,
                  const ROI& rr, const ROI& roi, std::vector<double>& acc,
                  std::vector<double>& wsum, std::vector<float>& chosen,
                  int nthreads)
{
    const int nc = int(cands.size());
    for_rows(roi, nthreads, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t k = size_t(y - rr.ybegin) * size_t(rr.width())
                             + size_t(x - rr.xbegin);
            const size_t o = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            int best         = -1;
            double best_risk = std::numeric_limits<double>::infinity();
            const bool pooled = risk.plane(nc)[k] > 0.0;
            for (int c = 0; c < nc; ++c) {
                const float* rgb = &cands[size_t(c)].rgb[3 * k];
                if (!(std::isfinite(rgb[0]) && std::isfinite(rgb[1])
                      && std::isfinite(rgb[2])))
                    continue;
                // No fit point around: the widest candidate that reaches.
                const double rk = pooled ? risk.plane(c)[k] : -double(c);
                if (rk < best_risk)
                    best = c, best_risk = rk;
            }
            if (best < 0)
                continue;
            for (int ch = 0; ch < 3; ++ch)
                acc[3 * o + ch] = double(cands[size_t(best)].rgb[3 * k + ch]);
            wsum[o]   = 1.0;
            chosen[o] = float(cands[size_t(best)].radius);
        }
    });
}

/// The radius chosen as map 0 of opt.diagnostics, the noise as map 2.
bool
write_box_diagnostics(ImageBuf& maps_img, const FilterInputs& in, const ROI& roi,
                      const std::vector<float>& chosen)
{
    std::vector<float> maps(4 * roi.npixels(), 0.0f);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t o = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            const size_t i = in.index(x, y);
            maps[4 * o]     = chosen[o];
            maps[4 * o + 2] = (in.cls[i] & kFitPoint) ? in.sigma[i] : 0.0f;
        }
    ROI r = roi;
    r.chbegin = 0;
    r.chend   = 4;
    return maps_img.set_pixels(r, TypeFloat, maps.data());
}

}  // namespace


std::vector<int>
box_radii(const FilterOptions& opt)
{
    std::vector<int> radii;
    for (int r = 1; r < opt.box_radius; r *= 2)
        radii.push_back(r);
    radii.push_back(opt.box_radius);
    return radii;
}


int
box_core_halo(const FilterOptions& opt)
{
    // The largest radius's reach, the risk's pooling, and the noise
    // estimate's and outlier test's footprint (6, as the windows' filter).
    int reach = 0;
    for (int r : box_radii(opt))
        reach = std::max(reach, box_candidate_reach(r));
    return reach + kRiskRadius + 6;
}


bool
box_filter_decoded(ImageBuf& dst, const ImageBuf& quotient,
                   const FilterInputs& in, const FilterOptions& opt, ROI roi,
                   const ROI& counted, int nthreads, FilterStats& totals)
{
    const ROI rr = roi_intersection(halo_region(roi, in.image, kRiskRadius),
                                    in.region);
    const std::vector<int> radii = box_radii(opt);
    std::vector<BoxCandidate> cands { input_candidate(in, rr) };
    for (size_t j = 0; j < radii.size(); ++j) {
        cands.emplace_back();
        box_candidate(in, opt, rr, radii[j], cands.back(), nthreads);
        if (cancel_requested(opt))
            return false;
        if (opt.progress)
            opt.progress(float(j + 1) / float(radii.size() + 1));
    }
    // The pilot light of the relative weights: radius 8 or the nearest.
    int pilot = 1;
    for (size_t j = 0; j < radii.size(); ++j)
        if (radii[j] <= 8)
            pilot = int(j) + 1;
    const Planes<double> risk = pooled_risks(in, cands, rr, pilot, nthreads);
    std::vector<double> acc(3 * roi.npixels(), 0.0), wsum(roi.npixels(), 0.0);
    std::vector<float> chosen(roi.npixels(), 0.0f);
    choose_candidates(cands, risk, rr, roi, acc, wsum, chosen, nthreads);
    if (cancel_requested(opt))
        return false;
    if (opt.diagnostics
        && !write_box_diagnostics(*opt.diagnostics, in, roi, chosen)) {
        dst.errorfmt("regression_filter: could not store the diagnostics: {}",
                     opt.diagnostics->geterror());
        return false;
    }
    return finish_filtered_light(dst, quotient, in, opt, roi, counted, nthreads,
                                 totals, std::move(acc), std::move(wsum));
}

}  // namespace detail
}  // namespace zdenoise
