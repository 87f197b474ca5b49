// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The noise estimate that does not take thin structure for noise
// (docs/FILTER.md section 14, step 1): for each of four directions the
// mean, over the 5x5 on the pixel's surface, of the squared second
// differences along it; the smallest of the four, over its bias. A shadow
// line or an edge along one direction leaves that direction's differences
// at the noise. Shared by keep_structure() (significance_filter.cpp, on the
// light's own planes) and the filter's noise estimate with
// FilterOptions::directional_noise (noise_estimate.cpp, on its fit points).

#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// Half-size of the box over which squared second differences are pooled.
constexpr int kDirectionalBox = 2;

/// The mean of the smallest of the four directions' 5x5 pools of squared
/// second differences (each over 1.5, unbiased alone) on unit Gaussian
/// noise: the minimum of four is biased low by this factor
/// (tests/test_significance.cpp measures it). The mean of the pools that
/// agree with the smallest (within 3x), nearly unbiased, measured worse on
/// the interiors (docs/FILTER.md section 14).
constexpr float kMinimumOfFourBias = 0.743f;

/// V at every pixel of p.region, NaN where it cannot be estimated (the
/// pixel takes no part, or no direction has 3 differences on its surface).
/// `Plane` gives: `region`, `index(x, y)`, `inside(x, y)`,
/// `same_surface(a, b)` and `value(i)` (the luminance, NaN where the pixel
/// takes no part).
template<class Plane>
std::vector<float>
directional_variance(const Plane& p, int nthreads)
{
    static const int kDirections[4][2] = { { 1, 0 }, { 0, 1 }, { 1, 1 }, { 1, -1 } };
    constexpr float nan = std::numeric_limits<float>::quiet_NaN();
    const ROI& r   = p.region;
    const size_t n = r.npixels();
    // The squared second difference along each direction, over 1.5 (its
    // variance is 1.5 V on noise of variance V): NaN where a point is
    // outside, takes no part, or is on another surface.
    std::vector<float> e(4 * n, nan);
    for_rows(r, nthreads, [&](int y) {
        for (int x = r.xbegin; x < r.xend; ++x)
            for (int d = 0; d < 4; ++d) {
                const int dx = kDirections[d][0], dy = kDirections[d][1];
                if (!p.inside(x - dx, y - dy) || !p.inside(x + dx, y + dy))
                    continue;
                const size_t c = p.index(x, y), a = p.index(x - dx, y - dy),
                             b = p.index(x + dx, y + dy);
                if (!p.same_surface(c, a) || !p.same_surface(c, b))
                    continue;
                const float diff = p.value(c) - 0.5f * (p.value(a) + p.value(b));
                e[4 * c + size_t(d)] = diff * diff / 1.5f;  // NaN propagates
            }
    });
    std::vector<float> var(n, nan);
    for_rows(r, nthreads, [&](int y) {
        for (int x = r.xbegin; x < r.xend; ++x) {
            const size_t c = p.index(x, y);
            if (!std::isfinite(p.value(c)))
                continue;
            float sum[4] = { 0, 0, 0, 0 };
            int count[4] = { 0, 0, 0, 0 };
            for (int v = y - kDirectionalBox; v <= y + kDirectionalBox; ++v)
                for (int u = x - kDirectionalBox; u <= x + kDirectionalBox; ++u) {
                    if (!p.inside(u, v))
                        continue;
                    const size_t i = p.index(u, v);
                    if (!p.same_surface(c, i))
                        continue;
                    for (int d = 0; d < 4; ++d)
                        if (std::isfinite(e[4 * i + size_t(d)])) {
                            sum[d] += e[4 * i + size_t(d)];
                            ++count[d];
                        }
                }
            float best = nan;
            for (int d = 0; d < 4; ++d)
                if (count[d] >= 3 && !(best <= sum[d] / float(count[d])))
                    best = sum[d] / float(count[d]);
            var[c] = best / kMinimumOfFourBias;
        }
    });
    return var;
}

}  // namespace detail
}  // namespace zdenoise
