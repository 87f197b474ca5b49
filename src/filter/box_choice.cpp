// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// blend_candidates(): the box core's choice (docs/FILTER.md 15.3), in
// order:
//   local_variance()   the input's noise from the radius-1 fit's residual
//   risk_terms()       each candidate's risk against the radius-1
//                      candidate, relMSE-weighted, and that candidate's own
//   pooled blend       per pixel the risks summed over the 11x11 around,
//                      each neighbour weighted by how alike the guide's
//                      light is, and the candidates blended by exp(-risk)

#include "box_choice.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "box_sums.h"
#include "filter_inputs.h"
#include "internal.h"

namespace zdenoise {
namespace detail {

using namespace OIIO;

namespace {

/// The candidate every risk is taken against: radius 1, which follows the
/// input's structure but carries less of its noise (about 0.4), so that a
/// firefly does not decide its neighbourhood as it does against z.
constexpr int kReference = 1;

/// Half-size of the box of radius-1 residuals that estimates the noise.
constexpr int kVarianceRadius = 2;

/// Half-size of the box over which the risks are pooled.
constexpr int kPoolRadius = 5;
static_assert(kPoolRadius + kVarianceRadius == kChoiceReach,
              "the choice reads the candidates within its reach");

/// A neighbour counts in the pool when its guide light is within about
/// this many noise deviations of the pixel's (a 2-sigma test; 3 measured
/// the same): pools do not cross an edge of the light.
constexpr double kSameLight = 2.0;

/// The blend's temperature in units of the reference's pooled variance:
/// within a flat optimum (0.15 to 0.5 within 1 % on the public set).
constexpr double kBlendTemperature = 0.3;

/// The relative-error floor of relMSE (zmetrics' 0.01 on the radiance).
constexpr double kRelFloor = 1e-2;

/// The input and radii 1, 2, 4, ... up to box_radius's largest, 128.
constexpr int kMostCandidates = 9;

double
luma(const float* rgb)
{
    return double(kLumaWeights[0]) * rgb[0] + double(kLumaWeights[1]) * rgb[1]
           + double(kLumaWeights[2]) * rgb[2];
}

size_t
at(const ROI& r, int x, int y)
{
    return size_t(y - r.ybegin) * size_t(r.width()) + size_t(x - r.xbegin);
}

/// The noise variance of zl at every pixel of rr: over the 5x5 around,
/// the radius-1 fit's squared residuals at fit points over their
/// 1 - D (what a residual keeps of the noise). Exact within rr less 2.
std::vector<double>
local_variance(const FilterInputs& in, const BoxCandidate& ref, const ROI& rr,
               int nthreads)
{
    Planes<double> p(rr.width(), rr.height(), 2);
    for_rows(rr, nthreads, [&](int y) {
        for (int x = rr.xbegin; x < rr.xend; ++x) {
            const size_t i = in.index(x, y), k = at(rr, x, y);
            const double l = luma(&ref.rgb[3 * k]);
            if (!(in.cls[i] & kFitPoint) || !std::isfinite(l))
                continue;
            const double d = double(in.zl[i]) - l;
            p.plane(0)[k] = d * d;
            p.plane(1)[k] = 1.0 - double(ref.hat[k]);
        }
    });
    box_sum_planes(p, p, rr.xbegin - in.image.xbegin, rr.ybegin - in.image.ybegin,
                   kVarianceRadius, nthreads);
    std::vector<double> v(rr.npixels());
    for (size_t k = 0; k < v.size(); ++k)
        v[k] = p.plane(0)[k] / std::max(p.plane(1)[k], 1e-9);
    return v;
}

/// Over rr: planes 0..nc-1 each candidate's risk at the fit points,
/// ((L_k - L_1)^2 - v |D_k - D_1| + v D_k) a^2 / (a^2 G^2 + 0.01) (Stein's
/// risk with the radius-1 candidate as the reference; a the albedo's
/// luminance, G the guide's light), 1e30 where not finite; plane nc the
/// reference's own, v D_1 a^2 / (a^2 G^2 + 0.01); nc + 1 the guide's light
/// and nc + 2 its variance v D_G.
Planes<double>
risk_terms(const FilterInputs& in, const std::vector<BoxCandidate>& cands,
           int guide, const ROI& rr, const std::vector<double>& v, int nthreads)
{
    const int nc = int(cands.size());
    Planes<double> t(rr.width(), rr.height(), nc + 3);
    for_rows(rr, nthreads, [&](int y) {
        for (int x = rr.xbegin; x < rr.xend; ++x) {
            const size_t i = in.index(x, y), k = at(rr, x, y);
            const double g = luma(&cands[size_t(guide)].rgb[3 * k]);
            const double gv = v[k] * double(cands[size_t(guide)].hat[k]);
            t.plane(nc + 1)[k] = std::isfinite(g) ? g : 0.0;
            t.plane(nc + 2)[k] = (std::isfinite(gv) ? gv : 0.0) + 1e-12;
            if (!(in.cls[i] & kFitPoint))
                continue;
            double a = 0.0;
            for (int c = 0; c < 3; ++c) {
                const float inv = in.inv_albedo[c][i];
                a += double(kLumaWeights[c]) * (inv > 0.0f ? 1.0 / double(inv) : 1.0);
            }
            const double light = std::isfinite(g) ? std::max(g, 0.0) : double(in.zl[i]);
            const double wl = a * a / (a * a * light * light + kRelFloor);
            const double l1 = luma(&cands[kReference].rgb[3 * k]);
            const double d1 = double(cands[kReference].hat[k]);
            for (int c = 0; c < nc; ++c) {
                const double lk = luma(&cands[size_t(c)].rgb[3 * k]);
                const double dk = double(cands[size_t(c)].hat[k]);
                const double s = ((lk - l1) * (lk - l1) - v[k] * std::fabs(dk - d1)
                                  + v[k] * dk) * wl;
                t.plane(c)[k] = std::isfinite(s) ? s : 1e30;
            }
            const double own = v[k] * d1 * wl;
            t.plane(nc)[k] = std::isfinite(own) ? own : 0.0;
        }
    });
    return t;
}

/// Pixel (x, y)'s blend from the risk terms over rr.
void
blend_pixel(const std::vector<BoxCandidate>& cands, const Planes<double>& t,
            const ROI& rr, int x, int y, double* out, double& wsum, float& radius)
{
    const int nc = int(cands.size());
    const size_t p = at(rr, x, y);
    const double gp = t.plane(nc + 1)[p], vp = t.plane(nc + 2)[p];
    // At most the input and radii 1, 2, 4, ... 128, and the reference's own.
    std::array<double, kMostCandidates + 1> pooled {};
    for (int v = std::max(y - kPoolRadius, rr.ybegin); v <= std::min(y + kPoolRadius, rr.yend - 1); ++v)
        for (int u = std::max(x - kPoolRadius, rr.xbegin); u <= std::min(x + kPoolRadius, rr.xend - 1); ++u) {
            const size_t q = at(rr, u, v);
            const double dg = t.plane(nc + 1)[q] - gp;
            const double w  = std::exp(-dg * dg / (kSameLight * kSameLight
                                                   * (vp + t.plane(nc + 2)[q])));
            for (int c = 0; c <= nc; ++c)
                pooled[size_t(c)] += w * t.plane(c)[q];
        }
    double least = std::numeric_limits<double>::infinity();
    std::array<bool, kMostCandidates> reaches {};
    for (int c = 0; c < nc; ++c) {
        const float* rgb = &cands[size_t(c)].rgb[3 * p];
        reaches[size_t(c)] = std::isfinite(rgb[0]) && std::isfinite(rgb[1])
                             && std::isfinite(rgb[2]);
        if (reaches[size_t(c)])
            least = std::min(least, pooled[size_t(c)]);
    }
    if (least == std::numeric_limits<double>::infinity())
        return;  // no candidate reaches the pixel
    const double scale = kBlendTemperature * pooled[size_t(nc)] + 1e-30;
    double sum = 0.0, acc[3] = { 0.0, 0.0, 0.0 }, r = 0.0;
    for (int c = 0; c < nc; ++c) {
        if (!reaches[size_t(c)])
            continue;
        const double w = std::exp(-(pooled[size_t(c)] - least) / scale);
        sum += w;
        r += w * cands[size_t(c)].radius;
        for (int ch = 0; ch < 3; ++ch)
            acc[ch] += w * double(cands[size_t(c)].rgb[3 * p + ch]);
    }
    for (int ch = 0; ch < 3; ++ch)
        out[ch] = acc[ch] / sum;
    wsum   = 1.0;
    radius = float(r / sum);
}

}  // namespace


void
blend_candidates(const FilterInputs& in, const std::vector<BoxCandidate>& cands,
                 int guide, const ROI& rr, const ROI& roi, std::vector<double>& acc,
                 std::vector<double>& wsum, std::vector<float>& radius,
                 int nthreads)
{
    if (cands.size() > size_t(kMostCandidates) || cands.size() <= size_t(kReference))
        return;  // box_radius is checked to 1..128: 2 to 9 candidates
    const std::vector<double> v = local_variance(in, cands[kReference], rr, nthreads);
    const Planes<double> t = risk_terms(in, cands, guide, rr, v, nthreads);
    for_rows(roi, nthreads, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t o = at(roi, x, y);
            blend_pixel(cands, t, rr, x, y, &acc[3 * o], wsum[o], radius[o]);
        }
    });
}

}  // namespace detail
}  // namespace zdenoise
