// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The reference of docs/FILTER.md section 7b, the energy correction: the
// plain reading of the spec, in double, one pixel at a time.

#include "reference_filter.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace zdenoise_ref {

using zdenoise::FilterOptions;

namespace {

constexpr double kLuma[3] = { 0.2126, 0.7152, 0.0722 };

// Section 7b: one box pass of radius r along x or y, each box clipped to
// the image, in double.
std::vector<double>
box_pass(const std::vector<double>& v, int w, int h, int r, bool along_x)
{
    std::vector<double> out(v.size(), 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double sum = 0.0;
            int n      = 0;
            for (int d = -r; d <= r; ++d) {
                const int xn = along_x ? x + d : x, yn = along_x ? y : y + d;
                if (xn >= 0 && xn < w && yn >= 0 && yn < h) {
                    sum += v[size_t(yn) * w + xn];
                    ++n;
                }
            }
            out[size_t(y) * w + x] = sum / n;
        }
    return out;
}

// Section 7b: zf scaled towards z's light where their blurs differ by more
// than z's noise at that scale explains.
}  // namespace


RefImage
correct_energy(const RefImage& z, const RefImage& zf, const RefImage& La,
               const FilterOptions& opt)
{
    const int w = z.w, h = z.h, r = opt.energy_radius;
    const size_t n = size_t(w) * h;
    auto changed = [&](int x, int y) {
        for (int c = 0; c < 3; ++c)
            if (z.at(x, y, c) != zf.at(x, y, c))
                return true;
        return false;
    };
    // the radiance luminance: z times the albedo + eps (1 where not finite)
    auto light = [&](const RefImage& q, int x, int y) {
        double l = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double a = La.at(x, y, c);
            l += kLuma[c] * q.at(x, y, c)
                 * (std::isfinite(a) ? std::max(a, 0.0) + opt.albedo_eps : 1.0);
        }
        return l;
    };
    std::vector<double> li(n, 0.0), lo(n, 0.0), m(n, 0.0), e(n, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double a = light(z, x, y), b = light(zf, x, y);
            if (changed(x, y) && std::isfinite(a) && std::isfinite(b)) {
                li[size_t(y) * w + x] = a;
                lo[size_t(y) * w + x] = b;
                m[size_t(y) * w + x]  = 1.0;
            }
        }
    // each masked pixel's unbiased one-sample variance from its masked
    // 8-neighbours
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (m[size_t(y) * w + x] == 0.0)
                continue;
            double sum = 0.0;
            int k      = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                    if ((dx || dy) && z.inside(x + dx, y + dy)
                        && m[size_t(y + dy) * w + x + dx] != 0.0) {
                        sum += li[size_t(y + dy) * w + x + dx];
                        ++k;
                    }
            if (k) {
                const double d = li[size_t(y) * w + x] - sum / k;
                e[size_t(y) * w + x] = d * d * k / (k + 1.0);
            }
        }
    // each pixel's own noise, the 3x3 mean of e (boxes clipped), and light
    const std::vector<double> own = box_pass(box_pass(e, w, h, 1, true), w, h, 1, false);
    const std::vector<double> own_light = lo;
    for (std::vector<double>* v : { &li, &lo, &m, &e })
        for (int pass = 0; pass < 3; ++pass)
            *v = box_pass(box_pass(*v, w, h, r, true), w, h, r, false);
    // the squared weights of the 2-D kernel away from the edges
    std::vector<double> k1(1, 1.0);
    for (int pass = 0; pass < 3; ++pass) {
        std::vector<double> next(k1.size() + 2 * r, 0.0);
        for (size_t i = 0; i < k1.size(); ++i)
            for (int d = 0; d <= 2 * r; ++d)
                next[i + d] += k1[i] / (2 * r + 1);
        k1 = next;
    }
    double s1 = 0.0;
    for (double x : k1)
        s1 += x * x;
    RefImage out = zf;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            if (!changed(x, y) || !(m[i] > 0.0))
                continue;
            const double mi = li[i] / m[i], mo = lo[i] / m[i];
            if (!(mi > 0.0) || !(mo > 0.0))
                continue;
            const double v    = e[i] / m[i] * s1 * s1 / m[i];
            const double d    = mi - mo;
            const double keep = d * d > v ? 1.0 - v / (d * d) : 0.0;
            double f = std::min(std::max(1.0 + keep * (mi / mo - 1.0), 0.5), 2.0);
            // no pixel moved by more than its own standard deviation
            const double sd = std::sqrt(own[i]), change = (f - 1.0) * own_light[i];
            if (std::abs(change) > sd && own_light[i] > 0.0)
                f = 1.0 + std::copysign(sd, change) / own_light[i];
            for (int c = 0; c < 3; ++c)
                out.at(x, y, c) = float(zf.at(x, y, c) * f);
        }
    return out;
}

}  // namespace zdenoise_ref
