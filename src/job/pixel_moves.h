// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Moving channels between interleaved rows of mixed pixel types, byte by
// byte where the values are not aligned for their type. The job's only
// pixel-level loop outside the library (reading a role's channels out of
// a file's rows, assembling the output's rows), kept apart so that the
// job's files above it deal in images and rows, not bytes.

#pragma once

#include <vector>

#include <OpenImageIO/imageio.h>

#include "row_reader.h"

namespace zdenoise {
namespace job {

/// Whether values of `type` can be read or written at `p`, `stride` bytes
/// apart. Packed pixels of mixed types do not always allow it (a float
/// after three halves), and then the values are moved as bytes.
bool
aligned_for(const void* p, OIIO::stride_t stride, OIIO::TypeDesc type);

/// Move `n` consecutive channels of one pixel type from one interleaved
/// row to another, converting to `to` (OIIO's conversions, as a read or
/// write converting them would).
void
move_channels(const unsigned char* src, OIIO::TypeDesc from,
              OIIO::stride_t src_stride, unsigned char* dst,
              OIIO::TypeDesc to, OIIO::stride_t dst_stride, int n, int width);

/// Runs of the file channels `indices` that lie next to each other in the
/// file with one pixel type: each moves in one call.
struct ChannelRun {
    int first = 0;  ///< position in `indices`
    int count = 0;
};

std::vector<ChannelRun>
channel_runs(const RowReader& rows, const std::vector<int>& indices);

}  // namespace job
}  // namespace zdenoise
