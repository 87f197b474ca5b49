// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// box_candidate(): one radius's candidate of the box core (docs/FILTER.md
// 15.1-15.2), in order:
//   fill_moments() / fill_cell_moments()  each fit point's f f^T, f z,
//                        zl^2, with f = (1, x, y, normal, log 1/depth), per
//                        pixel (radii up to 4) or summed over cells of r/4
//   box_sum_planes()     their sums over every window (box_sums.cpp)
//   fill_splats()        each window's ridge regression, weighted by its fit
//   box_sum_planes()     the splat: every pixel's (or cell's) windows summed
//   read_pixels() / read_cells()  the light at each pixel and its hat
//                        diagonal; from cells, interpolated bilinearly

#include "box_regression.h"

#include <algorithm>
#include <cmath>

#include "box_sums.h"
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

/// Ridge per feature, in the feature's units squared per point: small
/// against any variation the feature really has in a window, so that it
/// only settles a feature that is flat there (a plane's normal, a wall's
/// depth).
constexpr double kRidge[kFeatures] = { 0.0, 1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-6 };

/// The window weight's floor on its relative residual variance: windows
/// that fit better than this are weighted alike.
constexpr double kWeightFloor = 1e-3;

/// Index of f_j f_k (j <= k) among the pair planes.
constexpr int
pair_index(int j, int k)
{
    return j * kFeatures - j * (j - 1) / 2 + (k - j);
}

/// A cell's windows and splats reach this many cells on each side.
constexpr int kCellWindow = 4;

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


/// Add pixel (x, y)'s moments to the kMomentPlanes planes of `p` at o;
/// nothing if it is no fit point.
void
add_moments(const FilterInputs& in, int x, int y, Planes<double>& p, size_t o)
{
    double f[kFeatures];
    if (!features(in, x, y, f))
        return;
    const size_t i = in.index(x, y);
    for (int j = 0; j < kFeatures; ++j)
        for (int k = j; k < kFeatures; ++k)
            p.plane(pair_index(j, k))[o] += f[j] * f[k];
    for (int j = 0; j < kFeatures; ++j)
        for (int c = 0; c < 3; ++c)
            p.plane(kMomentZ + 3 * j + c)[o] += f[j] * double(in.zfit[c][i]);
    const double zl = double(in.zl[i]);
    p.plane(kMomentZZ)[o] += zl * zl;
}

/// A grid of cells of `side` pixels anchored at the frame's origin: cells
/// [cx0, cx0 + nx) x [cy0, cy0 + ny) in the frame's cell indices.
struct CellGrid {
    int side = 1, cx0 = 0, cy0 = 0, nx = 0, ny = 0;
    /// The cells that hold the pixels of `r` (frame coordinates).
    CellGrid(const ROI& r, const ROI& frame, int s)
        : side(s)
        , cx0(floor_div(r.xbegin - frame.xbegin, s))
        , cy0(floor_div(r.ybegin - frame.ybegin, s))
    {
        nx = floor_div(r.xend - frame.xbegin - 1, s) + 1 - cx0;
        ny = floor_div(r.yend - frame.ybegin - 1, s) + 1 - cy0;
    }
};

/// Every cell's moments: the sum over its fit points held in in.region,
/// in raster order within the cell.
Planes<double>
fill_cell_moments(const FilterInputs& in, const CellGrid& g, int nthreads)
{
    Planes<double> p(g.nx, g.ny, kMomentPlanes);
    const ROI& frame = in.image;
    OIIO::parallel_for(int64_t(0), int64_t(g.ny), [&](int64_t j) {
        const int y0 = frame.ybegin + (g.cy0 + int(j)) * g.side;
        for (int y = std::max(y0, in.region.ybegin);
             y < std::min(y0 + g.side, in.region.yend); ++y)
            for (int ci = 0; ci < g.nx; ++ci) {
                const int x0 = frame.xbegin + (g.cx0 + ci) * g.side;
                const size_t o = size_t(j) * size_t(g.nx) + size_t(ci);
                for (int x = std::max(x0, in.region.xbegin);
                     x < std::min(x0 + g.side, in.region.xend); ++x)
                    add_moments(in, x, y, p, o);
            }
    }, paropt_any_length(nthreads));
    return p;
}

/// Every window's fit, one window per element of the box-summed moments
/// `sums`, into its splat planes (0 where it has no fit).
Planes<double>
fill_splats(const Planes<double>& sums, int nthreads)
{
    Planes<double> splat(sums.width, sums.height, kSplatPlanes);
    const size_t n = sums.plane_size();
    OIIO::parallel_for(int64_t(0), int64_t(sums.height), [&](int64_t y) {
        for (size_t o = size_t(y) * size_t(sums.width);
             o < size_t(y + 1) * size_t(sums.width) && o < n; ++o) {
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
    }, paropt_any_length(nthreads));
    return splat;
}

/// Pixel (x, y)'s light and hat diagonal from splat sums `s` (kSplatPlanes
/// values), into cand at k; nothing where no window reached it.
void
read_light(const FilterInputs& in, int x, int y, const double* s,
           BoxCandidate& cand, size_t k)
{
    const double w = s[kSplatWeight];
    if (!(w > 0.0))
        return;
    double f[kFeatures];
    features(in, x, y, f);
    for (int c = 0; c < 3; ++c) {
        double v = 0.0;
        for (int j = 0; j < kFeatures; ++j)
            v += f[j] * s[c * kFeatures + j];
        cand.rgb[3 * k + c] = float(v / w);
    }
    cand.hat[k] = float(s[kSplatHat] / w);
}

/// A radius of at most 4: windows at every pixel of the sums' region.
void
pixel_candidate(const FilterInputs& in, const ROI& rr, int r,
                BoxCandidate& cand, int nthreads)
{
    const ROI& frame = in.image;
    const ROI sub = roi_intersection(halo_region(rr, frame, 2 * r), in.region);
    Planes<double> p(sub.width(), sub.height(), kMomentPlanes);
    for_rows(sub, nthreads, [&](int y) {
        for (int x = sub.xbegin; x < sub.xend; ++x)
            add_moments(in, x, y, p,
                        size_t(y - sub.ybegin) * size_t(sub.width())
                            + size_t(x - sub.xbegin));
    });
    const int x0 = sub.xbegin - frame.xbegin, y0 = sub.ybegin - frame.ybegin;
    box_sum_planes(p, p, x0, y0, r, nthreads);
    Planes<double> splat = fill_splats(p, nthreads);
    p = Planes<double>();
    box_sum_planes(splat, splat, x0, y0, r, nthreads);
    for_rows(rr, nthreads, [&](int y) {
        double s[kSplatPlanes];
        for (int x = rr.xbegin; x < rr.xend; ++x) {
            const size_t o = size_t(y - sub.ybegin) * size_t(sub.width())
                             + size_t(x - sub.xbegin);
            for (int k = 0; k < kSplatPlanes; ++k)
                s[k] = splat.plane(k)[o];
            read_light(in, x, y, s, cand,
                       size_t(y - rr.ybegin) * size_t(rr.width())
                           + size_t(x - rr.xbegin));
        }
    });
}

/// One axis of the bilinear read: pixel coordinate `px` (from the frame's
/// origin) between the centres of cells i and i + 1 (weight t on i + 1),
/// both clamped to the frame's cells [0, ncells) and given relative to the
/// grid's first cell c0.
void
cell_pair(int px, int side, int ncells, int c0, int& i, int& i1, double& t)
{
    const double u = (double(px) + 0.5) / double(side) - 0.5;
    const int lo   = int(std::floor(u));
    t              = u - double(lo);
    i  = std::clamp(lo, 0, ncells - 1) - c0;
    i1 = std::clamp(lo + 1, 0, ncells - 1) - c0;
}

/// A radius beyond 4: windows of (2 kCellWindow + 1)^2 cells of r / 4
/// pixels at every cell, splatted per cell and read bilinearly between the
/// four nearest cell centres.
void
cell_candidate(const FilterInputs& in, const ROI& rr, int r,
               BoxCandidate& cand, int nthreads)
{
    const ROI& frame = in.image;
    const int side   = box_cell(r);
    const ROI need   = roi_intersection(halo_region(rr, frame, box_candidate_reach(r)),
                                        in.region);
    const CellGrid g(need, frame, side);
    Planes<double> p = fill_cell_moments(in, g, nthreads);
    box_sum_planes(p, p, g.cx0, g.cy0, kCellWindow, nthreads);
    Planes<double> splat = fill_splats(p, nthreads);
    p = Planes<double>();
    box_sum_planes(splat, splat, g.cx0, g.cy0, kCellWindow, nthreads);
    const int ncx = floor_div(frame.width() - 1, side) + 1;
    const int ncy = floor_div(frame.height() - 1, side) + 1;
    for_rows(rr, nthreads, [&](int y) {
        int j, j1;
        double ty;
        cell_pair(y - frame.ybegin, side, ncy, g.cy0, j, j1, ty);
        for (int x = rr.xbegin; x < rr.xend; ++x) {
            int i, i1;
            double tx;
            cell_pair(x - frame.xbegin, side, ncx, g.cx0, i, i1, tx);
            const size_t o00 = size_t(j) * size_t(g.nx) + size_t(i);
            const size_t o01 = size_t(j) * size_t(g.nx) + size_t(i1);
            const size_t o10 = size_t(j1) * size_t(g.nx) + size_t(i);
            const size_t o11 = size_t(j1) * size_t(g.nx) + size_t(i1);
            double s[kSplatPlanes];
            for (int k = 0; k < kSplatPlanes; ++k) {
                const double* q = splat.plane(k);
                s[k] = (1.0 - ty) * ((1.0 - tx) * q[o00] + tx * q[o01])
                       + ty * ((1.0 - tx) * q[o10] + tx * q[o11]);
            }
            read_light(in, x, y, s, cand,
                       size_t(y - rr.ybegin) * size_t(rr.width())
                           + size_t(x - rr.xbegin));
        }
    });
}

}  // namespace


int
box_cell(int r)
{
    return r <= 4 ? 1 : r / kCellWindow;
}


int
box_candidate_reach(int r)
{
    // Pixels: a window and the windows around it. Cells: the next cell's
    // centre, its windows and theirs, each cell whole.
    return r <= 4 ? 2 * r : (2 * kCellWindow + 2) * box_cell(r);
}


void
box_candidate(const FilterInputs& in, const FilterOptions& opt, const ROI& rr,
              int r, BoxCandidate& cand, int nthreads)
{
    cand.radius = r;
    cand.rgb.assign(3 * rr.npixels(), NAN);
    cand.hat.assign(rr.npixels(), NAN);
    if (cancel_requested(opt))
        return;
    if (box_cell(r) == 1)
        pixel_candidate(in, rr, r, cand, nthreads);
    else
        cell_candidate(in, rr, r, cand, nthreads);
}

}  // namespace detail
}  // namespace zdenoise
