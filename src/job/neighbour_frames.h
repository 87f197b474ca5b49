// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// --temporal K (docs/TEMPORAL.md): the neighbouring frames' role images,
// read as frame t's selections pick them, and the flows from frame t to
// each neighbour, from the renderers' motion vectors.

#pragma once

#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "input_files.h"
#include "job_types.h"

namespace zdenoise {
namespace job {

/// One frame's images of the roles temporal_combine() reads (unused roles
/// stay empty), over the whole frame, float.
struct FrameRoles {
    OIIO::ImageBuf radiance, albedo, normal, depth, id, variance, half_a,
        half_b, motion;
};

/// The roles `roles` selects in job `j`'s files, read from neighbour job
/// `nj`'s files (the frame's own paths; every role's channels named as in
/// frame t's file, over the same pixels), over the rows `rows` of the
/// frame `frame_t` (frame t's --in window). Fails naming the neighbour's
/// file.
FrameRoles
read_neighbour_roles(const Job& j, const Job& nj, const RoleSelections& roles,
                     InputFiles& frame_files, const OIIO::ROI& frame_t,
                     const OIIO::ROI& rows, int threads);

/// The rows of the frame `frame` that the pixels of `flow` land on (the
/// nearest pixels of p + flow), within the frame; `flow` null: its own rows.
OIIO::ROI
rows_reached(const OIIO::ImageBuf* flow, const OIIO::ROI& over,
             const OIIO::ROI& frame);

/// Where each pixel of a frame shows in the next frame (`direction` 1) or
/// in the previous one (-1): temporal_combine()'s flow, offsets in pixels,
/// x right, y down the rows. From the frame's motion vectors as the
/// renderer wrote them: Cycles' Vector pass (4 channels) or 2 channels of
/// the motion since the previous frame (Arnold's motionvector; the next
/// frame assumed to continue it).
OIIO::ImageBuf
vector_flow(const OIIO::ImageBuf& vectors, int direction, int threads);

}  // namespace job
}  // namespace zdenoise
