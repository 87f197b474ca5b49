// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Holes filled from the light around them (docs/FILTER.md section 7).

#include "hole_fill.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "guide_weight.h"
#include "plane_fit.h"

namespace zdenoise {
namespace detail {

bool
hole_light(const FilterInputs& in, const FilterOptions& opt, int x, int y,
           float light[3])
{
    const int R      = hole_fill_radius(opt);
    const ROI& image = in.image;
    const int xa = std::max(x - R, image.xbegin), xb = std::min(x + R, image.xend - 1);
    const int ya = std::max(y - R, image.ybegin), yb = std::min(y + R, image.yend - 1);
    GuideWeight guide(in, opt);
    guide.centre(x, y);
    std::vector<float> g(size_t(xb - xa + 1) + kLanes);
    const double r2 = double(opt.r_max) * double(opt.r_max);
    // The weighted plane of section 5 through the light around the hole,
    // evaluated at (x, y): a hole in a gradient of light takes the gradient.
    FitMoments m;
    double lo[3], hi[3];
    std::fill(lo, lo + 3, std::numeric_limits<double>::infinity());
    std::fill(hi, hi + 3, -std::numeric_limits<double>::infinity());
    for (int yq = ya; yq <= yb; ++yq) {
        guide.row(xa, yq, xb - xa + 1, g.data());
        for (int xq = xa; xq <= xb; ++xq) {
            const size_t i = in.index(xq, yq);
            const float gq = g[size_t(xq - xa)];
            if (!(gq > 0.0f) || !(in.cls[i] & kFitPoint))
                continue;
            const double d2 = double((xq - x) * (xq - x) + (yq - y) * (yq - y));
            const double w  = double(gq) * std::exp(-d2 / r2);
            const double u = double(xq - x) / R, v = double(yq - y) / R;
            const double k[6] = { 1.0, u, v, u * u, u * v, v * v };
            for (int j = 0; j < 6; ++j)
                m.s[j] += w * k[j];
            for (int c = 0; c < 3; ++c) {
                const double zq = in.zfit[c][i];
                m.t[c][0] += w * zq;
                m.t[c][1] += w * zq * u;
                m.t[c][2] += w * zq * v;
                lo[c] = std::min(lo[c], zq);
                hi[c] = std::max(hi[c], zq);
            }
            m.count += 1;
        }
    }
    const Plane p = solve(m);
    if (!p.present)
        return false;
    // Within the light it was fitted to: no invented light.
    for (int c = 0; c < 3; ++c)
        light[c] = float(std::min(std::max(p.c[c], lo[c]), hi[c]));
    return true;
}

}  // namespace detail
}  // namespace zdenoise
