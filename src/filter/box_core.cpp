// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// box_filter_decoded(): the box core (docs/FILTER.md section 15): the
// input and, for each radius 1, 2, 4, ... box_radius, box_candidate()
// (box_regression.cpp); then blend_candidates() (box_choice.cpp): each
// candidate's risk, pooled over the same light around, and their blend.

#include "box_core.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "box_choice.h"
#include "box_regression.h"
#include "box_sums.h"
#include "decoded_filter.h"
#include "filter_inputs.h"
#include "internal.h"

namespace zdenoise {
namespace detail {

using namespace OIIO;

namespace {

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

/// The blend's mean radius as map 0 of opt.diagnostics, the noise as map 2.
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
    return reach + kChoiceReach + 6;
}


bool
box_filter_decoded(ImageBuf& dst, const ImageBuf& quotient,
                   const FilterInputs& in, const FilterOptions& opt, ROI roi,
                   const ROI& counted, int nthreads, FilterStats& totals)
{
    const ROI rr = roi_intersection(halo_region(roi, in.image, kChoiceReach),
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
    // The pooling's guide: radius 8, or the largest below it.
    int guide = 1;
    for (size_t j = 0; j < radii.size(); ++j)
        if (radii[j] <= 8)
            guide = int(j) + 1;
    std::vector<double> acc(3 * roi.npixels(), 0.0), wsum(roi.npixels(), 0.0);
    std::vector<float> chosen(roi.npixels(), 0.0f);
    blend_candidates(in, cands, guide, rr, roi, acc, wsum, chosen, nthreads);
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
