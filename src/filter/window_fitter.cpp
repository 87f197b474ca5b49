// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// WindowFitter: window growth, the five-plane fit, the edge and quality
// stops (docs/FILTER.md section 5), and the combination and splat of the
// final fit (section 6).

#include "window_fitter.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace zdenoise {
namespace detail {

void
WindowFitter::grow_to(int R)
{
    if (R <= m_grown)
        return;
    const ROI& img = m_in.image;
    const int ya   = std::max(m_y0 - R, img.ybegin);
    const int yb   = std::min(m_y0 + R, img.yend - 1);
    // The square of radius R less the square already grown, a row segment
    // or two at a time, clipped to the image: their guide weights row by
    // row, then what the window keeps of them in one call.
    m_segments.clear();
    auto add = [&](int y, int xa, int xb) {
        xa = std::max(xa, img.xbegin);
        xb = std::min(xb, img.xend - 1);
        if (xb < xa)
            return;
        const GrowSegment seg { m_in.index(xa, y), cache_index(xa - m_x0, y - m_y0),
                                xb - xa + 1 };
        m_guide.row(xa, y, seg.n, &m_g[seg.cache]);
        m_segments.push_back(seg);
    };
    for (int y = ya; y <= yb; ++y) {
        if (std::abs(y - m_y0) > m_grown) {
            add(y, m_x0 - R, m_x0 + R);
        } else {
            add(y, m_x0 - R, m_x0 - m_grown - 1);
            add(y, m_x0 + m_grown + 1, m_x0 + R);
        }
    }
    GrowRing ring;
    ring.cls       = m_in.cls.data();
    ring.zl        = m_in.zl.data();
    ring.fit_prior = m_in.fit_prior.data();
    for (int ch = 0; ch < 3; ++ch)
        ring.lfit[ch] = m_in.lfit[ch].data();
    ring.g          = m_g.data();
    ring.fit_weight = m_fit_weight.data();
    ring.segments   = m_segments.data();
    ring.count      = int(m_segments.size());
    ring.zsum       = m_zsum;
    ring.zcount     = m_zcount;
    ring.range      = m_range;
    grow_ring(ring);
    m_zsum   = ring.zsum;
    m_zcount = ring.zcount;
    m_range  = ring.range;
    m_grown = R;
}


WindowFit
WindowFitter::fit(int R, int value_buffer)
{
    WindowFit wf;
    wf.radius = R;
    wf.values = value_buffer;
    wf.mean   = float(m_zsum / m_zcount);
    // grow_to(R) has just run: its range is this window's.
    wf.range = m_range;
    set_spatial(R);
    const ROI win = window_in_image(R);
    FitColumns cols;
    cols.stride       = size_t(m_in.width);
    cols.cache_stride = size_t(m_side);
    cols.spatial      = &m_spatial_row[size_t(win.xbegin - m_x0 + R)];
    cols.columns      = win.width();
    cols.mean         = wf.mean;
    cols.value_scale  = value_scale(wf.mean);
    cols.sums         = m_column_sums.data();
    cols.sums_stride  = column_sums_stride();
    // Nine disjoint cells, each point added once: open quadrants 0-3,
    // half-axes 4 (+y), 5 (-x), 6 (-y), 7 (+x), and the centre 8, by the
    // sides of the centre's row and column (left, centre, right) each
    // group of rows spans.
    static const int kCellOfSide[3][3] = { { 2, 6, 3 }, { 5, 8, 7 }, { 1, 4, 0 } };
    const int groups[3][2] = { { win.ybegin, m_y0 - 1 }, { m_y0, m_y0 },
                               { m_y0 + 1, win.yend - 1 } };
    FitMoments cells[9];
    double w2s2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        const int ya = std::max(groups[k][0], win.ybegin);
        const int yb = std::min(groups[k][1], win.yend - 1);
        if (yb < ya)
            continue;
        const size_t i = m_in.index(win.xbegin, ya);
        const size_t c = cache_index(win.xbegin - m_x0, ya - m_y0);
        set_plane_pointers(cols, m_in, i);
        cols.fit_weight = &m_fit_weight[c];
        cols.values     = m_value[value_buffer].data() + c;
        cols.ey         = &m_spatial_row[size_t(ya - m_y0 + R)];
        cols.rows       = yb - ya + 1;
        cols.dy0        = float(ya - m_y0);
        fit_columns(cols);
        w2s2 += add_columns(cols.sums, cols.sums_stride, cols.columns,
                            float(win.xbegin - m_x0), double(R), kCellOfSide[k], cells);
    }
    solve_cells(wf, cells, w2s2);
    return wf;
}


void
WindowFitter::solve_cells(WindowFit& wf, const FitMoments cell[9], double w2s2)
{
    static const int kQuadrantCells[4][4] = {
        { 0, 4, 7, 8 }, { 1, 4, 5, 8 }, { 2, 5, 6, 8 }, { 3, 6, 7, 8 }
    };
    FitMoments whole;
    for (int k = 0; k < 9; ++k)
        whole += cell[k];
    wf.whole = solve(whole);
    for (int q = 0; q < 4; ++q) {
        FitMoments quad;
        for (int k : kQuadrantCells[q])
            quad += cell[k];
        wf.quadrant[q] = solve(quad);
    }
    wf.eta = wf.whole.present ? std::sqrt(w2s2) / whole.s[0]
                              : std::numeric_limits<double>::infinity();
}


WindowFit
WindowFitter::fit_on_pyramid(int R, int value_buffer)
{
    WindowFit wf;
    wf.radius  = R;
    wf.values  = value_buffer;
    wf.pyramid = true;
    const FilterInputs& c = m_pyramid->in;
    // Block b spans the fine pixels at offsets 2b and 2b + 1 from the
    // frame's origin o: its centre is at offset 2b + 0.5, and the centre
    // x0 sits at (x0 - o - 0.5) / 2 in blocks.
    const ROI& img = m_in.image;
    const int x0   = m_x0 - img.xbegin, y0 = m_y0 - img.ybegin;
    const float bx0 = (float(x0) - 0.5f) * 0.5f;
    const float by0 = (float(y0) - 0.5f) * 0.5f;
    m_coarse_guide.centre_as(m_guide, bx0, by0, 2.0f);
    // The blocks wholly inside the window's square and the image (so that
    // a fit reads no pixel the exact filter would not, whatever the strip).
    const int bxa = std::max(block_of(std::max(x0 - R, 0) + 1), c.region.xbegin);
    const int bxb = std::min(block_of(std::min(x0 + R, img.width() - 1) - 1),
                             c.region.xend - 1);
    const int bya = std::max(block_of(std::max(y0 - R, 0) + 1), c.region.ybegin);
    const int byb = std::min(block_of(std::min(y0 + R, img.height() - 1) - 1),
                             c.region.yend - 1);
    if (bxb < bxa || byb < bya)
        return wf;
    const int n = bxb - bxa + 1;
    // Guide and fit weights, and <z> over the fit points with g > 0, as
    // grow_to() has them at full resolution.
    double zsum = 0.0, zcount = 0.0;
    // The range of the blocks' radiance: the splat's bound where no
    // full-resolution point of the window is a good one (a block's mean
    // normal can pass the centre's test where none of its pixels does).
    WindowRange blocks = WindowRange::empty();
    for (int by = bya; by <= byb; ++by) {
        const size_t k = size_t(by - bya) * size_t(n);
        const size_t i = c.index(bxa, by);
        float* g       = &m_coarse_g[k];
        float* fw      = &m_coarse_fit_weight[k];
        m_coarse_guide.row(bxa, by, n, g);
        for (int q = 0; q < n; ++q) {
            const size_t iq = i + size_t(q);
            fw[q]           = 0.0f;
            if (!(g[q] > 0.0f))
                continue;
            zsum += m_pyramid->zl_sum[iq];
            zcount += m_pyramid->fit_points[iq];
            if (c.cls[iq] & kFitPoint)
                fw[q] = g[q] * c.fit_prior[iq];
            if (fw[q] > 0.0f)
                blocks.add(c.lfit[0][iq], c.lfit[1][iq], c.lfit[2][iq]);
        }
    }
    if (!(zcount > 0.0))
        return wf;
    wf.mean  = float(zsum / zcount);
    wf.range = blocks;
    // e(d) = exp(-d^2/R^2) at fine offsets d = 2 (b - b0).
    const float inv_r2 = 1.0f / float(R * R);
    auto spatial = [&](float d_blocks) {
        const float d = 2.0f * d_blocks;
        return std::exp(-d * d * inv_r2);
    };
    for (int q = 0; q < n; ++q)
        m_coarse_spatial[size_t(q)] = spatial(float(bxa + q) - bx0);
    // No block lies on the centre's row or column: the blocks above the
    // centre (dy > 0) are cells 1 (left) and 0, those below 2 and 3.
    static const int kCellOfSide[2][3] = { { 2, 8, 3 }, { 1, 8, 0 } };
    FitColumns cols;
    cols.stride       = size_t(c.width);
    cols.cache_stride = size_t(n);
    cols.spatial      = m_coarse_spatial.data();
    cols.columns      = n;
    cols.mean         = wf.mean;
    cols.value_scale  = value_scale(wf.mean);
    cols.sums         = m_column_sums.data();
    cols.sums_stride  = column_sums_stride();
    for (int by = bya; by <= byb; ++by)
        m_coarse_ey[size_t(by - bya)] = spatial(float(by) - by0);
    // The first row above the centre.
    int above = bya;
    while (above <= byb && !(float(above) - by0 > 0.0f))
        ++above;
    FitMoments cells[9];
    double w2s2 = 0.0;
    const int groups[2][2] = { { bya, above - 1 }, { above, byb } };
    for (int k = 0; k < 2; ++k) {
        if (groups[k][1] < groups[k][0])
            continue;
        const size_t kq = size_t(groups[k][0] - bya) * size_t(n);
        set_plane_pointers(cols, c, c.index(bxa, groups[k][0]));
        cols.fit_weight = &m_coarse_fit_weight[kq];
        cols.values     = &m_coarse_values[kq];
        cols.ey         = &m_coarse_ey[size_t(groups[k][0] - bya)];
        cols.rows       = groups[k][1] - groups[k][0] + 1;
        cols.dy0        = float(groups[k][0]) - by0;
        fit_columns(cols);
        w2s2 += add_columns(cols.sums, cols.sums_stride, n, float(bxa) - bx0,
                            0.5 * double(R), kCellOfSide[k], cells);
    }
    solve_cells(wf, cells, w2s2);
    return wf;
}


void
WindowFitter::prepare_pyramid_splat(WindowFit& w)
{
    const int R = w.radius;
    grow_to(R);
    const ROI win = window_in_image(R);
    RangeLanes range;
    range.clear();
    float* values = m_value[w.values].data();
    for (int y = win.ybegin; y < win.yend; ++y) {
        const size_t i = m_in.index(win.xbegin, y);
        const size_t c = cache_index(win.xbegin - m_x0, y - m_y0);
        value_row(&m_fit_weight[c], &m_in.zl[i], &m_in.lfit[0][i],
                  &m_in.lfit[1][i], &m_in.lfit[2][i], values + c, &range,
                  win.width(), w.mean, value_scale(w.mean));
    }
    const WindowRange fine(range);
    if (fine.has_points())
        w.range = fine;
}


bool
WindowFitter::edge_fires(const WindowFit& w) const
{
    if (!w.whole.present)
        return false;
    const double zl  = w.whole.luminance0();
    const double azl = std::max(std::fabs(zl), kEps);
    for (const Plane& q : w.quadrant) {
        if (!q.present)
            continue;
        const double eta_m = std::sqrt(std::max(q.var0, 0.0)) / azl;
        const double tau   = std::max(double(m_opt.edge_k) * eta_m,
                                      double(m_opt.tau_min));
        if (std::fabs(zl - q.luminance0()) / azl > tau)
            return true;
    }
    return false;
}


void
WindowFitter::splat(const WindowFit& w, StopReason reason)
{
    const int R = w.radius;
    set_spatial(R);
    auto coeffs = [](const Plane& p) {
        PlaneCoeffs k;
        for (int ch = 0; ch < 3; ++ch) {
            k.c[ch] = float(p.c[ch]);
            k.a[ch] = float(p.a[ch]);
            k.b[ch] = float(p.b[ch]);
        }
        for (int t = 0; t < 6; ++t)
            k.hat[t] = float(p.hat[t]);
        return k;
    };
    const PlaneCoeffs whole = coeffs(w.whole);
    PlaneCoeffs quadrant[4];
    for (int q = 0; q < 4; ++q)
        quadrant[q] = w.quadrant[q].present ? coeffs(w.quadrant[q]) : whole;
    SplatRow row;
    row.inv_r       = 1.0f / float(R);
    row.mean        = w.mean;
    row.value_scale = value_scale(w.mean);
    row.power       = m_opt.quadrant_power;
    row.whole       = whole;
    row.range       = w.range;
    row.s           = m_splat_s.data();
    for (int ch = 0; ch < 3; ++ch) {
        row.a[ch]   = m_splat_a[ch].data();
        row.hat[ch] = m_hat ? m_splat_hat[ch].data() : nullptr;
    }
    const float* values = m_value[w.values].data();
    // Only output pixels receive.
    const int ya = std::max(m_y0 - R, m_out.ybegin);
    const int yb = std::min(m_y0 + R, m_out.yend - 1);
    const int xa = std::max(m_x0 - R, m_out.xbegin);
    const int xb = std::min(m_x0 + R, m_out.xend - 1);
    const size_t out_w = size_t(m_out.width());
    for (int y = ya; y <= yb; ++y) {
        const int dy = y - m_y0;
        row.v        = float(dy) * row.inv_r;
        row.ey       = m_spatial_row[size_t(dy + R)];
        // Left of the centre (dx < 0) quadrant 1 or 2, else 0 or 3.
        row.left  = quadrant[dy >= 0 ? 1 : 2];
        row.right = quadrant[dy >= 0 ? 0 : 3];
        const size_t i = m_in.index(xa, y);
        const size_t c = cache_index(xa - m_x0, dy);
        row.cls        = &m_in.cls[i];
        row.g          = &m_g[c];
        row.spatial    = &m_spatial_row[size_t(xa - m_x0 + R)];
        row.fit_weight = &m_fit_weight[c];
        row.values     = values + c;
        row.zl         = &m_in.zl[i];
        for (int ch = 0; ch < 3; ++ch)
            row.inv_albedo[ch] = &m_in.inv_albedo[ch][i];
        row.n   = xb - xa + 1;
        row.dx0 = float(xa - m_x0);
        splat_row(row);
        const size_t first = size_t(y - m_out.ybegin) * out_w + size_t(xa - m_out.xbegin);
        static_assert(kHatSums == 3, "accumulate_row adds three hat terms");
        accumulate_row(row, row.n, &m_acc[3 * first], &m_wsum[first],
                       m_hat ? &(*m_hat)[kHatSums * first] : nullptr);
        if (m_diagnostics)
            add_diagnostics(w, reason, first, row.n);
    }
}


void
WindowFitter::add_diagnostics(const WindowFit& w, StopReason reason,
                              size_t first, int n)
{
    const int by_reason = reason == StopReason::Quality ? kSumQuality
                          : reason == StopReason::Size  ? kSumSize
                                                        : kSumEdge;
    for (int q = 0; q < n; ++q) {
        const double sw = double(m_splat_s[size_t(q)]);
        if (!(sw > 0.0))
            continue;
        double* d = &(*m_diagnostics)[kDiagnosticSums * (first + size_t(q))];
        d[kSumRadius] += sw * double(w.radius);
        d[kSumEta] += sw * w.eta;
        d[by_reason] += sw;
    }
}


StopReason
WindowFitter::process(int x0, int y0, int& radius, bool splat_window)
{
    m_x0    = x0;
    m_y0    = y0;
    m_grown = -1;
    m_zsum  = 0.0;
    m_zcount = 0;
    m_range  = WindowRange::empty();
    m_guide.centre(x0, y0);
    // The value term's noise: section 3's smoothed variance at the centre
    // (none where it is undefined).
    const float vs0 = m_in.vs[m_in.index(x0, y0)];
    m_centre_noise  = vs0 > 0.0f && vs0 < INFINITY ? m_value_noise_t * std::sqrt(vs0) : 0.0f;

    WindowFit previous, current;
    StopReason reason = StopReason::Size;
    int fits = 0;
    for (int R = m_opt.r_min;; R = next_radius(R)) {
        const int values = fits++ & 1;
        const bool on_pyramid = m_pyramid && R >= m_opt.pyramid_radius;
        if (on_pyramid)
            current = fit_on_pyramid(R, values);
        if (!on_pyramid || !current.whole.present) {
            // The exact fit, also where level 1 has no block to fit.
            grow_to(R);
            current = fit(R, values);
        }
        if (edge_fires(current)) {
            reason = StopReason::Edge;
            if (R > m_opt.r_min)
                current = previous;
            break;
        }
        if (current.eta <= m_opt.eta_target) {
            reason = StopReason::Quality;
            break;
        }
        if (R >= m_opt.r_max) {
            reason = StopReason::Size;
            break;
        }
        previous = current;
    }
    radius = current.radius;
    if (current.whole.present && splat_window) {
        if (current.pyramid)
            prepare_pyramid_splat(current);
        splat(current, reason);
    }
    return reason;
}

}  // namespace detail
}  // namespace zdenoise
