// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// temporal_combine() and chain_flow(): the neighbouring frames' light
// reprojected into frame t (docs/TEMPORAL.md, "What it does" 1-4). Stages:
//   check_combine_inputs()  the frames' images, flows and test scales
//   read_combine_inputs()   read_frame(): the planes of frame t, of each
//                           neighbour, and each flow over frame t's region
//   match_neighbours()      each pixel's match: reproject(), same_surface() (1, 2)
//   chain_matches()         a chained neighbour matched only where its via is
//   light_agrees()          the paired test on the light, each scale       (3)
//   combine_pixel()         the mean light of the frames that count,
//                           remodulated by their mean albedo               (4)

#include <zdenoise/temporal.h>

#include <cmath>
#include <algorithm>
#include <cstring>
#include <limits>

#include <OpenImageIO/imagebufalgo_util.h>

#include "filter/filter_inputs.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;

namespace {

constexpr const char* kOp = "temporal_combine";

/// The planes of one frame over `window` (row-major), float.
struct FramePlanes {
    ROI window;
    std::vector<float> rgb, albedo, alpha, normal, depth, variance, half_a,
        half_b;
    int variance_channels = 0;
    std::vector<uint32_t> id;  ///< plain id or primary Cryptomatte id bits
    bool has_id = false;

    bool inside(int x, int y) const
    {
        return x >= window.xbegin && x < window.xend && y >= window.ybegin
               && y < window.yend;
    }
    size_t index(int x, int y) const
    {
        return size_t(y - window.ybegin) * size_t(window.width())
               + size_t(x - window.xbegin);
    }
    /// Alpha > 0 (when given) and a valid depth (when given), as the
    /// filter's pixel classes (docs/FILTER.md section 2).
    bool surface(size_t i) const
    {
        if (!alpha.empty() && !(alpha[i] > 0.0f))
            return false;
        if (!depth.empty()
            && !(std::isfinite(depth[i]) && depth[i] > 0.0f && depth[i] < 1e9f))
            return false;
        return true;
    }
};

/// The id a pixel is compared by: a plain id's bits, or the id of the
/// largest coverage of (id, coverage) pairs (the first on ties).
std::vector<uint32_t>
primary_ids(const ImageBuf& ids, const ROI& window)
{
    const int nch            = ids.nchannels();
    const std::vector<float> v = detail::read_channels(ids, window, 0, nch);
    std::vector<uint32_t> out(window.npixels());
    for (size_t i = 0; i < out.size(); ++i) {
        const float* p = &v[i * size_t(nch)];
        int best       = 0;
        if (nch > 1)
            for (int k = 1; 2 * k + 1 < nch; ++k)
                if (p[2 * k + 1] > p[2 * best + 1])
                    best = k;
        std::memcpy(&out[i], &p[2 * best], sizeof(uint32_t));
    }
    return out;
}

FramePlanes
read_frame(const TemporalFrame& f, const ROI& window, bool combine_guides)
{
    FramePlanes p;
    p.window = window;
    p.rgb    = detail::read_channels(*f.radiance, window, 0, 3);
    p.albedo = detail::read_channels(*f.albedo, window, 0, 3);
    if (f.radiance->nchannels() > 3)
        p.alpha = detail::read_channels(*f.radiance, window, 3, 4);
    const Guides& g = f.guides;
    if (g.normal)
        p.normal = detail::read_channels(*g.normal, window, 0, 3);
    if (g.depth)
        p.depth = detail::read_channels(*g.depth, window, 0, 1);
    if (g.object_id) {
        p.id     = primary_ids(*g.object_id, window);
        p.has_id = true;
    }
    if (!combine_guides)
        return p;
    if (g.variance) {
        p.variance_channels = g.variance->nchannels() >= 3 ? 3 : 1;
        p.variance = detail::read_channels(*g.variance, window, 0,
                                           p.variance_channels);
    }
    if (g.half_a && g.half_b) {
        p.half_a = detail::read_channels(*g.half_a, window, 0, 3);
        p.half_b = detail::read_channels(*g.half_b, window, 0, 3);
    }
    return p;
}

/// Does pixel j of neighbour n show the surface pixel i of frame t shows?
bool
same_surface(const FramePlanes& t, size_t i, const FramePlanes& n, size_t j,
             const TemporalOptions& opt)
{
    if (t.surface(i) != n.surface(j))
        return false;
    if (!t.depth.empty() && !n.depth.empty() && t.surface(i)
        && !(std::fabs(n.depth[j] - t.depth[i])
             <= opt.depth_tolerance * t.depth[i]))
        return false;
    if (!t.normal.empty() && !n.normal.empty()) {
        const float* a = &t.normal[3 * i];
        const float* b = &n.normal[3 * j];
        const float la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        const float lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        const bool na = !(la >= 1e-6f), nb = !(lb >= 1e-6f);
        if (na != nb)
            return false;
        if (!na
            && !((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) >= opt.normal_cut * la * lb))
            return false;
    }
    if (t.has_id && n.has_id && t.id[i] != n.id[j])
        return false;
    return true;
}

/// The nearest pixel of `p + flow` (pixel centres at +0.5), or false.
bool
reproject(int x, int y, const float* flow, int& qx, int& qy)
{
    if (!flow)
        return qx = x, qy = y, true;
    const float fx = flow[0], fy = flow[1];
    if (!std::isfinite(fx) || !std::isfinite(fy) || std::fabs(fx) > 1e8f
        || std::fabs(fy) > 1e8f)
        return false;
    qx = int(std::floor(float(x) + 0.5f + fx));
    qy = int(std::floor(float(y) + 0.5f + fy));
    return true;
}

constexpr size_t kNoMatch = ~size_t(0);

/// A pixel of frame t's region and one neighbour: the neighbour's pixel
/// that shows the same surface (kNoMatch: none), and the difference of
/// their light's luminance (NaN where a channel is not demodulated in
/// both: no evidence for the test).
struct Match {
    size_t j = kNoMatch;
    float dz = 0.0f;
    /// The flow lands on the pixel itself (a static camera, a background
    /// that does not move): no sub-pixel misregistration.
    bool exact = false;
};

/// The luminance of pixel i's light z = L / (A + eps); NaN unless all
/// three channels are demodulated.
float
light_luminance(const FramePlanes& f, size_t i, float eps)
{
    float z[3];
    for (int c = 0; c < 3; ++c) {
        const float a = f.albedo[3 * i + size_t(c)];
        if (!detail::albedo_demodulated(a, eps))
            return std::numeric_limits<float>::quiet_NaN();
        z[c] = f.rgb[3 * i + size_t(c)] / (a + eps);
    }
    return detail::luminance(z);
}

/// matches[k][i] for every pixel i of t's region and neighbour k.
std::vector<std::vector<Match>>
match_neighbours(const FramePlanes& t, const std::vector<FramePlanes>& ns,
                 const std::vector<std::vector<float>>& flows,
                 const TemporalOptions& opt, float eps, int nthreads)
{
    std::vector<std::vector<Match>> out(ns.size());
    const ROI& w = t.window;
    for (size_t k = 0; k < ns.size(); ++k) {
        const FramePlanes& n = ns[k];
        std::vector<Match>& mk = out[k];
        mk.assign(w.npixels(), Match());
        detail::for_rows(w, nthreads, [&](int y) {
            for (int x = w.xbegin; x < w.xend; ++x) {
                const size_t i = t.index(x, y);
                int qx = 0, qy = 0;
                const float* f = flows[k].empty() ? nullptr : &flows[k][2 * i];
                if (!reproject(x, y, f, qx, qy) || !n.inside(qx, qy))
                    continue;
                const size_t j = n.index(qx, qy);
                if (!same_surface(t, i, n, j, opt))
                    continue;
                mk[i].j     = j;
                mk[i].exact = !f || (f[0] == 0.0f && f[1] == 0.0f);
                const float d = light_luminance(n, j, eps)
                                - light_luminance(t, i, eps);
                mk[i].dz = std::isfinite(d)
                               ? d
                               : std::numeric_limits<float>::quiet_NaN();
            }
        });
    }
    return out;
}

/// For each pixel of roi: does the neighbour show frame t's light around
/// it? A paired test on the luminance differences of the matched pixels in
/// the box of radius r (clipped to the window w): their mean within
/// `sigmas` standard errors of 0, with at least 4 pairs. A moving shadow, a
/// light switched on or a reflection that moves differently from its
/// surface changes the mean; noise only its spread. Each scale r, 2r, 4r ...
/// must agree. The sums run in one order per pixel (the box's columns, then
/// their sums from left to right), so that a pixel's answer does not depend
/// on roi or the thread count.
std::vector<uint8_t>
light_agrees(const std::vector<Match>& m, const ROI& w, const ROI& roi,
             const TemporalOptions& opt, int nthreads)
{
    std::vector<uint8_t> agrees(roi.npixels(), 1);
    const double sigmas = opt.rejection_sigmas;
    for (int scale = 0; scale < opt.test_scales; ++scale) {
        const int r = opt.test_radius << scale;
        detail::for_rows(roi, nthreads, [&](int y) {
            // Per column of the window: the pairs, the sum and the sum of
            // squares over the box's rows.
            const int width = w.width();
            std::vector<double> cn(size_t(width), 0.0), cs(size_t(width), 0.0),
                cs2(size_t(width), 0.0);
            for (int v = std::max(y - r, w.ybegin);
                 v <= std::min(y + r, w.yend - 1); ++v) {
                const Match* row = &m[size_t(v - w.ybegin) * size_t(width)];
                for (int u = 0; u < width; ++u) {
                    const Match& p = row[u];
                    if (p.j == kNoMatch || !std::isfinite(p.dz))
                        continue;
                    cn[size_t(u)] += 1.0;
                    cs[size_t(u)] += p.dz;
                    cs2[size_t(u)] += double(p.dz) * p.dz;
                }
            }
            uint8_t* out = &agrees[size_t(y - roi.ybegin) * size_t(roi.width())];
            for (int x = roi.xbegin; x < roi.xend; ++x) {
                if (!out[x - roi.xbegin])
                    continue;
                double n = 0.0, sum = 0.0, sum2 = 0.0;
                for (int u = std::max(x - r, w.xbegin);
                     u <= std::min(x + r, w.xend - 1); ++u) {
                    n += cn[size_t(u - w.xbegin)];
                    sum += cs[size_t(u - w.xbegin)];
                    sum2 += cs2[size_t(u - w.xbegin)];
                }
                bool same = n >= 4.0;
                if (same) {
                    const double mean = sum / n;
                    const double var  = std::max(sum2 - n * mean * mean, 0.0)
                                       / (n - 1.0);
                    same = std::fabs(mean) <= sigmas * std::sqrt(var / n);
                }
                out[x - roi.xbegin] = same;
            }
        });
    }
    return agrees;
}


/// Does frame `f` have a radiance and an albedo, and do all its images
/// cover its radiance's data window with the channels they need?
bool
check_frame_images(ImageBuf& dst, const TemporalFrame& f,
                   const std::string& which)
{
    if (!f.radiance || !f.albedo) {
        dst.errorfmt("{}: {} has no {}", kOp, which,
                     f.radiance ? "albedo" : "radiance");
        return false;
    }
    const ROI window = f.radiance->roi();
    auto check = [&](const ImageBuf* img, const char* what, int nch) {
        if (!img)
            return true;
        if (img->roi().xbegin != window.xbegin || img->roi().xend != window.xend
            || img->roi().ybegin != window.ybegin
            || img->roi().yend != window.yend) {
            dst.errorfmt("{}: {}'s {} covers another data window than its "
                         "radiance",
                         kOp, which, what);
            return false;
        }
        if (img->nchannels() < nch) {
            dst.errorfmt("{}: {}'s {} has {} channels, needs {}", kOp, which,
                         what, img->nchannels(), nch);
            return false;
        }
        return true;
    };
    const Guides& g = f.guides;
    return check(f.radiance, "radiance", 3) && check(f.albedo, "albedo", 3)
           && check(g.normal, "normal", 3) && check(g.depth, "depth", 1)
           && check(g.object_id, "object id", 1)
           && check(g.variance, "variance", 1) && check(g.half_a, "half A", 3)
           && check(g.half_b, "half B", 3);
}

/// temporal_combine()'s arguments (images, flows over roi, test scales).
/// Sets roi to the pixels to combine: within frame t's, all its channels.
bool
check_combine_inputs(ImageBuf& dst, const TemporalFrame& frame,
                     const std::vector<TemporalFrame>& neighbours,
                     const TemporalOptions& opt, ROI& roi)
{
    if (!check_frame_images(dst, frame, "frame t"))
        return false;
    const ROI full = frame.radiance->roi();
    if (!roi.defined())
        roi = full;
    roi = roi_intersection(roi, full);
    roi.chbegin = 0;
    roi.chend   = frame.radiance->nchannels();
    for (size_t k = 0; k < neighbours.size(); ++k) {
        const TemporalFrame& n = neighbours[k];
        const std::string which = "neighbour " + std::to_string(k);
        if (!check_frame_images(dst, n, which))
            return false;
        const ROI fw = n.flow ? n.flow->roi() : ROI();
        if (n.flow && (fw.nchannels() < 2 || fw.xbegin > roi.xbegin || fw.xend < roi.xend
                       || fw.ybegin > roi.ybegin || fw.yend < roi.yend)) {
            dst.errorfmt("{}: {}'s flow needs 2 channels over frame t's "
                         "pixels", kOp, which);
            return false;
        }
    }
    if (opt.test_radius < 1 || opt.test_scales < 1 || opt.test_scales > 8) {
        dst.errorfmt("{}: the light test needs test_radius >= 1 and 1 to 8 "
                     "test_scales", kOp);
        return false;
    }
    return true;
}

/// Frame t over roi and the light test's largest box, the neighbours over
/// their data windows, their flows over frame t's region (or empty).
struct CombineInputs {
    FramePlanes t;
    std::vector<FramePlanes> ns;
    std::vector<std::vector<float>> flows;
};

CombineInputs
read_combine_inputs(const TemporalFrame& frame,
                    const std::vector<TemporalFrame>& neighbours,
                    const TemporalOptions& opt, const ROI& roi)
{
    const int r = opt.test_reach();
    ROI region  = roi_intersection(
        ROI(roi.xbegin - r, roi.xend + r, roi.ybegin - r, roi.yend + r),
        frame.radiance->roi());
    region.chbegin = 0;
    region.chend   = roi.chend;
    CombineInputs in;
    in.t = read_frame(frame, region, true);
    const bool guides = !in.t.variance.empty() || !in.t.half_a.empty();
    for (const TemporalFrame& n : neighbours) {
        in.ns.push_back(read_frame(n, n.radiance->roi(), guides));
        // Beyond the flow's pixels (a caller's flow over roi only) the
        // test's box has no correspondence.
        const ROI fr = n.flow ? roi_intersection(n.flow->roi(), region) : region;
        std::vector<float> f;
        if (n.flow) {
            f.assign(2 * region.npixels(), std::numeric_limits<float>::quiet_NaN());
            const std::vector<float> part = detail::read_channels(*n.flow, fr, 0, 2);
            for (int y = fr.ybegin; y < fr.yend; ++y)
                std::copy_n(&part[2 * size_t(y - fr.ybegin) * size_t(fr.width())],
                            2 * size_t(fr.width()), &f[2 * in.t.index(fr.xbegin, y)]);
        }
        in.flows.push_back(std::move(f));
    }
    return in;
}

/// Chains (TemporalFrame::via): a chained neighbour's pixel counts only
/// where the frame between shows the same surface. Nearest first, so that
/// a via's own via is applied before.
bool
chain_matches(ImageBuf& dst, const std::vector<TemporalFrame>& neighbours,
              std::vector<std::vector<Match>>& matches)
{
    for (size_t k = 0; k < neighbours.size(); ++k) {
        const int via = neighbours[k].via;
        if (via < 0)
            continue;
        if (size_t(via) >= neighbours.size() || size_t(via) == k) {
            dst.errorfmt("{}: neighbour {}'s via ({}) is no other neighbour",
                         kOp, k, via);
            return false;
        }
    }
    std::vector<size_t> by_depth(neighbours.size());
    auto depth = [&](size_t k) {
        int d = 0;
        for (int v = neighbours[k].via; v >= 0 && d <= int(neighbours.size());
             v = neighbours[size_t(v)].via)
            ++d;
        return d;
    };
    for (size_t k = 0; k < by_depth.size(); ++k)
        by_depth[k] = k;
    std::stable_sort(by_depth.begin(), by_depth.end(),
                     [&](size_t a, size_t b) { return depth(a) < depth(b); });
    for (size_t k : by_depth) {
        const int via = neighbours[k].via;
        if (via < 0)
            continue;
        for (size_t i = 0; i < matches[k].size(); ++i)
            if (matches[size_t(via)][i].j == kNoMatch)
                matches[k][i].j = kNoMatch;
    }
    return true;
}

/// Per neighbour, the share of roi's pixels that show the same surface.
std::vector<double>
same_surface_shares(const std::vector<std::vector<Match>>& matches,
                    const FramePlanes& t, const ROI& roi)
{
    const size_t npixels = roi.npixels();
    std::vector<double> shares(matches.size(), 0.0);
    for (size_t k = 0; k < matches.size(); ++k) {
        size_t same = 0;
        for (int y = roi.ybegin; y < roi.yend; ++y)
            for (int x = roi.xbegin; x < roi.xend; ++x)
                same += matches[k][t.index(x, y)].j != kNoMatch;
        shares[k] = npixels ? double(same) / double(npixels) : 0.0;
    }
    return shares;
}

/// What combine_pixel() reads: frame t and the neighbours, each
/// neighbour's matches over t's region and its light test over roi.
struct Combination {
    const FramePlanes& t;
    const std::vector<FramePlanes>& ns;
    const std::vector<std::vector<Match>>& matches;
    const std::vector<std::vector<uint8_t>>& agrees;
    ROI roi;
    float eps;
    bool with_variance, with_halves;
};

/// dst's images over roi: the radiance frame t's (the channels beyond RGB
/// stay so), the frames, the albedo, the variance and the halves zero.
void
prepare_combined(TemporalCombined& dst, const TemporalFrame& frame,
                 const Combination& cb, int nthreads)
{
    const ROI& roi = cb.roi;
    ImageSpec spec(roi.width(), roi.height(), roi.chend, TypeDesc::FLOAT);
    spec.x = roi.xbegin;
    spec.y = roi.ybegin;
    dst.radiance.reset(spec);
    ImageBufAlgo::copy(dst.radiance, *frame.radiance, TypeUnknown, roi, nthreads);
    auto plane = [&](ImageBuf& img, int nch) {
        ImageSpec s(roi.width(), roi.height(), nch, TypeDesc::FLOAT);
        s.x = roi.xbegin;
        s.y = roi.ybegin;
        img.reset(s, InitializePixels::Yes);
    };
    plane(dst.frames, 1);
    plane(dst.albedo, 3);
    if (cb.with_variance)
        plane(dst.variance, cb.t.variance_channels);
    if (cb.with_halves) {
        plane(dst.half_a, 3);
        plane(dst.half_b, 3);
    }
}

/// One pixel's sums per channel over the frames that count: the light,
/// its variance and the halves' light, each divided by the frame's A + eps;
/// the albedo of the frames whose flow is exact.
struct PixelSums {
    double z[3] = {}, var[3] = {}, half_a[3] = {}, half_b[3] = {},
           albedo[3] = {};
    int count[3] = {}, albedo_count[3] = {};
    int frames = 1;

    void add(const Combination& cb, const FramePlanes& f, size_t j, int c,
             bool exact)
    {
        const float scale = 1.0f / (f.albedo[3 * j + size_t(c)] + cb.eps);
        z[c] += double(f.rgb[3 * j + size_t(c)]) * scale;
        if (cb.with_variance) {
            const int vc = f.variance_channels == 3 ? c : 0;
            var[c] += double(f.variance[size_t(f.variance_channels) * j
                                        + size_t(vc)])
                      * scale * scale;
        }
        if (cb.with_halves) {
            half_a[c] += double(f.half_a[3 * j + size_t(c)]) * scale;
            half_b[c] += double(f.half_b[3 * j + size_t(c)]) * scale;
        }
        if (exact) {
            albedo[c] += double(f.albedo[3 * j + size_t(c)]);
            ++albedo_count[c];
        }
        ++count[c];
    }
};

/// Pixel (x, y)'s sums: frame t's, then in order each neighbour's that
/// matches and passes the light test (counted in the row's `counted`).
PixelSums
sum_frames(const Combination& cb, int x, int y, uint32_t* counted)
{
    const FramePlanes& t = cb.t;
    const float eps      = cb.eps;
    const size_t i       = t.index(x, y);
    PixelSums s;
    for (int c = 0; c < 3; ++c)
        if (detail::albedo_demodulated(t.albedo[3 * i + size_t(c)], eps))
            s.add(cb, t, i, c, true);
    for (size_t k = 0; k < cb.ns.size(); ++k) {
        const FramePlanes& n = cb.ns[k];
        const Match& m       = cb.matches[k][i];
        if (m.j == kNoMatch
            || !cb.agrees[k][size_t(y - cb.roi.ybegin) * size_t(cb.roi.width())
                             + size_t(x - cb.roi.xbegin)])
            continue;
        const size_t j = m.j;
        bool used = false;
        for (int c = 0; c < 3; ++c)
            if (detail::albedo_demodulated(t.albedo[3 * i + size_t(c)], eps)
                && detail::albedo_demodulated(n.albedo[3 * j + size_t(c)], eps)
                && std::isfinite(n.rgb[3 * j + size_t(c)])) {
                s.add(cb, n, j, c, m.exact);
                used = true;
            }
        s.frames += used;
        counted[k] += used;
    }
    return s;
}

/// Pixel (x, y) of dst: the mean light of the frames that count,
/// remodulated by their mean albedo; frame t's where not demodulated.
void
combine_pixel(TemporalCombined& dst, const Combination& cb, int x, int y,
              uint32_t* counted)
{
    const FramePlanes& t = cb.t;
    const size_t i       = t.index(x, y);
    const PixelSums s    = sum_frames(cb, x, y, counted);
    float var[3] = {}, ha[3] = {}, hb[3] = {};
    float* out_rgb = static_cast<float*>(dst.radiance.pixeladdr(x, y));
    for (int c = 0; c < 3; ++c) {
        float& out_albedo = static_cast<float*>(dst.albedo.pixeladdr(x, y))[c];
        out_albedo = t.albedo[3 * i + size_t(c)];
        if (!s.count[c])
            continue;  // not demodulated: frame t's radiance
        // The albedo averaged over the same frames where the flow is exact:
        // its own noise (a render's albedo AOV) would flicker otherwise. A
        // fractional flow would shift the texture by up to half a pixel:
        // there it stays frame t's.
        out_albedo     = float(s.albedo[c] / s.albedo_count[c]);
        const double a = double(out_albedo) + cb.eps;
        out_rgb[c] = float(s.z[c] / s.count[c] * a);
        if (cb.with_variance)
            var[c] = float(s.var[c] / (double(s.count[c]) * s.count[c]) * a * a);
        if (cb.with_halves) {
            ha[c] = float(s.half_a[c] / s.count[c] * a);
            hb[c] = float(s.half_b[c] / s.count[c] * a);
        }
    }
    *static_cast<float*>(dst.frames.pixeladdr(x, y)) = float(s.frames);
    if (cb.with_variance) {
        float* v = static_cast<float*>(dst.variance.pixeladdr(x, y));
        for (int c = 0; c < t.variance_channels; ++c)
            v[c] = s.count[c] ? var[c]
                              : t.variance[size_t(t.variance_channels) * i
                                           + size_t(c)];
    }
    if (cb.with_halves) {
        float* a = static_cast<float*>(dst.half_a.pixeladdr(x, y));
        float* b = static_cast<float*>(dst.half_b.pixeladdr(x, y));
        for (int c = 0; c < 3; ++c) {
            a[c] = s.count[c] ? ha[c] : t.half_a[3 * i + size_t(c)];
            b[c] = s.count[c] ? hb[c] : t.half_b[3 * i + size_t(c)];
        }
    }
}

}  // namespace


bool
temporal_combine(TemporalCombined& dst, const TemporalFrame& frame,
                 const std::vector<TemporalFrame>& neighbours,
                 const TemporalOptions& opt, ROI roi, int nthreads)
{
    if (!check_combine_inputs(dst.radiance, frame, neighbours, opt, roi))
        return false;
    const CombineInputs in = read_combine_inputs(frame, neighbours, opt, roi);
    std::vector<std::vector<Match>> matches
        = match_neighbours(in.t, in.ns, in.flows, opt, opt.albedo_eps, nthreads);
    if (!chain_matches(dst.radiance, neighbours, matches))
        return false;
    std::vector<std::vector<uint8_t>> agrees;
    for (const std::vector<Match>& m : matches)
        agrees.push_back(light_agrees(m, in.t.window, roi, opt, nthreads));
    dst.same_surface = same_surface_shares(matches, in.t, roi);
    const Combination cb { in.t, in.ns, matches, agrees, roi, opt.albedo_eps,
                           !in.t.variance.empty(), !in.t.half_a.empty() };
    for (const FramePlanes& n : in.ns)
        if ((cb.with_variance && n.variance.empty())
            || (cb.with_halves && n.half_a.empty())) {
            dst.radiance.errorfmt("{}: frame t has {}, a neighbour does not",
                                  kOp, cb.with_variance ? "a variance" : "halves");
            return false;
        }
    prepare_combined(dst, frame, cb, nthreads);
    // Counted per row and neighbour (summed after, in order).
    const size_t nn = in.ns.size();
    std::vector<uint32_t> counted(size_t(roi.height()) * nn, 0);
    detail::for_rows(roi, nthreads, [&](int y) {
        uint32_t* row = counted.data() + size_t(y - roi.ybegin) * nn;
        for (int x = roi.xbegin; x < roi.xend; ++x)
            combine_pixel(dst, cb, x, y, row);
    });
    const size_t npixels = roi.npixels();
    dst.counted.assign(nn, 0.0);
    for (size_t k = 0; k < nn; ++k) {
        double sum = 0.0;
        for (int y = 0; y < roi.height(); ++y)
            sum += counted[size_t(y) * nn + k];
        dst.counted[k] = npixels ? sum / double(npixels) : 0.0;
    }
    return true;
}


bool
chain_flow(ImageBuf& dst, const ImageBuf& to_next,
           const ImageBuf& next_to_after, ROI roi, int nthreads)
{
    if (to_next.nchannels() < 2 || next_to_after.nchannels() < 2) {
        dst.errorfmt("chain_flow: a flow needs 2 channels");
        return false;
    }
    if (!roi.defined())
        roi = to_next.roi();
    roi.chbegin = 0;
    roi.chend   = 2;
    const ROI next = next_to_after.roi();
    const std::vector<float> a = detail::read_channels(to_next, roi, 0, 2);
    const std::vector<float> b = detail::read_channels(next_to_after, next, 0, 2);
    ImageSpec spec(roi.width(), roi.height(), 2, TypeDesc::FLOAT);
    spec.x = roi.xbegin;
    spec.y = roi.ybegin;
    dst.reset(spec);
    detail::for_rows(roi, nthreads, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t o = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            float* d = static_cast<float*>(dst.pixeladdr(x, y));
            d[0] = d[1] = std::numeric_limits<float>::quiet_NaN();
            int qx = 0, qy = 0;
            if (!reproject(x, y, &a[2 * o], qx, qy)
                || !(qx >= next.xbegin && qx < next.xend && qy >= next.ybegin
                     && qy < next.yend))
                continue;
            const size_t j = size_t(qy - next.ybegin) * size_t(next.width())
                             + size_t(qx - next.xbegin);
            d[0] = a[2 * o] + b[2 * j];
            d[1] = a[2 * o + 1] + b[2 * j + 1];
        }
    });
    return true;
}

}  // namespace zdenoise
