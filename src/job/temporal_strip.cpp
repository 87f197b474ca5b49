// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// --temporal's combination of frame t with its neighbours over a strip
// (docs/TEMPORAL.md): the neighbours' flows and roles read nearest first,
// then temporal_combine().

#include "temporal_strip.h"

#include <algorithm>
#include <cstdlib>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include "failure.h"
#include "neighbour_frames.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

TemporalOptions
temporal_options(const Job& j)
{
    TemporalOptions o;
    o.albedo_eps = j.filter.albedo_eps;
    return o;
}

int
temporal_reach(const Job& j)
{
    return j.temporal > 0 ? temporal_options(j).test_reach() : 0;
}


namespace {

/// `b` cut to `to` (all its channels), when it is there and larger.
void
crop_to(ImageBuf& b, const ROI& to, int threads)
{
    if (!b.initialized() || b.roi() == to)
        return;
    ROI r     = to;
    r.chbegin = 0;
    r.chend   = b.nchannels();
    ImageBuf c;
    if (!ImageBufAlgo::copy(c, b, TypeFloat, r, threads))
        fail(format("--temporal: {}", one_line(c.geterror())));
    b = std::move(c);
}


/// The neighbours in the order they are read, nearest first (so that a
/// flow's previous step is there), and for each the neighbour one frame
/// nearer to frame t (n: frame t itself), the frame its flow's last step
/// leaves from.
void
neighbour_order(const Job& j, std::vector<size_t>& order,
                std::vector<size_t>& before)
{
    const size_t n = j.neighbours.size();
    order.resize(n);
    for (size_t k = 0; k < n; ++k)
        order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return std::abs(j.neighbour_offsets[a]) < std::abs(j.neighbour_offsets[b]);
    });
    before.assign(n, n);
    for (size_t k = 0; k < n; ++k) {
        const int o = j.neighbour_offsets[k], nearer = o - (o > 0 ? 1 : -1);
        for (size_t m = 0; m < n; ++m)
            if (j.neighbour_offsets[m] == nearer)
                before[k] = m;
    }
}


/// Neighbour k's flow to frame t: one step from the frame before it
/// (frame t, or the neighbour nearer to it), by that frame's motion
/// vectors, chained to that frame's flow.
void
neighbour_flow(const Job& j, const RoleImages& img,
               const std::vector<FrameRoles>& frames,
               const std::vector<size_t>& before, size_t k,
               std::vector<ImageBuf>& flows)
{
    const size_t n = frames.size();
    const int dir  = j.neighbour_offsets[k] > 0 ? 1 : -1;
    const ImageBuf& vectors = before[k] == n ? img.motion
                                             : frames[before[k]].motion;
    ImageBuf step = vector_flow(vectors, dir, j.threads);
    if (before[k] == n) {
        flows[k] = std::move(step);
    } else if (!chain_flow(flows[k], flows[before[k]], step, {}, j.threads)) {
        fail(format("--temporal: {}", one_line(flows[k].geterror())));
    }
}


/// Neighbour k's roles over the rows its flow reaches from `around` (and
/// the albedo prefilter's halo), converted and prefiltered as frame t's.
FrameRoles
read_neighbour(const Job& j, const Plan& p, InputFiles& files, size_t k,
               const ImageBuf* flow, const ROI& around)
{
    // Neighbours' albedos are prefiltered (not pooled: their own albedos
    // are not read).
    const int prefilter = p.albedo.pool ? 0 : p.albedo.prefilter;
    const int reach     = prefilter ? albedo_prefilter_halo() : 0;
    const Job& nj       = j.neighbours[k];
    ROI rows            = rows_reached(flow, around, p.noisy);
    const ROI used      = rows;
    rows.ybegin = std::max(rows.ybegin - reach, p.noisy.ybegin);
    rows.yend   = std::min(rows.yend + reach, p.noisy.yend);
    FrameRoles f;
    try {
        f = read_neighbour_roles(j, nj, p.roles, files, p.noisy, rows,
                                 j.threads);
    } catch (const Failure& e) {
        fail(format("--temporal: neighbour frame {:+d}: {}",
                    j.neighbour_offsets[k], e.message));
    }
    convert_role(p, f.radiance, p.spaces.input, p.spaces.working, nj.in);
    convert_role(p, f.albedo, p.spaces.albedo, p.spaces.working, nj.albedo);
    convert_role(p, f.half_a, p.spaces.input, p.spaces.working, nj.half_a);
    convert_role(p, f.half_b, p.spaces.input, p.spaces.working, nj.half_b);
    if (prefilter) {
        ImageBuf clean;
        if (!prefilter_albedo(clean, f.albedo, prefilter, used, j.threads))
            fail(format("'{}': {}", nj.albedo.path,
                        one_line(clean.geterror())));
        f.albedo = std::move(clean);
        for (ImageBuf* b : { &f.radiance, &f.normal, &f.depth, &f.id,
                             &f.variance, &f.half_a, &f.half_b })
            crop_to(*b, used, j.threads);
    }
    return f;
}


/// A frame's images as temporal_combine() takes them.
TemporalFrame
as_temporal_frame(const ImageBuf& radiance, const ImageBuf& albedo,
                  const ImageBuf& normal, const ImageBuf& depth,
                  const ImageBuf& id, const ImageBuf& variance,
                  const ImageBuf& half_a, const ImageBuf& half_b)
{
    auto given = [](const ImageBuf& b) {
        return b.initialized() ? &b : nullptr;
    };
    TemporalFrame f;
    f.radiance         = &radiance;
    f.albedo           = &albedo;
    f.guides.normal    = given(normal);
    f.guides.depth     = given(depth);
    f.guides.object_id = given(id);
    f.guides.variance  = given(variance);
    f.guides.half_a    = given(half_a);
    f.guides.half_b    = given(half_b);
    return f;
}


/// What -v says of the combination, for the first strip.
void
log_combined(const Job& j, const TemporalCombined& c, JobResult& result)
{
    const size_t n   = j.neighbours.size();
    const auto stats = ImageBufAlgo::computePixelStats(c.frames);
    result.log.push_back(format("temporal  {:.2f} frames a pixel on "
                                "average (of {}) in the first strip",
                                stats.avg.empty() ? 1.0 : stats.avg[0],
                                n + 1));
    // Near 0 where things move: vectors of another convention.
    for (size_t k = 0; k < n; ++k)
        result.log.push_back(format(
            "temporal  frame {:+d}: the same surface at {:.0f} %, counted "
            "at {:.0f} % of the pixels",
            j.neighbour_offsets[k], 100.0 * c.same_surface[k],
            100.0 * c.counted[k]));
}

}  // namespace


void
combine_neighbours(const Job& j, const Plan& p, InputFiles& files,
                   const Strip& strip, RoleImages& img, JobResult& result)
{
    const TemporalOptions options = temporal_options(j);
    const int halo     = filter_halo(j.filter);
    const ROI region   = strip.widened(halo);
    const ROI around   = strip.widened(halo + options.test_reach());
    for (ImageBuf* b : { &img.radiance, &img.albedo, &img.normal, &img.depth,
                         &img.id, &img.variance, &img.half_a, &img.half_b,
                         &img.motion })
        crop_to(*b, around, j.threads);

    const size_t n = j.neighbours.size();
    std::vector<size_t> order, before;
    neighbour_order(j, order, before);
    std::vector<FrameRoles> frames(n);
    std::vector<ImageBuf> flows(n);
    for (size_t k : order) {
        if (!j.static_camera)
            neighbour_flow(j, img, frames, before, k, flows);
        frames[k] = read_neighbour(j, p, files, k,
                                   flows[k].initialized() ? &flows[k] : nullptr,
                                   around);
    }
    const TemporalFrame t = as_temporal_frame(img.radiance, img.albedo,
                                              img.normal, img.depth, img.id,
                                              img.variance, img.half_a,
                                              img.half_b);
    std::vector<TemporalFrame> neighbours;
    for (size_t k = 0; k < n; ++k) {
        const FrameRoles& f = frames[k];
        neighbours.push_back(as_temporal_frame(f.radiance, f.albedo, f.normal,
                                               f.depth, f.id, f.variance,
                                               f.half_a, f.half_b));
        neighbours.back().flow = j.static_camera ? nullptr : &flows[k];
        if (!j.static_camera && before[k] != n)
            neighbours.back().via = int(before[k]);
    }
    TemporalCombined c;
    if (!temporal_combine(c, t, neighbours, options, region, j.threads))
        fail(format("--temporal: {}", one_line(c.radiance.geterror())));
    img.radiance = std::move(c.radiance);
    img.albedo   = std::move(c.albedo);
    if (img.variance.initialized())
        img.variance = std::move(c.variance);
    if (img.half_a.initialized()) {
        img.half_a = std::move(c.half_a);
        img.half_b = std::move(c.half_b);
    }
    // Every image of the strip over what the filter reads.
    for (ImageBuf* b : { &img.normal, &img.depth, &img.id, &img.remodulation,
                         &img.motion })
        crop_to(*b, region, j.threads);
    if (strip.core.ybegin == p.noisy.ybegin)
        log_combined(j, c, result);
}


}  // namespace job
}  // namespace zdenoise
