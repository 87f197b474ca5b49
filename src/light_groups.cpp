// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// split_light_groups() (include/zdenoise/light_groups.h,
// docs/LIGHT_GROUPS.md): each group's share of the light, estimated as a
// ratio of window sums with weights that every group shares, times the
// denoised beauty. The stages, in order:
//   decode_guides()   the guide planes GuideWeight reads
//   read_planes()     the denoised and noisy beauty and the groups
//   pixel_shares()    one pixel's ratio of sums, and its groups

#include <zdenoise/light_groups.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "checks.h"
#include "filter/filter_inputs.h"
#include "filter/guide_weight.h"
#include "filter/pixel_classes.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;
using namespace detail;

namespace {

/// The light over the region: the denoised beauty, and the noisy groups
/// followed by the rest (the beauty minus the groups) and the excess (the
/// groups minus the beauty), each clamped at 0; 3 floats a pixel each.
/// The excess is light the groups hold and the beauty does not: a world
/// group's light where the film is transparent.
struct GroupPlanes {
    std::vector<float> denoised;
    std::vector<std::vector<float>> parts;  ///< groups, rest, excess
};

/// The guide planes of `guides` over in.region as GuideWeight reads them.
bool
decode_guides(FilterInputs& in, ImageBuf& err, const Guides& guides,
              const std::vector<float>& light, const FilterOptions& filter,
              int nthreads)
{
    const size_t n = in.region.npixels();
    if (guides.normal)
        decode_normals(in, *guides.normal);
    if (guides.object_id && !decode_object_ids(in, err, *guides.object_id))
        return false;
    std::vector<float> depth;
    if (guides.depth)
        depth = read_channels(*guides.depth, in.region, 0, 1);
    // The classes' quotient and albedo: only kSurface and the inverse
    // depth are read here.
    const std::vector<float> ones(3 * n, 1.0f);
    classify_pixels(in, light, ones, {}, depth, filter.albedo_eps, nthreads);
    in.cls.resize(n + kPlanePadding, 0);
    if (!in.invdepth.empty())
        in.invdepth.resize(n + kPlanePadding, 0.0f);
    return true;
}

GroupPlanes
read_planes(const ROI& region, const ImageBuf& denoised, const ImageBuf& beauty,
            const std::vector<const ImageBuf*>& groups)
{
    GroupPlanes p;
    p.denoised = read_channels(denoised, region, 0, 3);
    std::vector<float> rest = read_channels(beauty, region, 0, 3);
    for (const ImageBuf* g : groups) {
        std::vector<float> light = read_channels(*g, region, 0, 3);
        for (size_t i = 0; i < light.size(); ++i) {
            rest[i] -= light[i];
            light[i] = std::max(light[i], 0.0f);  // NaN -> 0
        }
        p.parts.push_back(std::move(light));
    }
    std::vector<float> excess(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) {
        excess[i] = std::max(-rest[i], 0.0f);
        rest[i]   = std::max(rest[i], 0.0f);
    }
    p.parts.push_back(std::move(rest));
    p.parts.push_back(std::move(excess));
    return p;
}

/// The window means `mean` of the groups and the rest (the last), made to
/// add up to `target` (the light to split) into `out`: the difference goes
/// to each in proportion to its variance `var` among the window's pixels
/// (the least-squares adjustment of independent estimates to a known sum:
/// a clean group keeps its mean, the noisy ones take the correction), or,
/// where no part varies, in proportion to their means. A part that would
/// go below 0 is 0 and the others share what is left.
void
reconcile(const std::vector<double>& mean, const std::vector<double>& var,
          double target, std::vector<float>& out)
{
    const size_t n = mean.size();
    std::vector<bool> fixed(n, false);
    std::vector<double> x(mean);
    for (size_t round = 0; round <= n; ++round) {
        double diff = target, vsum = 0.0, msum = 0.0;
        for (size_t k = 0; k < n; ++k) {
            diff -= fixed[k] ? 0.0 : mean[k];
            vsum += fixed[k] ? 0.0 : var[k];
            msum += fixed[k] ? 0.0 : mean[k];
        }
        bool clipped = false;
        for (size_t k = 0; k < n; ++k) {
            if (fixed[k])
                continue;
            const double share = vsum > 0.0 ? var[k] / vsum
                                 : msum > 0.0 ? mean[k] / msum
                                              : (k + 1 == n ? 1.0 : 0.0);
            x[k] = mean[k] + share * diff;
            if (x[k] < 0.0) {
                x[k] = 0.0, fixed[k] = true, clipped = true;
            }
        }
        if (!clipped)
            break;
    }
    for (size_t k = 0; k < n; ++k)
        out[k] = float(x[k]);
}

/// Pixel (x, y)'s groups (3 floats each, into out[k]) from the window sums.
void
pixel_shares(const FilterInputs& in, const GroupPlanes& p, GuideWeight& gw,
             const LightGroupOptions& opt, int x, int y,
             std::vector<float>& g, std::vector<double>& sums,
             std::vector<float*>& out)
{
    const size_t nparts = p.parts.size();  // the groups, rest, excess
    std::fill(sums.begin(), sums.end(), 0.0);
    double wsum = 0.0;
    const size_t c0 = in.index(x, y);
    const float* b0 = &p.denoised[3 * c0];
    const int r = opt.radius;
    const int xb = std::max(x - r, in.region.xbegin);
    const int xe = std::min(x + r + 1, in.region.xend);
    const float inv_r2  = 1.0f / float(r * r);
    const float inv_t2  = 1.0f / (opt.tolerance * opt.tolerance);
    gw.centre(x, y);
    for (int v = std::max(y - r, in.region.ybegin);
         v < std::min(y + r + 1, in.region.yend); ++v) {
        gw.row(xb, v, xe - xb, g.data());
        for (int u = xb; u < xe; ++u) {
            // g(p; p) is 1 even where p is no surface (no depth).
            const float guide = u == x && v == y ? 1.0f : g[size_t(u - xb)];
            if (!(guide > 0.0f))
                continue;
            const size_t q = in.index(u, v);
            const float* bq = &p.denoised[3 * q];
            float like = 0.0f;
            for (int c = 0; c < 3; ++c) {
                const float s = std::fabs(b0[c]) + std::fabs(bq[c]);
                const float d = s > 0.0f ? (bq[c] - b0[c]) / s : 0.0f;
                like += d * d;
            }
            const float d2 = float((u - x) * (u - x) + (v - y) * (v - y));
            const float w  = guide * std::exp(-(d2 * inv_r2 + like * inv_t2 / 3.0f));
            if (!(w > 0.0f))
                continue;
            wsum += double(w);
            for (size_t k = 0; k < nparts; ++k)
                for (int c = 0; c < 3; ++c) {
                    const double l = p.parts[k][3 * q + size_t(c)];
                    sums[6 * k + size_t(c)] += double(w) * l;
                    sums[6 * k + 3 + size_t(c)] += double(w) * l * l;
                }
        }
    }
    // wsum >= 1: the pixel itself, unless its light is not finite.
    const size_t excess = nparts - 1;  // the groups and the rest before it
    std::vector<double> mean(excess), var(excess);
    std::vector<float> result(excess);
    for (int c = 0; c < 3; ++c) {
        for (size_t k = 0; k < excess; ++k) {
            mean[k] = wsum > 0.0 ? sums[6 * k + size_t(c)] / wsum : 0.0;
            var[k]  = wsum > 0.0
                          ? std::max(sums[6 * k + 3 + size_t(c)] / wsum - mean[k] * mean[k], 0.0)
                          : 0.0;
        }
        // The excess is the pixel's own: a mean would carry a transparent
        // neighbour's into a pixel whose groups hold just its beauty.
        const double target = (std::isfinite(b0[c]) ? double(b0[c]) : 0.0)
                              + double(p.parts[excess][3 * c0 + size_t(c)]);
        reconcile(mean, var, target, result);
        for (size_t k = 0; k + 1 < excess; ++k)
            out[k][c] = result[k];
    }
}

bool
check_group_inputs(ImageBuf& err, const ImageBuf& denoised, const ImageBuf& beauty,
                   const std::vector<const ImageBuf*>& groups, const Guides& guides,
                   const ROI& roi, const ROI& frame, const ROI& need)
{
    const char* opname = "split_light_groups";
    if (groups.empty()) {
        err.errorfmt("{}: no light group given", opname);
        return false;
    }
    if (!check_input(err, denoised, opname, "denoised beauty", need, 3)
        || !check_frame(err, opname, roi, frame)
        || !check_input(err, beauty, opname, "beauty", need, 3)
        || !check_guides(err, guides, opname, need))
        return false;
    for (const ImageBuf* g : groups)
        if (!g || !check_input(err, *g, opname, "light group", need, 3))
            return false;
    return true;
}

}  // namespace


int
light_groups_halo(const LightGroupOptions& options)
{
    return std::max(options.radius, 1);
}


bool
split_light_groups(std::vector<ImageBuf>& dst, const ImageBuf& denoised,
                   const ImageBuf& beauty,
                   const std::vector<const ImageBuf*>& groups,
                   const Guides& guides, const FilterOptions& filter,
                   const LightGroupOptions& options, ROI roi, int nthreads)
{
    const char* opname = "split_light_groups";
    dst.resize(std::max(groups.size(), size_t(1)));
    ImageBuf& err = dst[0];
    if (!denoised.initialized()) {
        err.errorfmt("{}: the denoised beauty is not initialized", opname);
        return false;
    }
    if (options.radius < 1 || !(options.tolerance > 0.0f)) {
        err.errorfmt("{}: radius must be at least 1 and tolerance positive",
                     opname);
        return false;
    }
    if (!roi.defined())
        roi = denoised.roi();
    const ROI frame = filter.frame.defined() ? filter.frame : denoised.roi();
    FilterInputs in;
    in.region = halo_region(roi, frame, light_groups_halo(options));
    in.image  = frame;
    in.width  = in.region.width();
    in.height = in.region.height();
    if (!check_group_inputs(err, denoised, beauty, groups, guides, roi, frame,
                            in.region))
        return false;
    const GroupPlanes planes = read_planes(in.region, denoised, beauty, groups);
    if (!decode_guides(in, err, guides, planes.denoised, filter, nthreads))
        return false;
    std::vector<bool> given;
    for (ImageBuf& d : dst) {
        given.push_back(d.initialized());
        if (!prepare_result(err, d, roi, frame, 3, opname, "dst"))
            return false;
    }
    const size_t k = groups.size();
    std::vector<std::vector<float>> out(k, std::vector<float>(3 * roi.npixels()));
    for_rows(roi, nthreads, [&](int y) {
        if (cancel_requested(filter))
            return;
        GuideWeight gw(in, filter);
        std::vector<float> g(size_t(2 * options.radius + 1) + kPlanePadding);
        std::vector<double> sums(6 * (k + 2));
        std::vector<float*> px(k);
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t i = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            for (size_t j = 0; j < k; ++j)
                px[j] = &out[j][3 * i];
            pixel_shares(in, planes, gw, options, x, y, g, sums, px);
        }
    });
    if (cancel_requested(filter)) {
        for (size_t j = 0; j < dst.size(); ++j)
            cancelled(dst[j], given[j], roi, nthreads);
        return false;
    }
    ROI rgb    = roi;
    rgb.chbegin = 0;
    rgb.chend   = 3;
    for (size_t j = 0; j < k; ++j)
        dst[j].set_pixels(rgb, TypeFloat, out[j].data());
    return true;
}

}  // namespace zdenoise
