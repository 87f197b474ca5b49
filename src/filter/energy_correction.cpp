// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The low-frequency energy correction (docs/FILTER.md section 7b). The
// value term weighs the bright tail of skewed Monte Carlo noise down, so
// at low sample counts the filtered light comes out low, and low by
// different amounts from place to place: blotches. The input's blur at a
// scale of tens of pixels is unbiased and, there, nearly noise-free; the
// filtered light is scaled towards it by as much as the difference
// exceeds what the input's noise at that scale explains (a Wiener-style
// shrinkage), so a correct region is left alone.

#include "energy_correction.h"

#include <algorithm>
#include <cmath>

#include "internal.h"

namespace zdenoise {
namespace detail {

namespace {

/// `v` (w x h, row-major) replaced by the mean over each pixel's box of
/// radius r along x or y, the box clipped to the w x h area. Each box is
/// summed in double from its first pixel to its last, not from a running
/// or prefix sum: an area placed elsewhere in the frame (a strip, a tile)
/// gives every box it holds whole the same bits.
void
box_pass(std::vector<float>& v, int w, int h, int r, bool along_x, int nthreads)
{
    // How many of the box's 2 r + 1 pixels lie in [0, n).
    auto inside = [r](int i, int n) { return std::min(i + r, n - 1) - std::max(i - r, 0) + 1; };
    std::vector<float> out(v.size());
    for_ranges(size_t(h), nthreads, [&](size_t b, size_t e) {
        std::vector<double> acc(static_cast<size_t>(w));
        for (size_t y = b; y < e; ++y) {
            std::fill(acc.begin(), acc.end(), 0.0);
            for (int d = -r; d <= r; ++d) {
                if (along_x) {
                    const float* row = &v[y * size_t(w)];
                    for (int x = std::max(0, -d); x < std::min(w, w - d); ++x)
                        acc[size_t(x)] += row[x + d];
                } else {
                    const int yn = int(y) + d;
                    if (yn < 0 || yn >= h)
                        continue;
                    const float* row = &v[size_t(yn) * size_t(w)];
                    for (int x = 0; x < w; ++x)
                        acc[size_t(x)] += row[x];
                }
            }
            const int rows = inside(int(y), h);
            for (int x = 0; x < w; ++x)
                out[y * size_t(w) + size_t(x)]
                    = float(acc[size_t(x)] / (along_x ? inside(x, w) : rows));
        }
    });
    v.swap(out);
}


/// Three box passes of radius r in x and in y: close to a Gaussian of
/// standard deviation sqrt(r (r + 1)).
void
blur(std::vector<float>& v, int w, int h, int r, int nthreads)
{
    for (int pass = 0; pass < 3; ++pass) {
        box_pass(v, w, h, r, true, nthreads);
        box_pass(v, w, h, r, false, nthreads);
    }
}


/// The sum of the squared weights of blur()'s kernel away from edges:
/// what the variance of a mean over it is of one pixel's.
double
blur_square_sum(int r)
{
    std::vector<double> k(1, 1.0);
    for (int pass = 0; pass < 3; ++pass) {
        std::vector<double> next(k.size() + size_t(2 * r), 0.0);
        for (size_t i = 0; i < k.size(); ++i)
            for (int d = 0; d <= 2 * r; ++d)
                next[i + size_t(d)] += k[i] / (2 * r + 1);
        k.swap(next);
    }
    double s = 0.0;
    for (double x : k)
        s += x * x;
    return s * s;  // x and y
}


/// The radiance luminance of quotient pixel i: z times the albedo the
/// filter divided by (1 where that is not finite).
float
radiance_luminance(const float* z, const float* albedo, float eps)
{
    float l = 0.0f;
    for (int c = 0; c < 3; ++c) {
        const float a = std::isfinite(albedo[c]) ? std::max(albedo[c], 0.0f) + eps : 1.0f;
        l += kLumaWeights[c] * z[c] * a;
    }
    return l;
}


/// Each masked pixel's squared difference from the mean of its masked
/// 8-neighbours, scaled to be an unbiased estimate of its variance; 0
/// elsewhere.
std::vector<float>
squared_differences(const std::vector<float>& l, const std::vector<float>& mask,
                    int w, int h, int nthreads)
{
    std::vector<float> e(l.size(), 0.0f);
    for_ranges(size_t(h), nthreads, [&](size_t b, size_t end) {
        for (int y = int(b); y < int(end); ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = size_t(y) * size_t(w) + size_t(x);
                if (mask[i] == 0.0f)
                    continue;
                double sum = 0.0;
                int n      = 0;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int xn = x + dx, yn = y + dy;
                        if ((dx | dy) == 0 || xn < 0 || yn < 0 || xn >= w || yn >= h)
                            continue;
                        const size_t j = size_t(yn) * size_t(w) + size_t(xn);
                        if (mask[j] != 0.0f) {
                            sum += l[j];
                            ++n;
                        }
                    }
                if (n > 0) {
                    const double r = l[i] - sum / n;
                    e[i]           = float(r * r * n / (n + 1));
                }
            }
    });
    return e;
}

}  // namespace


void
correct_energy(ImageBuf& dst, const ImageBuf& filtered, const ImageBuf& quotient,
               const ImageBuf& albedo, float albedo_eps, int radius, ROI roi,
               ROI area, int nthreads)
{
    const int w = area.width(), h = area.height();
    const size_t npix = size_t(w) * size_t(h);
    const std::vector<float> zin  = read_channels(quotient, area, 0, 3);
    const std::vector<float> zout = read_channels(filtered, area, 0, 3);
    const std::vector<float> alb  = read_channels(albedo, area, 0, 3);
    auto changed = [&](size_t i) {
        return zin[3 * i] != zout[3 * i] || zin[3 * i + 1] != zout[3 * i + 1]
               || zin[3 * i + 2] != zout[3 * i + 2];
    };
    // The light in and out where the filter changed a pixel (the mask).
    std::vector<float> lin(npix, 0.0f), lout(npix, 0.0f), mask(npix, 0.0f);
    for_ranges(npix, nthreads, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            const float* a = &alb[3 * i];
            const float li = radiance_luminance(&zin[3 * i], a, albedo_eps);
            const float lo = radiance_luminance(&zout[3 * i], a, albedo_eps);
            if (changed(i) && std::isfinite(li) && std::isfinite(lo)) {
                lin[i]  = li;
                lout[i] = lo;
                mask[i] = 1.0f;
            }
        }
    });
    std::vector<float> var = squared_differences(lin, mask, w, h, nthreads);
    // Each pixel's own noise (the 3x3 mean of e) and light: no pixel moves
    // by more than one standard deviation of its own, so a clean region
    // beside a noisy one keeps what the filter gave it.
    std::vector<float> own_var = var;
    box_pass(own_var, w, h, 1, true, nthreads);
    box_pass(own_var, w, h, 1, false, nthreads);
    const std::vector<float> own_light = lout;
    for (std::vector<float>* v : { &lin, &lout, &mask, &var })
        blur(*v, w, h, radius, nthreads);
    const double square_sum = blur_square_sum(radius);

    // roi's RGB, as filtered (what `filtered` holds there) and corrected.
    ROI rgb = roi;
    rgb.chbegin = 0;
    rgb.chend   = 3;
    const int rw = roi.width();
    std::vector<float> out(3 * size_t(rw) * size_t(roi.height()));
    for_ranges(size_t(roi.height()), nthreads, [&](size_t b, size_t e) {
        for (size_t ry = b; ry < e; ++ry)
            for (int rx = 0; rx < rw; ++rx) {
                const int x = roi.xbegin + rx, y = roi.ybegin + int(ry);
                const size_t i = size_t(y - area.ybegin) * size_t(w)
                                 + size_t(x - area.xbegin);
                float* o = &out[3 * (ry * size_t(rw) + size_t(rx))];
                for (int c = 0; c < 3; ++c)
                    o[c] = zout[3 * i + size_t(c)];
                const double m = mask[i];
                if (!changed(i) || !(m > 0.0))
                    continue;  // left as it was: not ours to change
                const double mi = lin[i] / m, mo = lout[i] / m;
                if (!(mi > 0.0) || !(mo > 0.0))
                    continue;
                // The variance of the input's blur: its pixels' over the
                // kernel's effective count (square_sum / m).
                const double v = var[i] / m * square_sum / m;
                const double d = mi - mo;
                const double keep = d * d > v ? 1.0 - v / (d * d) : 0.0;
                double k = std::min(std::max(1.0 + keep * (mi / mo - 1.0), 0.5), 2.0);
                const double sd = std::sqrt(double(own_var[i]));
                const double change = (k - 1.0) * own_light[i];
                if (std::abs(change) > sd && own_light[i] > 0.0f)
                    k = 1.0 + std::copysign(sd, change) / own_light[i];
                for (int c = 0; c < 3; ++c)
                    o[c] = float(o[c] * k);
            }
    });
    dst.set_pixels(rgb, OIIO::TypeFloat, out.data());
}

}  // namespace detail
}  // namespace zdenoise
