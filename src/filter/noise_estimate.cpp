// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The noise estimate (docs/FILTER.md section 3): one function per source of
// the variance, and the smoothing the fit reads.

#include "noise_estimate.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "directional_variance.h"
#include "internal.h"
#include "median_kernel.h"

namespace zdenoise {
namespace detail {

namespace {

// Median of the chi-square distribution with one degree of freedom: turns
// the median of squared residuals into a variance.
constexpr float kChi2Median = 0.4549364f;

constexpr float kUndefined = std::numeric_limits<float>::quiet_NaN();

bool
fit_point(const FilterInputs& in, size_t i)
{
    return (in.cls[i] & kFitPoint) != 0;
}

/// The variance of pixel i's quotient luminance from the radiance's
/// per-channel variances varL (one value when stride is 1): their
/// luminance-weighted mean, each divided by the squared albedo.
float
quotient_variance(const std::vector<float>& albedo, float eps_a, size_t i,
                  const float* varL, int stride)
{
    float v = 0.0f;
    for (int c = 0; c < 3; ++c) {
        const float vl = varL[stride == 1 ? 0 : c];
        const float a  = albedo[3 * i + c] + eps_a;
        v += kLumaWeights[c] * vl / (a * a);
    }
    return (std::isfinite(v) && v >= 0.0f) ? v : kUndefined;
}

/// The robust local variance of section 3: at each fit point, the median
/// of the squared residuals `e` (each an unbiased one-sample estimate of V,
/// NaN where undefined) over its 5x5, divided by the median of chi-square
/// with one degree of freedom; 0 where no e is defined. Edges and isolated
/// fireflies do not inflate it.
RawVariance
robust_variance(const FilterInputs& in, const RawVariance& e, int nthreads)
{
    RawVariance var(in.region.npixels(), kUndefined);
    auto fit = [&](size_t i) { return fit_point(in, i); };
    const int w = in.width;
    for_rows(in.region, nthreads, [&](int y) {
        // The boxes wholly inside the region, a row at a time
        // (median_kernel.h); the rest, and boxes holding a NaN, one by one.
        const int y0 = y - in.region.ybegin;
        std::vector<float> boxed;
        if (y0 >= 2 && y0 + 2 < in.height && w > 4) {
            const float* rows[5];
            for (int dy = 0; dy < 5; ++dy)
                rows[dy] = &e[size_t(y0 - 2 + dy) * size_t(w)];
            boxed.resize(size_t(w - 4));
            median5x5_row(rows, w - 4, boxed.data());
        }
        float window[25];
        for (int x = in.region.xbegin; x < in.region.xend; ++x) {
            const size_t i = in.index(x, y);
            if (!fit(i))
                continue;
            const int bx = x - in.region.xbegin - 2;
            if (bx >= 0 && size_t(bx) < boxed.size() && !std::isnan(boxed[size_t(bx)])) {
                var[i] = boxed[size_t(bx)] / kChi2Median;
                continue;
            }
            int n = 0;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx)
                    if (in.in_region(x + dx, y + dy)) {
                        const float eq = e[in.index(x + dx, y + dy)];
                        if (!std::isnan(eq))
                            window[n++] = eq;
                    }
            if (n == 0) {
                var[i] = 0.0f;
                continue;
            }
            var[i] = median(window, n) / kChi2Median;
        }
    });
    return var;
}

}  // namespace


float
median(float* v, int n)
{
    std::nth_element(v, v + n / 2, v + n);
    const float upper = v[n / 2];
    if (n & 1)
        return upper;
    return 0.5f * (*std::max_element(v, v + n / 2) + upper);
}


/// Are two pixels on the same surface for the noise estimate: same (plain
/// or primary Cryptomatte) id, and close normals when normals are given.
bool
same_surface(const FilterInputs& in, size_t a, size_t b)
{
    if (in.has_normal()) {
        const float na[3] = { in.normal[0][a], in.normal[1][a], in.normal[2][a] };
        const float nb[3] = { in.normal[0][b], in.normal[1][b], in.normal[2][b] };
        const bool za = no_normal(na), zb = no_normal(nb);
        if (za != zb)
            return false;
        if (!za && na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2] <= 0.9f)
            return false;
    }
    if (in.id_pairs == -1)
        return same_id(in.ids[0][a], in.ids[0][b]);
    if (in.id_pairs > 0) {
        // Primary id: the rank of largest coverage (the first of equals).
        auto primary = [&](size_t i, float& id) {
            float best = 0.0f;
            bool any   = false;
            for (size_t k = 0; k < size_t(in.id_pairs); ++k)
                if (in.ids[2 * k + 1][i] > best) {
                    best = in.ids[2 * k + 1][i];
                    id   = in.ids[2 * k][i];
                    any  = true;
                }
            return any;
        };
        float ida = 0, idb = 0;
        const bool ha = primary(a, ida), hb = primary(b, idb);
        if (ha != hb || (ha && !same_id(ida, idb)))
            return false;
    }
    return true;
}


RawVariance
variance_from_guide(const FilterInputs& in, const ImageBuf& variance,
                    const std::vector<float>& albedo, float albedo_eps)
{
    const size_t npix = in.region.npixels();
    RawVariance var(npix, kUndefined);
    const int nch = variance.nchannels() >= 3 ? 3 : 1;
    std::vector<float> vl = read_channels(variance, in.region, 0, nch);
    for (size_t i = 0; i < npix; ++i)
        if (fit_point(in, i))
            var[i] = quotient_variance(albedo, albedo_eps, i,
                                       &vl[size_t(nch) * i], nch);
    return var;
}


RawVariance
variance_from_halves(const FilterInputs& in, const ImageBuf& half_a,
                     const ImageBuf& half_b, const std::vector<float>& albedo,
                     float albedo_eps, int nthreads)
{
    const size_t npix = in.region.npixels();
    RawVariance e(npix, kUndefined);
    std::vector<float> a = read_channels(half_a, in.region, 0, 3);
    std::vector<float> b = read_channels(half_b, in.region, 0, 3);
    for (size_t i = 0; i < npix; ++i) {
        if (!fit_point(in, i))
            continue;
        float vl[3];
        for (int c = 0; c < 3; ++c) {
            const float d = a[3 * i + c] - b[3 * i + c];
            vl[c]         = 0.25f * d * d;
        }
        e[i] = quotient_variance(albedo, albedo_eps, i, vl, 3);
    }
    // One pair of samples a pixel is a variance estimate with one degree of
    // freedom: too noisy to stop windows on. The same robust 5x5 estimate
    // as the image's own (docs/FILTER.md section 3).
    return robust_variance(in, e, nthreads);
}


RawVariance
variance_from_image(const FilterInputs& in, int nthreads)
{
    const size_t npix = in.region.npixels();
    auto fit = [&](size_t i) { return fit_point(in, i); };
    const float nan = kUndefined;
    // Estimated from z: squared residuals against the 8-neighbour mean
    // on the same surface, then a robust (median) 5x5 estimate.
    std::vector<float> resid(npix, nan);
    for_rows(in.region, nthreads, [&](int y) {
        for (int x = in.region.xbegin; x < in.region.xend; ++x) {
            const size_t i = in.index(x, y);
            if (!fit(i))
                continue;
            double sum = 0.0;
            int n      = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    if ((dx | dy) == 0 || !in.in_region(x + dx, y + dy))
                        continue;
                    const size_t j = in.index(x + dx, y + dy);
                    if (fit(j) && same_surface(in, i, j)) {
                        sum += in.zl[j];
                        ++n;
                    }
                }
            if (n > 0) {
                const double r = in.zl[i] - sum / n;
                resid[i]       = float(r * r * n / (n + 1));
            }
        }
    });
    return robust_variance(in, resid, nthreads);
}


RawVariance
variance_directional(const FilterInputs& in, int nthreads)
{
    // The fit points' luminance on the filter's surfaces (same_surface()).
    struct FitPoints {
        const FilterInputs& in;
        const ROI& region;
        size_t index(int x, int y) const { return in.index(x, y); }
        bool inside(int x, int y) const { return in.in_region(x, y); }
        bool same_surface(size_t a, size_t b) const
        {
            return detail::same_surface(in, a, b);
        }
        float value(size_t i) const { return fit_point(in, i) ? in.zl[i] : kUndefined; }
    };
    return directional_variance(FitPoints { in, in.region }, nthreads);
}


void
smooth_noise(FilterInputs& in, const RawVariance& var, int nthreads)
{
    const size_t npix = in.region.npixels();
    auto fit = [&](size_t i) { return fit_point(in, i); };
    in.vs.assign(npix, 0.0f);
    in.sigma.assign(npix, 0.0f);
    for_rows(in.region, nthreads, [&](int y) {
        for (int x = in.region.xbegin; x < in.region.xend; ++x) {
            const size_t i = in.index(x, y);
            if (!fit(i))
                continue;
            double vsum = 0.0, zsum = 0.0;
            int nv = 0, nz = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    if (!in.in_region(x + dx, y + dy))
                        continue;
                    const size_t j = in.index(x + dx, y + dy);
                    if (!fit(j))
                        continue;
                    zsum += in.zl[j];
                    ++nz;
                    if (!std::isnan(var[j])) {
                        vsum += var[j];
                        ++nv;
                    }
                }
            const float vs = nv ? float(vsum / nv) : 0.0f;
            const float zs = float(zsum / nz);
            in.vs[i]       = vs;
            in.sigma[i]    = std::sqrt(vs) / std::max(std::fabs(zs), float(kEps));
        }
    });
}


RawVariance
raw_variance(const FilterInputs& in, const Guides& guides,
             const std::vector<float>& albedo, float albedo_eps,
             bool directional, int nthreads)
{
    // With `directional` (a direct layer's light), the smaller of the two
    // estimates: each reads some structure as noise (the median a lattice
    // of lines, the four directions' pools a line at another angle or a
    // corner), and both are calibrated on noise alone.
    auto own = [&] {
        RawVariance var = variance_from_image(in, nthreads);
        if (directional) {
            const RawVariance d = variance_directional(in, nthreads);
            for (size_t i = 0; i < var.size(); ++i)
                if (d[i] < var[i])
                    var[i] = d[i];
        }
        return var;
    };
    if (guides.variance)
        return variance_from_guide(in, *guides.variance, albedo, albedo_eps);
    if (guides.half_a && guides.half_b) {
        RawVariance var = variance_from_halves(in, *guides.half_a,
                                               *guides.half_b, albedo,
                                               albedo_eps, nthreads);
        const RawVariance image = own();
        for (size_t i = 0; i < var.size(); ++i)
            if (image[i] > var[i] || std::isnan(var[i]))
                var[i] = image[i];
        return var;
    }
    return own();
}

}  // namespace detail
}  // namespace zdenoise
