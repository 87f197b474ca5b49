// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Outliers split off and spread (docs/FILTER.md section 3a).

#include "outliers.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "guide_weight.h"
#include "internal.h"

namespace zdenoise {
namespace detail {

namespace {

/// The standard normal quantile Phi^-1(p) for p in [0.5, 1), by bisection
/// of erfc (60 halvings: exact to double precision; called once a call).
double
normal_quantile(double p)
{
    double lo = 0.0, hi = 40.0;
    for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

}  // namespace


float
outlier_threshold(int r_max)
{
    const double n = double(2 * r_max + 1) * double(2 * r_max + 1);
    return float(normal_quantile(1.0 - 1.0 / n));
}


std::vector<Outlier>
split_outliers(FilterInputs& in, std::vector<float>& z,
               const std::vector<float>& albedo, const RawVariance& var,
               const FilterOptions& opt, int nthreads)
{
    const ROI& r     = in.region;
    const float t    = outlier_threshold(opt.r_max);
    const float eps  = opt.albedo_eps;
    auto fit         = [&](size_t i) { return (in.cls[i] & kFitPoint) != 0; };
    // Decide on the unchanged luminance first (every test reads the
    // neighbours' original values), then cap.
    std::vector<float> cap(r.npixels(), 0.0f);
    for_rows(r, nthreads, [&](int y) {
        // Cancelled: the rows left are skipped (decode_filter_inputs()
        // then drops the result).
        if (cancel_requested(opt))
            return;
        float level[25], spread[25];
        for (int x = r.xbegin; x < r.xend; ++x) {
            const size_t i = in.index(x, y);
            if (!fit(i))
                continue;
            // Its brightest same-surface neighbour first: most points are
            // below it and need no more.
            float neighbour = -std::numeric_limits<float>::infinity();
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    if ((dx | dy) == 0 || !in.in_region(x + dx, y + dy))
                        continue;
                    const size_t j = in.index(x + dx, y + dy);
                    if (fit(j) && in.zl[j] > neighbour && same_surface(in, i, j))
                        neighbour = in.zl[j];
                }
            if (!(in.zl[i] > neighbour))
                continue;
            int nl = 0, ns = 0;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx) {
                    if (!in.in_region(x + dx, y + dy))
                        continue;
                    const size_t j = in.index(x + dx, y + dy);
                    if (!fit(j) || !same_surface(in, i, j))
                        continue;
                    level[nl++] = in.zl[j];
                    if (!std::isnan(var[j]))
                        spread[ns++] = var[j];
                }
            if (ns == 0)
                continue;
            // The neighbourhood's level and its noise, both medians: the
            // outlier itself moves neither. A point is capped only above
            // both that and its brightest neighbour: light that two
            // neighbours share is structure, not a lone sample.
            const float mu  = median(level, nl);
            const float sd  = std::sqrt(median(spread, ns));
            const float top = std::max(mu + t * sd, neighbour);
            if (in.zl[i] > top && top > 0.0f)
                cap[i] = top;
        }
    });
    std::vector<Outlier> outliers;
    for (int y = r.ybegin; y < r.yend; ++y)
        for (int x = r.xbegin; x < r.xend; ++x) {
            const size_t i = in.index(x, y);
            if (!(cap[i] > 0.0f))
                continue;
            const float keep = cap[i] / in.zl[i];
            Outlier o;
            o.x = x;
            o.y = y;
            for (int c = 0; c < 3; ++c) {
                float& zc    = z[3 * i + c];
                o.excess[c]  = zc * (1.0f - keep) * (albedo[3 * i + c] + eps);
                zc          *= keep;
            }
            in.zl[i] = cap[i];
            outliers.push_back(o);
        }
    return outliers;
}


void
spread_outliers(const FilterInputs& in, const FilterOptions& opt,
                const ROI& out, std::vector<double>& spread, int nthreads)
{
    const int R      = opt.r_max;
    const ROI& image = in.image;
    // Only an outlier within r_max of the output reaches it; in.outliers is
    // in raster order, so these are too.
    std::vector<const Outlier*> near;
    for (const Outlier& o : in.outliers)
        if (o.x >= out.xbegin - R && o.x < out.xend + R && o.y >= out.ybegin - R
            && o.y < out.yend + R)
            near.push_back(&o);
    if (near.empty())
        return;
    // exp(-d^2 / R^2) at d + R.
    std::vector<float> spatial(size_t(2 * R + 1));
    for (int d = -R; d <= R; ++d)
        spatial[size_t(d + R)] = std::exp(-float(d * d) / float(R * R));
    // The weights w(q) = g(q; p) exp(-|q - p|^2 / R^2) of one outlier's row y
    // into g (xa..xb): the same floats in both passes.
    struct Span {
        int xa, xb, ya, yb;
    };
    auto span = [&](const Outlier& o) {
        return Span { std::max(o.x - R, image.xbegin), std::min(o.x + R, image.xend - 1),
                      std::max(o.y - R, image.ybegin), std::min(o.y + R, image.yend - 1) };
    };
    auto row_weights = [&](GuideWeight& guide, const Outlier& o, const Span& sp,
                           int y, float* g) {
        const int n = sp.xb - sp.xa + 1;
        guide.row(sp.xa, y, n, g);
        const float ey = spatial[size_t(y - o.y + R)];
        for (int k = 0; k < n; ++k)
            g[k] *= ey * spatial[size_t(sp.xa + k - o.x + R)];
    };
    // Pass 1, per outlier: the sum of w(q) (La_c(q) + eps) over every
    // receiver of its window (not only the output's), so that the result
    // is the same for any tile.
    std::vector<std::array<double, 3>> norm(near.size());
    // Cancelled (opt.cancel): every remaining outlier or row returns at
    // once, and the caller drops the spread.
    OIIO::parallel_for(int64_t(0), int64_t(near.size()), [&](int64_t k) {
        if (cancel_requested(opt))
            return;
        const Outlier& o = *near[size_t(k)];
        const Span sp    = span(o);
        GuideWeight guide(in, opt);
        guide.centre(o.x, o.y);
        std::vector<float> g(size_t(2 * R + 1) + kLanes);
        std::array<double, 3> sum = { 0.0, 0.0, 0.0 };
        for (int y = sp.ya; y <= sp.yb; ++y) {
            row_weights(guide, o, sp, y, g.data());
            for (int x = sp.xa; x <= sp.xb; ++x) {
                const float w = g[size_t(x - sp.xa)];
                if (!(w > 0.0f))
                    continue;
                const size_t i = in.index(x, y);
                for (int c = 0; c < 3; ++c)
                    if (in.cls[i] & (kReceiveR << c))
                        sum[size_t(c)] += double(w) / double(in.inv_albedo[c][i]);
            }
        }
        norm[size_t(k)] = sum;
    }, paropt_any_length(nthreads));
    // Pass 2, per output row: z_c(q) += excess_c w(q) / norm_c, the outliers
    // in raster order (each row on its own: any thread count, same sums).
    // The light added is smooth, and its radiance is the excess.
    const size_t out_w = size_t(out.width());
    OIIO::parallel_for(int64_t(out.ybegin), int64_t(out.yend), [&](int64_t yy) {
        if (cancel_requested(opt))
            return;
        const int y = int(yy);
        GuideWeight guide(in, opt);
        std::vector<float> g(size_t(2 * R + 1) + kLanes);
        // The outliers of rows y - R .. y + R (near is sorted by row).
        const size_t first = size_t(
            std::lower_bound(near.begin(), near.end(), y - R,
                             [](const Outlier* o, int row) { return o->y < row; })
            - near.begin());
        for (size_t k = first; k < near.size() && near[k]->y <= y + R; ++k) {
            const Outlier& o = *near[k];
            const Span sp = span(o);
            guide.centre(o.x, o.y);
            row_weights(guide, o, sp, y, g.data());
            const int xa = std::max(sp.xa, out.xbegin), xb = std::min(sp.xb, out.xend - 1);
            for (int x = xa; x <= xb; ++x) {
                const float w = g[size_t(x - sp.xa)];
                if (!(w > 0.0f))
                    continue;
                const size_t i = in.index(x, y);
                double* s = &spread[3 * (size_t(y - out.ybegin) * out_w
                                         + size_t(x - out.xbegin))];
                for (int c = 0; c < 3; ++c)
                    if ((in.cls[i] & (kReceiveR << c)) && norm[k][size_t(c)] > 0.0)
                        s[c] += double(o.excess[c]) * double(w) / norm[k][size_t(c)];
            }
        }
    }, paropt_any_length(nthreads));
}

}  // namespace detail
}  // namespace zdenoise
