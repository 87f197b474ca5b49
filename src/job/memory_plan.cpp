// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "memory_plan.h"

#include <fstream>

#include <OpenImageIO/strutil.h>

#include "alpha_plan.h"
#include "failure.h"
#include "strips.h"
#include "strip_plan.h"
#include "temporal_strip.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

std::string
readable_size(double bytes)
{
    const double mib = bytes / double(1 << 20);
    return mib < 1024.0 ? format("{:.0f} MiB", mib)
                        : format("{:.1f} GiB", mib / 1024.0);
}


/// What an OpenEXR reader or writer of a file with these pixels keeps
/// besides them: per thread of OpenEXR's pool, two blocks (tiles, or rows:
/// 16 for zip, 32 for piz, ...) in flight, each with its compressor's
/// buffers (measured: three times the block for zip).
double
codec_bytes(const ImageSpec& spec, size_t pixel_bytes)
{
    const std::string c = Strutil::lower(spec.get_string_attribute("compression"));
    int threads = 0;
    OIIO::getattribute("exr_threads", threads);
    threads = std::max(threads, 1);
    if (spec.tile_width)
        return 3.0 * 2.0 * threads * double(spec.tile_width)
               * double(spec.tile_height) * double(pixel_bytes);
    int rows = 16;
    if (c.empty() || c == "none" || c == "rle" || c == "zips")
        rows = 1;
    else if (Strutil::starts_with(c, "dwab"))
        rows = 256;
    else if (!Strutil::starts_with(c, "zip"))
        rows = 32;
    return 3.0 * 2.0 * threads * rows * double(pixel_bytes)
           * double(spec.width);
}


void
add_file_costs(StripCost& cost, InputFiles& files)
{
    for (const std::string& path : files.paths()) {
        const InputHeader& h = files.header(path);
        cost.file_row += double(files.rows(path).pixel_bytes())
                         * double(h.spec.width);
        cost.fixed += double(files.rows(path).fixed_bytes());
        for (const ImageSpec& part : h.native)
            cost.fixed += codec_bytes(part, part.pixel_bytes(true));
    }
}


double
role_bytes(InputFiles& files, const Selection& s, bool read_only)
{
    const RowReader& rows = files.rows(s.path);
    return read_only && wraps(rows, s, channel_runs(rows, s.indices))
               ? 0.0
               : 4.0 * double(s.indices.size());
}


void
add_output_costs(StripCost& cost, const OutputSink& sink,
                 const ImageSpec& spec, size_t pixel_bytes)
{
    cost.out_row = double(pixel_bytes) * cost.width;
    if (sink.holds_image()) {
        cost.fixed += cost.out_row * cost.height;
    } else {
        ImageSpec scanlines = spec;  // written as scanlines (FileSink)
        scanlines.tile_width = scanlines.tile_height = 0;
        cost.fixed += codec_bytes(scanlines, pixel_bytes);
    }
}


StripCost
strip_cost(const Job& j, const Plan& p, InputFiles& files,
           const OutputSink& sink, const ImageSpec& spec)
{
    StripCost cost;
    cost.width  = p.noisy.width();
    cost.height = p.noisy.height();
    // A direct layer's keep_structure() and denoise_alpha()'s read one
    // pixel beyond the strip.
    const bool alpha = denoised_alpha_channel(j, p.roles.radiance) >= 0;
    cost.halo = filter_halo(j.filter) + (p.path || alpha ? 1 : 0);
    // The residual layer's mask looks further than the filter.
    cost.around = cost.halo + p.layers.reach
                  + p.albedo.halo() + split_reach(p.groups, p.aovs);
    add_file_costs(cost, files);
    // Role images: copies when converted or not lying together in the
    // file, else the file's rows themselves (Strip::image()). The quotient
    // (demodulate()), the filtered and the denoised radiance.
    cost.held_pixel = role_bytes(files, p.roles.radiance, p.radiance_as_is)
                      + 16.0;
    cost.core_pixel = 32.0;
    // The alpha (denoise_alpha()): its plane, the coverage as light and its
    // albedo of 1 (held), and the result (strip).
    if (alpha) {
        cost.held_pixel += 4.0 + 24.0;
        cost.core_pixel += 4.0 + 12.0;
    }
    // The light groups (split_light_groups()): each group's copy and its
    // result, the denoised beauty over the rows around the strip.
    const double groups = double(p.groups.names.size());
    cost.held_pixel += groups * 12.0 + (groups > 0 ? 16.0 : 0.0);
    cost.core_pixel += groups * 12.0;
    // The AOVs (--aov): each one's copy (held) and result, split one at a
    // time; the denoised beauty around the strip as for the groups.
    const double aovs = double(p.aovs.names.size());
    cost.held_pixel += aovs * 12.0 + (aovs > 0 && groups == 0 ? 16.0 : 0.0);
    cost.core_pixel += aovs * 12.0;
    if (!p.layered)
        cost.held_pixel += role_bytes(files, p.roles.albedo, p.albedo_as_is);
    for (const OptionalRole* o : p.roles.optional())
        if (o->used)
            cost.held_pixel += role_bytes(files, o->selection,
                                          role_as_is(*o, p));
    if (p.layered) {
        // Each layer's radiance and albedo sums, the residual and the sum
        // (over the held rows), each denoised layer (over the strip).
        cost.held_pixel += 24.0 * double(p.layers.layers.size()) + 24.0
                           + (p.layers.residual_is_layer ? 8.0 : 0.0);
        cost.core_pixel += 12.0 * double(p.layers.layers.size());
    }
    // The filter's tile: its decoded planes and accumulators (192 bytes a
    // pixel, on the safe side); with select also the selection's planes
    // (FILTER.md 13: candidate 0's output and hat diagonal, the pilot, the
    // fitted quotient, the two feature regressions, the risks; 1080p in 2
    // strips: 812 MiB peak, this estimate 860 MiB).
    cost.tile       = j.filter.select ? detail::kSelectionTile : detail::kFilterTile;
    cost.tile_pixel = j.filter.select ? 320.0 : 192.0;
    // The prefiltered albedo, its variance, its sums (4 doubles).
    if (p.albedo.prefilter)
        cost.held_pixel += 24.0 + 32.0;
    if (p.albedo.pool)
        cost.held_pixel += 12.0;
    // The maps, and the filter's sums for them (5 doubles a pixel).
    if (p.maps)
        cost.core_pixel += 16.0 + 40.0 + (p.layered ? 48.0 : 0.0);
    add_output_costs(cost, sink, spec, p.output.pixel_bytes);
    if (j.temporal > 0) {
        // The light test's box around what the filter reads; each
        // neighbour's roles (as floats, over about as many rows as the
        // strip: the rows its flow reaches), its flow and the combined
        // images.
        cost.around += temporal_reach(j);
        double role_floats = double(p.roles.radiance.indices.size()
                                    + p.roles.albedo.indices.size());
        for (const OptionalRole* o : p.roles.optional())
            if (o->used)
                role_floats += double(o->selection.indices.size());
        cost.held_pixel += double(j.neighbours.size()) * (4.0 * role_floats + 16.0)
                           + 4.0 * role_floats;
    }
    return cost;
}


/// How many rows a strip has: --tile, or else as many as keep a strip's
/// memory within a comfortable size (or the memory limit, when that is
/// lower), in strips of equal height. Strips are at most as tall as the
/// filter's internal tile: up to that, cutting the frame costs the filter
/// nothing a whole-frame run does not pay too (a strip boundary, like a
/// tile boundary, makes the centres within r_max of it be fitted twice).
/// Below 256 rows that cost grows quickly (2 r_max of S rows), and below
/// three times the rows re-read around a strip (2 `around`) more than a
/// third of the work is on rows another strip filters too (the selection's
/// halo is twice the filter's), so strips are thinner than either only when
/// one would need more than 1 GiB or the memory limit demands it; and where
/// even the thinnest strip needs more than the comfortable size (wide
/// frames, path mode's larger halo), only the limit thins them. Refuses,
/// before any pixel is read, a job whose strip would need more memory than
/// allowed: an oversized (or corrupt) header must fail with a message, not
/// get the process killed.
void
plan_strips(const Job& j, const InputHeader& in, const StripCost& cost,
            JobResult& result)
{
    const uint64_t limit = j.mem_limit ? j.mem_limit : default_memory_limit();
    // Leaves room for the rest of a render node's work; a 1080p frame with
    // 54 passes takes four strips of 270 rows.
    constexpr double kComfortable = 256.0 * (1 << 20);
    // What a strip may take to stay efficient: a 1080p frame with the
    // selection takes 2 strips of 540 rows at about 850 MiB.
    constexpr double kEfficient = 1024.0 * (1 << 20);
    const int efficient           = std::max(256, 3 * 2 * cost.around);
    constexpr int kThinnest       = 16;
    const int height = cost.height;
    int rows         = 0;
    double needed    = 0.0;
    if (j.tile_rows > 0) {
        rows   = std::min(j.tile_rows, height);
        needed = cost.bytes(rows);
    } else {
        const double budget = std::min(double(limit), kComfortable);
        int n  = (height + cost.tile - 1) / cost.tile;
        rows   = (height + n - 1) / n;
        needed = cost.bytes(rows);
        // Where even the thinnest strip exceeds the budget, its halo is what
        // takes the memory, and thinner strips only read and filter it
        // again (an 8K frame in path mode: 270 strips of 16 rows, 34 min,
        // against about 6 in strips of 720): equal strips of at most
        // `efficient` rows, thinner only as the limit demands.
        const bool halo_bound = needed > budget
                                && cost.bytes(std::min(kThinnest, height)) > budget;
        if (halo_bound) {
            n      = std::max(n, (height + efficient - 1) / efficient);
            rows   = (height + n - 1) / n;
            needed = cost.bytes(rows);
        }
        while (needed > (halo_bound ? double(limit) : budget) && rows > kThinnest) {
            const int next = (height + n) / (n + 1);
            if (!halo_bound && next < efficient
                && needed <= std::min(double(limit), kEfficient))
                break;
            ++n;
            rows   = next;
            needed = cost.bytes(rows);
        }
    }
    if (needed > double(limit)) {
        const std::string how
            = j.tile_rows > 0 ? format(" in strips of {} rows (--tile)", rows)
              : rows < height ? format(" even in strips of {} rows", rows)
                              : std::string();
        fail(format("'{}' is {}x{} with {} channels: denoising it needs "
                    "about {}{}, more than the memory limit of {}",
                    j.in.path, cost.width, height, in.channelnames.size(),
                    readable_size(needed), how,
                    readable_size(double(limit))));
    }
    result.strip_rows      = rows;
    result.strips          = (height + rows - 1) / rows;
    result.estimated_bytes = needed;
}


uint64_t
default_memory_limit()
{
    // Half of the RAM, or of the cgroup's limit when the job runs in a
    // container or a farm slot with one: what the kernel's OOM killer
    // enforces.
    uint64_t total = 0;
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    uint64_t kib = 0;
    while (meminfo >> key >> kib) {
        if (key == "MemTotal:") {
            total = kib * 1024;
            break;
        }
        meminfo.ignore(256, '\n');
    }
    std::ifstream cgroup("/sys/fs/cgroup/memory.max");
    uint64_t cgroup_max = 0;
    if (cgroup >> cgroup_max && cgroup_max > 0
        && (total == 0 || cgroup_max < total))
        total = cgroup_max;
    if (total == 0)
        total = uint64_t(8) << 30;  // unknown: assume a modest machine
    return total / 2;
}

}  // namespace job
}  // namespace zdenoise
