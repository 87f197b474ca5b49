// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// WindowFitter: one centre's window grown radius by radius, its five
// planes fitted, the stop tests, and the splat of the final fit
// (docs/FILTER.md sections 5 and 6).

#pragma once

#include <algorithm>
#include <vector>

#include "filter_inputs.h"
#include "fit_kernel.h"
#include "guide_kernel.h"
#include "guide_weight.h"
#include "outliers.h"
#include "plane_fit.h"
#include "pyramid_level.h"
#include "row_kernels.h"
#include "splat_kernel.h"

namespace zdenoise {
namespace detail {

/// The five planes of one window and what the splat needs of it.
struct WindowFit {
    int radius  = 0;
    int values  = 0;     ///< which WindowFitter::m_value holds its exp(-vt)
    float mean  = 0.0f;  ///< <z>: mean luminance of the window's points
    double eta  = 0.0;   ///< predicted relative noise at the centre
    Plane whole;
    Plane quadrant[4];
    WindowRange range;  ///< of the radiance of the fit's points
    /// Fitted on the pyramid's level 1 (docs/FILTER.md 5.1): `values` and
    /// `range` are filled at full resolution just before the splat.
    bool pyramid = false;
};

enum class StopReason { Quality, Size, Edge };

/// What the diagnostics (FilterOptions::diagnostics) sum at each output
/// pixel, kDiagnosticSums doubles a pixel: the splat weight s of each
/// window times its final radius and its eta, and s per stop reason.
enum DiagnosticSum {
    kSumRadius,
    kSumEta,
    kSumQuality,
    kSumSize,
    kSumEdge,
    kDiagnosticSums
};

/// What the hat diagonal (docs/SELECTION.md 2.5, 2.6) sums at each output
/// pixel, kHatSums doubles a pixel: SplatRow::hat's three terms.
/// D = (sum s H_l (1 - c (zl - A_l)) - sum s c A_l + out_l sum s c) / wsum.
enum HatSum { kHatOwn, kHatValue, kHatValueA, kHatSums };

/// Grows, fits and splats the windows of the centres of a range of rows.
/// One per block of centres: holds the per-centre scratch (guide weights of the
/// window) so that nothing is allocated per pixel.
class WindowFitter {
public:
    WindowFitter(const FilterInputs& in, const FilterOptions& opt,
                 const ROI& out, std::vector<double>& acc,
                 std::vector<double>& wsum, std::vector<double>* diagnostics,
                 std::vector<double>* hat = nullptr,
                 const PyramidLevel* pyramid = nullptr)
        : m_in(in)
        , m_opt(opt)
        , m_out(out)
        , m_acc(acc)
        , m_wsum(wsum)
        , m_diagnostics(diagnostics)
        , m_hat(hat)
        , m_guide(in, opt)
        , m_pyramid(pyramid)
        , m_coarse_guide(pyramid ? pyramid->in : in, opt)
        , m_value_noise_t(opt.value_noise ? outlier_threshold(opt.r_max) : 0.0f)
        , m_side(2 * opt.r_max + 1)
        , m_g(cache_size(), 0.0f)
        , m_fit_weight(cache_size(), 0.0f)
        , m_value { std::vector<float>(cache_size(), 0.0f),
                    std::vector<float>(cache_size(), 0.0f) }
        , m_spatial_row(size_t(m_side) + kPlanePadding, 0.0f)
        , m_column_sums(kColumnSums * column_sums_stride(), 0.0f)
        , m_splat_s(size_t(m_side) + kPlanePadding, 0.0f)
        , m_splat_a { std::vector<float>(size_t(m_side) + kPlanePadding, 0.0f),
                      std::vector<float>(size_t(m_side) + kPlanePadding, 0.0f),
                      std::vector<float>(size_t(m_side) + kPlanePadding, 0.0f) }
    {
        m_segments.reserve(2 * size_t(m_side));
        if (m_hat)
            for (std::vector<float>& h : m_splat_hat)
                h.assign(size_t(m_side) + kPlanePadding, 0.0f);
        if (m_pyramid) {
            // Level 1 holds at most r_max + 1 blocks of a window's side.
            const size_t side = size_t(opt.r_max) + 1;
            m_coarse_g.assign(side * side + kPlanePadding, 0.0f);
            m_coarse_fit_weight.assign(side * side + kPlanePadding, 0.0f);
            m_coarse_values.assign(side * side + kPlanePadding, 0.0f);
            m_coarse_spatial.assign(side + kPlanePadding, 0.0f);
            m_coarse_ey.assign(side, 0.0f);
        }
    }

    /// Fit the window of fit point (x0, y0) and splat it (unless
    /// splat_window is false: a strided lattice point of the next block,
    /// fitted only for its stop reason).
    StopReason process(int x0, int y0, int& radius, bool splat_window = true);

    /// The radius tried after R: R + 1, or R * radius_growth (at least
    /// R + 1), never beyond r_max.
    int next_radius(int R) const
    {
        const int grown = int(float(R) * m_opt.radius_growth);
        return std::min(std::max(R + 1, grown), m_opt.r_max);
    }

private:
    /// The caches hold the largest window and kPlanePadding floats of
    /// padding (the kernels read whole vectors).
    size_t cache_size() const { return size_t(m_side) * m_side + kPlanePadding; }
    size_t cache_index(int dx, int dy) const
    {
        return size_t(dy + m_opt.r_max) * m_side + (dx + m_opt.r_max);
    }
    float& g_at(int dx, int dy) { return m_g[cache_index(dx, dy)]; }
    /// The window of radius R around the centre, clipped to the image.
    ROI window_in_image(int R) const
    {
        const ROI& img = m_in.image;
        return ROI(std::max(m_x0 - R, img.xbegin), std::min(m_x0 + R + 1, img.xend),
                   std::max(m_y0 - R, img.ybegin), std::min(m_y0 + R + 1, img.yend));
    }
    /// Fill m_spatial_row for radius R: exp(-d^2/R^2) at index d + R.
    void set_spatial(int R)
    {
        for (int d = 0; d <= R; ++d)
            m_spatial_row[size_t(R + d)] = m_spatial_row[size_t(R - d)]
                = std::exp(-float(d * d) / float(R * R));
    }
    /// The value term's exponent is value_scale(<z>) |zl - <z>| (clamped
    /// in exp_neg so that weights never underflow).
    float value_scale(float mean) const
    {
        return m_opt.value_k / (std::max(std::fabs(mean), float(kEps)) + m_centre_noise);
    }
    // noinline: the three stages stay separate in profiles
    // (docs/PERFORMANCE.md); a call per window or radius costs nothing.
    /// Extend the cached guide weights and point sums to radius R.
    [[gnu::noinline]] void grow_to(int R);
    /// Fit at radius R, keeping the value factors in m_value[values].
    [[gnu::noinline]] WindowFit fit(int R, int values);
    /// Fit at radius R on the pyramid's level 1 (docs/FILTER.md 5.1); the
    /// splat fills m_value[values]. Absent (whole.present false) where the
    /// window holds no block that is a fit point.
    [[gnu::noinline]] WindowFit fit_on_pyramid(int R, int values);
    /// The planes of a fit from its nine cells' moments and its sum of
    /// w^2 sigma^2.
    void solve_cells(WindowFit& wf, const FitMoments cells[9], double w2s2);
    /// Floats between the column sums' planes: a window's side and padding.
    size_t column_sums_stride() const { return size_t(m_side) + kPlanePadding; }
    /// Point the fit kernel's planes at pixel index i of `in`.
    static void set_plane_pointers(FitColumns& cols, const FilterInputs& in, size_t i)
    {
        cols.zl = &in.zl[i];
        for (int ch = 0; ch < 3; ++ch)
            cols.z[ch] = &in.zfit[ch][i];
        cols.vs    = &in.vs[i];
        cols.sigma = &in.sigma[i];
    }
    /// What a fit on the pyramid leaves to the splat: the guide and fit
    /// weights, value factors and radiance range at full resolution.
    [[gnu::noinline]] void prepare_pyramid_splat(WindowFit& w);
    bool edge_fires(const WindowFit& w) const;
    /// Add the splat weights of the row segment just splatted (n pixels
    /// from output index `first`) to the diagnostics' sums.
    void add_diagnostics(const WindowFit& w, StopReason reason, size_t first,
                         int n);
    [[gnu::noinline]] void splat(const WindowFit& w, StopReason reason);

    const FilterInputs& m_in;
    const FilterOptions& m_opt;
    const ROI& m_out;
    std::vector<double>& m_acc;
    std::vector<double>& m_wsum;
    /// kDiagnosticSums per output pixel, or null: no diagnostics.
    std::vector<double>* m_diagnostics;
    /// kHatSums per output pixel, or null: no hat diagonal.
    std::vector<double>* m_hat;
    GuideWeight m_guide;
    const PyramidLevel* m_pyramid;  ///< null: every fit at full resolution
    GuideWeight m_coarse_guide;     ///< on m_pyramid's level
    /// t of the value term's noise (docs/FILTER.md section 5), 0 without
    /// value_noise; and t s(p0) of the window's centre.
    float m_value_noise_t, m_centre_noise = 0.0f;
    /// Level 1's guide and fit weights over a window, its value factors
    /// (not kept) and e(dx) of its columns.
    std::vector<float> m_coarse_g, m_coarse_fit_weight, m_coarse_values,
        m_coarse_spatial, m_coarse_ey;
    int m_side;
    std::vector<float> m_g;  ///< g(q; p0) over the grown window
    /// g(q; p0) exp(-sigma(q)) for good fit points, 0 for the others: the
    /// part of the fit weight that does not change with R.
    std::vector<float> m_fit_weight;
    /// exp(-vt(q)) of the good points at the last two radii fitted (the
    /// splat of the final fit reuses them; an edge steps back one fit).
    std::vector<float> m_value[2];
    /// exp(-d^2/R^2) at d + R, d = -R..R (and kLanes of padding)
    std::vector<float> m_spatial_row;
    /// The fit kernel's column sums for one group of rows.
    std::vector<float> m_column_sums;
    /// The splat kernel's output for one row (and kPlanePadding floats).
    std::vector<float> m_splat_s, m_splat_a[3], m_splat_hat[3];
    int m_x0 = 0, m_y0 = 0, m_grown = -1;
    double m_zsum = 0.0;  ///< sum of zl over fit points with g > 0
    int m_zcount  = 0;
    /// The radiance range of the grown window's good points (fit weight > 0).
    WindowRange m_range;
    /// The row segments of the last growth (at most two a row).
    std::vector<GrowSegment> m_segments;
};

}  // namespace detail
}  // namespace zdenoise
