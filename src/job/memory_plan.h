// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The memory plan: what a strip of the frame costs (the files' held rows,
// the role images, the filter's tile, the output's rows and codecs), and
// from that the strips' height. A frame whose strip would not fit the
// memory limit is refused here, before any pixel is read. Apart from the
// job because it is a model of memory, measured (docs/PERFORMANCE.md,
// "Memory"), not a step of the work.

#pragma once

#include <algorithm>
#include <string>

#include <OpenImageIO/imageio.h>

#include "internal.h"
#include "input_files.h"
#include "output.h"
#include "job_types.h"

namespace zdenoise {
namespace job {

struct Plan;  // strip_plan.h

/// The memory a strip needs. Measured peaks of the heap (docs/PERFORMANCE.md,
/// "Memory") sit at or below these estimates, which leave out what does
/// not depend on the job (the program and its libraries); the guard must
/// err on the side of refusing.
struct StripCost {
    double held_pixel = 0;  ///< per pixel of the held rows (strip + halo)
    double core_pixel = 0;  ///< per pixel of the strip's own rows
    double file_row   = 0;  ///< the input files' held rows, per row
    double out_row    = 0;  ///< one output row as the sink takes it
    double fixed      = 0;  ///< decoders, encoder, an output held whole
    int width = 0, height = 0;
    int halo   = 0;  ///< the filter's (filter_halo())
    int around = 0;  ///< rows read above and below a strip (>= halo)

    /// The filter's working memory: per pixel of one internal tile of
    /// regression_filter() with its halo (its decoded planes, accumulators
    /// and, with select, the selection's planes), and the tile's side
    /// (detail::kFilterTile, or kSelectionTile with select).
    double tile_pixel = 0;
    int tile          = 0;

    double bytes(int rows) const
    {
        const double held = std::min(double(height),
                                     double(rows) + 2.0 * around);
        const double tile_w = std::min(double(width), double(tile) + 2.0 * halo);
        const double tile_h = std::min(held, double(tile) + 2.0 * halo);
        return fixed + file_row * held + held_pixel * width * held
               + core_pixel * width * double(rows)
               + out_row * std::min(rows, Output::kBandRows)
               + tile_pixel * tile_w * tile_h;
    }
};


/// Half of the machine's memory (MemTotal, or the cgroup's memory.max when
/// lower): room for the frame and whatever else runs on a render node.
uint64_t
default_memory_limit();

/// "512 MiB", "1.5 GiB".
std::string
readable_size(double bytes);

/// What an OpenEXR reader or writer of a file with these pixels keeps
/// besides them (per thread of OpenEXR's pool, blocks in flight with their
/// compressor's buffers).
double
codec_bytes(const OIIO::ImageSpec& spec, size_t pixel_bytes);

/// Add to `cost` the rows every wanted file of `files` holds, its reader's
/// buffers and decoders.
void
add_file_costs(StripCost& cost, InputFiles& files);

/// The bytes per held pixel of a role's image: none when it is the file's
/// rows themselves (Strip::image() with `read_only`), else a float copy.
double
role_bytes(InputFiles& files, const Selection& s, bool read_only);

/// Add to `cost` the output: rows of `pixel_bytes` per pixel as the sink
/// takes them, and the whole image if the sink holds it, else the
/// encoder of a file with the spec `spec`.
void
add_output_costs(StripCost& cost, const OutputSink& sink,
                 const OIIO::ImageSpec& spec, size_t pixel_bytes);

/// The memory a strip of job `j` costs, as plan() has decided it (`p`:
/// roles, layers, albedo, maps, the output's rows as `sink` takes them;
/// `spec` the output's): the model of memory, measured (docs/PERFORMANCE.md,
/// "Memory").
StripCost
strip_cost(const Job& j, const Plan& p, InputFiles& files,
           const OutputSink& sink, const OIIO::ImageSpec& spec);

/// How many rows a strip of job `j` has (result.strip_rows, strips,
/// estimated_bytes); refuses a job whose strip needs more memory than
/// allowed.
void
plan_strips(const Job& j, const InputHeader& in, const StripCost& cost,
            JobResult& result);

}  // namespace job
}  // namespace zdenoise
