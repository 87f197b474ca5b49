// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// box_filter_decoded(): the box core (docs/FILTER.md section 15). For each
// candidate radius r, in order:
//   fill_sums()          each fit point's moments: f f^T, f z, zl^2, with
//                        f = (1, x, y, normal, log 1/depth)
//   box_sum_planes()     their sums over every window (box_sums.cpp)
//   fill_splats()        each window's ridge regression, at a lattice of
//                        centres (stride r / 4), weighted by its fit
//   box_sum_planes()     the splat: every pixel's windows summed
//   read_candidate()     the light at each pixel and its hat diagonal
// then choose_candidates(): Stein's risk of each candidate and of the
// input, pooled 11x11, and per pixel the least.

#include "box_core.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "box_sums.h"
#include "decoded_filter.h"
#include "filter_inputs.h"
#include "internal.h"

namespace zdenoise {
namespace detail {

using namespace OIIO;

namespace {

/// The regression's features: 1, x, y, the normal's three components and
/// log(1 / depth).
constexpr int kFeatures = 7;
constexpr int kPairs    = kFeatures * (kFeatures + 1) / 2;
/// Sum planes: f_j f_k (j <= k), f_j z_c, zl^2.
constexpr int kMomentPlanes = kPairs + 3 * kFeatures + 1;
constexpr int kMomentZ      = kPairs;
constexpr int kMomentZZ     = kPairs + 3 * kFeatures;
/// Splat planes: w beta_cj, w K/n (the window's mean leverage), w.
constexpr int kSplatPlanes = 3 * kFeatures + 2;
constexpr int kSplatHat    = 3 * kFeatures;
constexpr int kSplatWeight = 3 * kFeatures + 1;

/// Half-size of the box over which the risks are pooled before the choice:
/// 121 pixels. A pixel's risk is mostly noise; on the public set at 16 spp
/// 11x11 chose better than 7x7 or 5x5 (bench/results/2026-12-box-core-log.md).
constexpr int kRiskRadius = 5;

/// The risk's residual z - out is clipped at this many noise deviations:
/// Monte Carlo's heavy tails (a firefly below the outlier test's
/// threshold) would otherwise decide a whole pooled box for the radius
/// that follows it (the same measurement: 3 beat 2, 4 and no clip).
constexpr double kClipSigmas = 3.0;

/// Ridge per feature, in the feature's units squared per point: small
/// against any variation the feature really has in a window, so that it
/// only settles a feature that is flat there (a plane's normal, a wall's
/// depth).
constexpr double kRidge[kFeatures] = { 0.0, 1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-6 };

/// The relative-error floor of relMSE (zmetrics' 0.01 on the radiance).
constexpr double kRelFloor = 1e-2;

/// The window weight's floor on its relative residual variance: windows
/// that fit better than this are weighted alike.
constexpr double kWeightFloor = 1e-3;

/// Index of f_j f_k (j <= k) among the pair planes.
constexpr int
pair_index(int j, int k)
{
    return j * kFeatures - j * (j - 1) / 2 + (k - j);
}

/// The lattice of a radius's window centres: every pixel up to radius 4,
/// then every r/4-th, so that a pixel is covered by at least 81 windows
/// and solves cost about 3.4 a pixel for all radii.
int
window_stride(int r)
{
    return std::max(1, r / 4);
}

/// Pixel (x, y)'s features; false if it takes no part in fits.
bool
features(const FilterInputs& in, int x, int y, double f[kFeatures])
{
    const size_t i = in.index(x, y);
    f[0] = 1.0;
    f[1] = double(x - in.image.xbegin);
    f[2] = double(y - in.image.ybegin);
    for (int c = 0; c < 3; ++c)
        f[3 + c] = in.has_normal() ? double(in.normal[c][i]) : 0.0;
    const float id = in.invdepth.empty() ? 0.0f : in.invdepth[i];
    f[6] = id > 0.0f ? std::log(double(id)) : 0.0;
    return (in.cls[i] & kFitPoint) != 0;
}

/// The moments of every fit point of `sub` into planes (kMomentPlanes).
void
fill_sums(const FilterInputs& in, const ROI& sub, Planes<double>& p,
          int nthreads)
{
    p = Planes<double>(sub.width(), sub.height(), kMomentPlanes);
    for_rows(sub, nthreads, [&](int y) {
        for (int x = sub.xbegin; x < sub.xend; ++x) {
            double f[kFeatures];
            if (!features(in, x, y, f))
                continue;
            const size_t i = in.index(x, y);
            const size_t o = size_t(y - sub.ybegin) * size_t(sub.width())
                             + size_t(x - sub.xbegin);
            for (int j = 0; j < kFeatures; ++j)
                for (int k = j; k < kFeatures; ++k)
                    p.plane(pair_index(j, k))[o] = f[j] * f[k];
            for (int j = 0; j < kFeatures; ++j)
                for (int c = 0; c < 3; ++c)
                    p.plane(kMomentZ + 3 * j + c)[o] = f[j] * double(in.zfit[c][i]);
            const double zl = double(in.zl[i]);
            p.plane(kMomentZZ)[o] = zl * zl;
        }
    });
}

/// One window's fit from its sums `s` (one value a moment plane): beta
/// (intercept first, in the global features), its mean leverage K / n,
/// and its weight. False where it has too few points or no solution.
bool
solve_window(const double* s, double beta[3][kFeatures], double& leverage,
             double& weight)
{
    constexpr int m = kFeatures - 1;  // the centred features
    const double n  = s[pair_index(0, 0)];
    if (!(n >= 3.0))
        return false;
    double mean[kFeatures], zmean[3];
    for (int j = 1; j < kFeatures; ++j)
        mean[j] = s[pair_index(0, j)] / n;
    for (int c = 0; c < 3; ++c)
        zmean[c] = s[kMomentZ + c] / n;
    // Covariances with a ridge, factored in place (Cholesky).
    double a[m][m], g[3][m];
    double dof = 1.0;
    for (int j = 0; j < m; ++j) {
        for (int k = 0; k <= j; ++k)
            a[j][k] = s[pair_index(k + 1, j + 1)] - n * mean[k + 1] * mean[j + 1];
        const double ridge = n * kRidge[j + 1] + 1e-12;
        dof += a[j][j] > 0.0 ? a[j][j] / (a[j][j] + ridge) : 0.0;
        a[j][j] += ridge;
        for (int c = 0; c < 3; ++c)
            g[c][j] = s[kMomentZ + 3 * (j + 1) + c] - n * mean[j + 1] * zmean[c];
    }
    for (int j = 0; j < m; ++j) {
        for (int k = 0; k < j; ++k) {
            double v = a[j][k];
            for (int q = 0; q < k; ++q)
                v -= a[j][q] * a[k][q];
            a[j][k] = v / a[k][k];
        }
        double d = a[j][j];
        for (int q = 0; q < j; ++q)
            d -= a[j][q] * a[j][q];
        if (!(d > 0.0))
            return false;
        a[j][j] = std::sqrt(d);
    }
    double rss_l = s[kMomentZZ], zl = 0.0;
    for (int c = 0; c < 3; ++c) {
        double t[m];
        for (int j = 0; j < m; ++j) {
            double v = g[c][j];
            for (int q = 0; q < j; ++q)
                v -= a[j][q] * t[q];
            t[j] = v / a[j][j];
        }
        for (int j = m - 1; j >= 0; --j) {
            double v = t[j];
            for (int q = j + 1; q < m; ++q)
                v -= a[q][j] * t[q];
            t[j] = v / a[j][j];
        }
        double intercept = zmean[c];
        for (int j = 0; j < m; ++j) {
            beta[c][j + 1] = t[j];
            intercept -= t[j] * mean[j + 1];
        }
        beta[c][0] = intercept;
        zl += double(kLumaWeights[c]) * zmean[c];
    }
    // The luminance's residual: its own fit is the luma mix of the three.
    double explained = 0.0;
    for (int j = 0; j < m; ++j) {
        double bl = 0.0, gl = 0.0;
        for (int c = 0; c < 3; ++c) {
            bl += double(kLumaWeights[c]) * beta[c][j + 1];
            gl += double(kLumaWeights[c]) * g[c][j];
        }
        explained += bl * gl;
    }
    rss_l -= n * zl * zl + explained;
    const double resid = std::max(rss_l, 0.0) / std::max(n - dof, 1.0)
                         / (zl * zl + 1e-8);
    leverage = dof / n;
    weight   = 1.0 / (resid + kWeightFloor);
    return std::isfinite(weight) && std::isfinite(leverage);
}

/// Every window of radius r centred on the lattice within `win`, fitted
/// from the box sums `sums` over `sub`, into its splat planes (0 at the
/// pixels that are no centre).
void
fill_splats(const Planes<double>& sums, const ROI& sub, const ROI& win,
            const ROI& frame, int r, Planes<double>& splat, int nthreads)
{
    splat = Planes<double>(sub.width(), sub.height(), kSplatPlanes);
    const int s = window_stride(r);
    for_rows(win, nthreads, [&](int y) {
        if ((y - frame.ybegin) % s)
            return;
        for (int x = win.xbegin; x < win.xend; ++x) {
            if ((x - frame.xbegin) % s)
                continue;
            const size_t o = size_t(y - sub.ybegin) * size_t(sub.width())
                             + size_t(x - sub.xbegin);
            double moments[kMomentPlanes];
            for (int k = 0; k < kMomentPlanes; ++k)
                moments[k] = sums.plane(k)[o];
            double beta[3][kFeatures], leverage, weight;
            if (!solve_window(moments, beta, leverage, weight))
                continue;
            for (int c = 0; c < 3; ++c)
                for (int j = 0; j < kFeatures; ++j)
                    splat.plane(c * kFeatures + j)[o] = weight * beta[c][j];
            splat.plane(kSplatHat)[o]    = weight * leverage;
            splat.plane(kSplatWeight)[o] = weight;
        }
    });
}

/// One candidate over the risk region: its light (3 floats a pixel, NaN
/// where no window reaches) and hat diagonal.
struct Candidate {
    int radius = 0;  ///< 0: the input
    std::vector<float> rgb, hat;
};

/// The candidate of radius r over `rr` from its summed splats over `sub`.
void
read_candidate(const FilterInputs& in, const Planes<double>& splat,
               const ROI& sub, const ROI& rr, Candidate& cand, int nthreads)
{
    cand.rgb.assign(3 * rr.npixels(), NAN);
    cand.hat.assign(rr.npixels(), NAN);
    for_rows(rr, nthreads, [&](int y) {
        for (int x = rr.xbegin; x < rr.xend; ++x) {
            const size_t o = size_t(y - sub.ybegin) * size_t(sub.width())
                             + size_t(x - sub.xbegin);
            const size_t k = size_t(y - rr.ybegin) * size_t(rr.width())
                             + size_t(x - rr.xbegin);
            const double w = splat.plane(kSplatWeight)[o];
            if (!(w > 0.0))
                continue;
            double f[kFeatures];
            features(in, x, y, f);
            for (int c = 0; c < 3; ++c) {
                double v = 0.0;
                for (int j = 0; j < kFeatures; ++j)
                    v += f[j] * splat.plane(c * kFeatures + j)[o];
                cand.rgb[3 * k + c] = float(v / w);
            }
            cand.hat[k] = float(splat.plane(kSplatHat)[o] / w);
        }
    });
}

/// The candidate of radius r (section 15.1).
bool
run_radius(const FilterInputs& in, const FilterOptions& opt, const ROI& roi,
           const ROI& rr, int r, Candidate& cand, int nthreads)
{
    const ROI& frame = in.image;
    const ROI sub = roi_intersection(halo_region(roi, frame, 2 * r + kRiskRadius),
                                     in.region);
    const ROI win = roi_intersection(halo_region(roi, frame, r + kRiskRadius), sub);
    const int x0 = sub.xbegin - frame.xbegin, y0 = sub.ybegin - frame.ybegin;
    Planes<double> planes;
    fill_sums(in, sub, planes, nthreads);
    box_sum_planes(planes, planes, x0, y0, r, nthreads);
    if (cancel_requested(opt))
        return false;
    Planes<double> splat;
    fill_splats(planes, sub, win, frame, r, splat, nthreads);
    planes = Planes<double>();
    box_sum_planes(splat, splat, x0, y0, r, nthreads);
    cand.radius = r;
    read_candidate(in, splat, sub, rr, cand, nthreads);
    return !cancel_requested(opt);
}

/// The input as a candidate: z itself, hat diagonal 1.
Candidate
input_candidate(const FilterInputs& in, const ROI& rr)
{
    Candidate cand;
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
pooled_risks(const FilterInputs& in, const std::vector<Candidate>& cands,
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
choose_candidates(const std::vector<Candidate>& cands, const Planes<double>& risk,
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
    radii.push_back(std::max(opt.box_radius, 1));
    return radii;
}


int
box_core_halo(const FilterOptions& opt)
{
    // Two windows of the largest radius, the risk's pooling, and the noise
    // estimate's and outlier test's footprint (6, as the windows' filter).
    return 2 * std::max(opt.box_radius, 1) + kRiskRadius + 6;
}


bool
box_filter_decoded(ImageBuf& dst, const ImageBuf& quotient,
                   const FilterInputs& in, const FilterOptions& opt, ROI roi,
                   const ROI& counted, int nthreads, FilterStats& totals)
{
    const ROI rr = roi_intersection(halo_region(roi, in.image, kRiskRadius),
                                    in.region);
    const std::vector<int> radii = box_radii(opt);
    std::vector<Candidate> cands { input_candidate(in, rr) };
    for (size_t j = 0; j < radii.size(); ++j) {
        cands.emplace_back();
        if (!run_radius(in, opt, roi, rr, radii[j], cands.back(), nthreads))
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
