// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// significance_filter() and keep_structure() (docs/FILTER.md section 14):
// light averaged only across what its noise explains, for the direct light
// of a sun or a small lamp, which the renderer computes with little noise
// and whose hard and thin shadows a plane fitted over a window cannot
// hold. The stages, in order:
//   decode_light()        the light, its luminance and the guides
//   estimate_variance()   V per pixel, from the image itself
//   significant_mean()    one pixel's mean over the neighbours a test at
//                         their noise cannot tell from it
//   residual_statistic()  does a smoother's result depart from the light
//                         beyond its noise (keep_structure())

#include <zdenoise/zdenoise.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "filter/directional_variance.h"
#include "filter/filter_inputs.h"
#include "checks.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;
using namespace detail;

namespace {

/// Half-size of the search window.
constexpr int kSearch = 5;
/// A neighbour joins the mean when the mean over the 3x3 pairs of
/// (y_p - y_q)^2 / (V_p + V_q) is below this: about the 85 % quantile of
/// chi-square with 9 degrees of freedom over 9, so that a neighbour of the
/// same light is kept 85 % of the time and one across a line of four noise
/// deviations' contrast rarely.
constexpr float kPatchLevel = 1.5f;
/// A neighbour noisier than this many times the pixel's variance adds more
/// noise than it removes (inverse-variance weighting would give it less
/// than a quarter of the pixel's weight): left out.
constexpr float kNoisierLimit = 4.0f;
/// Neighbours on the same surface: normals within about 25 degrees.
constexpr float kNormalCos = 0.9f;
/// keep_structure(): the 99.9 % quantile of chi-square with 8 degrees of
/// freedom, over 8 (26.124 / 8): a smoother whose residual over the 8
/// neighbours is larger has removed structure, not noise. (The 99 % level,
/// 2.511, measured 0.5 % worse on newspaper, whose light has little
/// structure: Monte Carlo noise has heavier tails than the test assumes.)
constexpr float kResidualLevel = 3.265f;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// The light over `region` (the part of the frame the input holds), as
/// the stages read it.
struct LightPlane {
    ROI region;
    int w = 0, h = 0;
    std::vector<float> rgb;     ///< 3 a pixel
    std::vector<float> y;       ///< luminance; NaN where any channel is not finite
    std::vector<float> normal;  ///< 3 a pixel, unit length; empty: no guide
    std::vector<float> id;      ///< channel 0 of the id guide; empty: none
    std::vector<float> var;     ///< V; NaN where it cannot be estimated

    size_t index(int x, int y_) const
    {
        return size_t(y_ - region.ybegin) * size_t(w) + size_t(x - region.xbegin);
    }
    float value(size_t i) const { return y[i]; }
    bool inside(int x, int y_) const
    {
        return x >= region.xbegin && x < region.xend && y_ >= region.ybegin
               && y_ < region.yend;
    }
    bool same_surface(size_t a, size_t b) const
    {
        if (!id.empty() && !(id[a] == id[b]))
            return false;
        if (normal.empty())
            return true;
        const float* na = &normal[3 * a];
        const float* nb = &normal[3 * b];
        return na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2] > kNormalCos;
    }
};


bool
read_channels(ImageBuf& dst, const ImageBuf& img, const ROI& region, int nch,
              std::vector<float>& out, const char* opname, const char* what)
{
    ROI r    = region;
    r.chbegin = 0;
    r.chend   = nch;
    out.assign(size_t(nch) * region.npixels(), 0.0f);
    if (img.get_pixels(r, TypeFloat, out.data()))
        return true;
    dst.errorfmt("{}: cannot read the {}: {}", opname, what, img.geterror());
    return false;
}


bool
decode_light(LightPlane& p, ImageBuf& dst, const ImageBuf& light,
             const Guides& guides, const ROI& region, const char* opname)
{
    p.region = region;
    p.w      = region.width();
    p.h      = region.height();
    if (!read_channels(dst, light, region, 3, p.rgb, opname, "light"))
        return false;
    const size_t n = region.npixels();
    p.y.assign(n, kNaN);
    for (size_t i = 0; i < n; ++i) {
        const float* c = &p.rgb[3 * i];
        if (std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]))
            p.y[i] = luminance(c);
    }
    if (guides.normal) {
        if (!read_channels(dst, *guides.normal, region, 3, p.normal, opname,
                           "normal guide"))
            return false;
        for (size_t i = 0; i < n; ++i) {
            float* v       = &p.normal[3 * i];
            const float l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            const float s  = (std::isfinite(l2) && l2 > 0.0f) ? 1.0f / std::sqrt(l2)
                                                              : 0.0f;
            v[0] *= s;
            v[1] *= s;
            v[2] *= s;
        }
    }
    if (guides.object_id
        && !read_channels(dst, *guides.object_id, region, 1, p.id, opname,
                          "object id guide"))
        return false;
    return true;
}


/// V at every pixel (directional_variance.h): a shadow line or edge along
/// one direction leaves that direction's differences at the noise.
void
estimate_variance(LightPlane& p, int nthreads)
{
    p.var = directional_variance(p, nthreads);
}


/// (a - b)^2 / (va + vb), 0 for equal values, +inf for different values
/// without noise.
float
normalised_difference(float a, float b, float va, float vb)
{
    const float d = a - b;
    const float v = va + vb;
    if (v > 0.0f)
        return d * d / v;
    return d == 0.0f ? 0.0f : std::numeric_limits<float>::infinity();
}


/// Is neighbour q's 3x3 indistinguishable from pixel p's at their noise?
bool
indistinguishable(const LightPlane& p, int px, int py, int qx, int qy)
{
    float sum = 0.0f;
    int count = 0;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            if (!p.inside(px + dx, py + dy) || !p.inside(qx + dx, qy + dy))
                continue;
            const size_t a = p.index(px + dx, py + dy);
            const size_t b = p.index(qx + dx, qy + dy);
            if (!std::isfinite(p.var[a]) || !std::isfinite(p.var[b]))
                continue;  // NaN var: y is not finite or unknown noise
            sum += normalised_difference(p.y[a], p.y[b], p.var[a], p.var[b]);
            ++count;
        }
    return count > 0 && sum < kPatchLevel * float(count);
}


/// Pixel (x, y_)'s mean over the neighbours within kSearch that are on its
/// surface, at most kNoisierLimit times as noisy and indistinguishable;
/// the light as it is where its own noise is unknown. Returns how many
/// pixels the mean took (the pixel itself included; 0 where its noise is
/// unknown).
int
significant_mean(const LightPlane& p, int x, int y_, float* out)
{
    const size_t c = p.index(x, y_);
    const float vc = p.var[c];
    if (!std::isfinite(vc)) {
        std::copy(&p.rgb[3 * c], &p.rgb[3 * c] + 3, out);
        return 0;
    }
    double sum[3] = { 0, 0, 0 };
    int count     = 0;
    for (int v = y_ - kSearch; v <= y_ + kSearch; ++v)
        for (int u = x - kSearch; u <= x + kSearch; ++u) {
            if (!p.inside(u, v))
                continue;
            const size_t q = p.index(u, v);
            if (!(p.var[q] <= kNoisierLimit * vc) || !p.same_surface(c, q)
                || !indistinguishable(p, x, y_, u, v))
                continue;
            for (int k = 0; k < 3; ++k)
                sum[k] += double(p.rgb[3 * q + size_t(k)]);
            ++count;
        }
    for (int k = 0; k < 3; ++k)
        out[k] = float(sum[k] / double(count));  // count >= 1: the pixel itself
    return count;
}


/// The mean over the 8 neighbours on the pixel's surface of
/// (y - y_smoothed)^2 / V; NaN where no term has a known V. Not the pixel's
/// own: structure the input shows holds in more than one pixel (a 1-px line
/// has two of its pixels among any of its pixels' neighbours, an edge
/// three), while a lone outlier (a firefly, which the smoother rightly
/// removed) does not make its own case.
float
residual_statistic(const LightPlane& p, const std::vector<float>& smoothed_y,
                   int x, int y_)
{
    const size_t c = p.index(x, y_);
    float sum = 0.0f;
    int count = 0;
    for (int v = y_ - 1; v <= y_ + 1; ++v)
        for (int u = x - 1; u <= x + 1; ++u) {
            if (!p.inside(u, v) || (u == x && v == y_))
                continue;
            const size_t i = p.index(u, v);
            if (!p.same_surface(c, i))
                continue;  // another surface's light says nothing of this one
            if (!std::isfinite(p.var[i]) || !std::isfinite(smoothed_y[i]))
                continue;
            sum += normalised_difference(p.y[i], smoothed_y[i], p.var[i], 0.0f);
            ++count;
        }
    return count ? sum / float(count) : kNaN;
}


/// Check the arguments common to the three operations, set roi and frame
/// (by default the light's data window), decode the light over roi widened
/// by `halo` and estimate its noise; make dst a float result of `nch`
/// channels over roi.
bool
prepare(ImageBuf& dst, const ImageBuf& light, const Guides& guides,
        ROI& frame, ROI& roi, int halo, int nch, LightPlane& p,
        const char* opname, int nthreads)
{
    if (!light.initialized()) {
        dst.errorfmt("{}: input image is not initialized", opname);
        return false;
    }
    if (!roi.defined())
        roi = light.roi();
    if (!frame.defined())
        frame = light.roi();
    if (!check_input(dst, light, opname, "light", roi, 3)
        || !check_frame(dst, opname, roi, frame))
        return false;
    const ROI need = halo_region(roi, frame, halo);
    if (!check_input(dst, light, opname, "light", need, 3)
        || !check_guides(dst, guides, opname, need)
        || !decode_light(p, dst, light, guides, need, opname))
        return false;
    estimate_variance(p, nthreads);
    return prepare_result(dst, dst, roi, frame, nch, opname, "dst");
}


/// Channels 0 .. nch - 1 of dst over roi from `values` (nch a pixel).
bool
write_channels(ImageBuf& dst, const ROI& roi, int nch,
               const std::vector<float>& values)
{
    ROI r    = roi;
    r.chbegin = 0;
    r.chend   = nch;
    return dst.set_pixels(r, TypeFloat, values.data());
}

}  // namespace


int
noise_variance_halo()
{
    // The 5x5 pool of second differences.
    return kDirectionalBox + 1;
}


bool
noise_variance(ImageBuf& dst, const ImageBuf& light, const Guides& guides,
               ROI frame, ROI roi, int nthreads)
{
    const char* opname = "noise_variance";
    LightPlane p;
    if (!prepare(dst, light, guides, frame, roi, noise_variance_halo(), 1, p,
                 opname, nthreads))
        return false;
    std::vector<float> out(roi.npixels());
    for (int y_ = roi.ybegin; y_ < roi.yend; ++y_)
        for (int x = roi.xbegin; x < roi.xend; ++x)
            out[size_t(y_ - roi.ybegin) * size_t(roi.width())
                + size_t(x - roi.xbegin)] = p.var[p.index(x, y_)];
    return write_channels(dst, roi, 1, out);
}


int
significance_halo()
{
    // Search, its 3x3 test, and V there: the 5x5 of second differences.
    return kSearch + 1 + kDirectionalBox + 1;
}


bool
significance_filter(ImageBuf& dst, const ImageBuf& light, const Guides& guides,
                    ROI frame, ROI roi, int nthreads)
{
    const char* opname = "significance_filter";
    LightPlane p;
    if (!prepare(dst, light, guides, frame, roi, significance_halo(), 3, p,
                 opname, nthreads))
        return false;
    std::vector<float> out(3 * roi.npixels());
    for_rows(roi, nthreads, [&](int y_) {
        for (int x = roi.xbegin; x < roi.xend; ++x)
            significant_mean(p, x, y_,
                             &out[3 * (size_t(y_ - roi.ybegin) * size_t(roi.width())
                                       + size_t(x - roi.xbegin))]);
    });
    return write_channels(dst, roi, 3, out);
}


bool
keep_structure(ImageBuf& dst, const ImageBuf& light, const ImageBuf& smoothed,
               const Guides& guides, ROI frame, int64_t* kept, ROI roi,
               int nthreads)
{
    const char* opname = "keep_structure";
    if (!light.initialized()) {
        dst.errorfmt("{}: input image is not initialized", opname);
        return false;
    }
    if (!roi.defined())
        roi = light.roi();
    if (!frame.defined())
        frame = light.roi();
    // The 3x3 test at roi's border reads the smoother's result one pixel
    // beyond; read it before dst, which may be the same image, is written.
    ROI around    = halo_region(roi, frame, 1);
    around.chbegin = 0;
    around.chend   = 3;
    if (!check_input(dst, smoothed, opname, "smoothed", around, 3))
        return false;
    std::vector<float> s_rgb(3 * around.npixels());
    if (!smoothed.get_pixels(around, TypeFloat, s_rgb.data())) {
        dst.errorfmt("{}: cannot read smoothed: {}", opname, smoothed.geterror());
        return false;
    }
    LightPlane p;
    if (!prepare(dst, light, guides, frame, roi, significance_halo(), 3, p,
                 opname, nthreads))
        return false;
    // The smoother's luminance on the light's grid (NaN beyond `around`).
    std::vector<float> s_y(p.region.npixels(), kNaN);
    const size_t aw = size_t(around.width());
    auto at_around  = [&](int x, int y_) {
        return 3 * (size_t(y_ - around.ybegin) * aw + size_t(x - around.xbegin));
    };
    for (int y_ = around.ybegin; y_ < around.yend; ++y_)
        for (int x = around.xbegin; x < around.xend; ++x) {
            const float* c = &s_rgb[at_around(x, y_)];
            if (std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]))
                s_y[p.index(x, y_)] = luminance(c);
        }
    std::vector<float> out(3 * roi.npixels());
    std::vector<int64_t> row_kept(size_t(roi.height()), 0);
    const size_t rw = size_t(roi.width());
    for_rows(roi, nthreads, [&](int y_) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            float* o = &out[3 * (size_t(y_ - roi.ybegin) * rw + size_t(x - roi.xbegin))];
            const float t = residual_statistic(p, s_y, x, y_);
            // A smoother's non-finite value never passes where the light
            // is finite: the significance filter takes its place.
            const size_t c   = p.index(x, y_);
            const bool broken = !std::isfinite(s_y[c]) && std::isfinite(p.y[c]);
            // Where the light has no noise (V 0: a clean emitter, an empty
            // shadow), any change the smoother made is no noise removed,
            // the pixel's own too.
            const bool clean_changed = p.var[c] == 0.0f && s_y[c] != p.y[c];
            if (!(t > kResidualLevel) && !broken && !clean_changed) {
                // The smoother's residual is noise: keep its result.
                std::copy(&s_rgb[at_around(x, y_)], &s_rgb[at_around(x, y_)] + 3, o);
                continue;
            }
            significant_mean(p, x, y_, o);
            ++row_kept[size_t(y_ - roi.ybegin)];
        }
    });
    if (kept) {
        *kept = 0;
        for (int64_t k : row_kept)
            *kept += k;
    }
    return write_channels(dst, roi, 3, out);
}

ImageBuf
significance_filter(const ImageBuf& light, const Guides& guides, ROI frame,
                    ROI roi, int nthreads)
{
    return returned_image("significance_filter", [&](ImageBuf& result) {
        return significance_filter(result, light, guides, frame, roi, nthreads);
    });
}


ImageBuf
keep_structure(const ImageBuf& light, const ImageBuf& smoothed,
               const Guides& guides, ROI frame, int64_t* kept, ROI roi,
               int nthreads)
{
    return returned_image("keep_structure", [&](ImageBuf& result) {
        return keep_structure(result, light, smoothed, guides, frame, kept,
                              roi, nthreads);
    });
}

}  // namespace zdenoise
