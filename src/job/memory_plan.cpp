// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "memory_plan.h"

#include <fstream>

#include <OpenImageIO/strutil.h>

#include "failure.h"
#include "strips.h"

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
/// one would need more than 1 GiB (very wide frames: 16384 pixels) or the
/// memory limit demands it. Refuses,
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
        while (needed > budget && rows > kThinnest) {
            const int next = (height + n) / (n + 1);
            if (next < efficient && needed <= std::min(double(limit), kEfficient))
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
