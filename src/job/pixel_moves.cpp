// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "pixel_moves.h"

#include <cstring>

namespace zdenoise {
namespace job {

using namespace OIIO;


/// Whether values of `type` can be read or written at `p`, `stride` bytes
/// apart. Packed pixels of mixed types do not always allow it (a float
/// after three halves), and then the values are moved as bytes.
bool
aligned_for(const void* p, stride_t stride, TypeDesc type)
{
    const size_t a = type.basesize();
    return reinterpret_cast<uintptr_t>(p) % a == 0 && size_t(stride) % a == 0;
}


/// Move `n` consecutive channels of one pixel type from one interleaved
/// row to another, converting to `to` (OIIO's conversions, as a read or
/// write converting them would).
void
move_channels(const unsigned char* src, TypeDesc from, stride_t src_stride,
              unsigned char* dst, TypeDesc to, stride_t dst_stride, int n,
              int width)
{
    const size_t in = size_t(n) * from.size(), out = size_t(n) * to.size();
    if (from == to) {
        for (int x = 0; x < width; ++x)
            std::memcpy(dst + x * dst_stride, src + x * src_stride, in);
        return;
    }
    // Misaligned values go through packed (so aligned) rows of their own.
    thread_local std::vector<unsigned char> packed_in, packed_out;
    if (!aligned_for(src, src_stride, from)) {
        packed_in.resize(in * size_t(width));
        for (int x = 0; x < width; ++x)
            std::memcpy(&packed_in[size_t(x) * in], src + x * src_stride, in);
        src        = packed_in.data();
        src_stride = stride_t(in);
    }
    if (!aligned_for(dst, dst_stride, to)) {
        packed_out.resize(out * size_t(width));
        convert_image(n, width, 1, 1, src, from, src_stride, AutoStride,
                      AutoStride, packed_out.data(), to, stride_t(out),
                      AutoStride, AutoStride);
        for (int x = 0; x < width; ++x)
            std::memcpy(dst + x * dst_stride, &packed_out[size_t(x) * out],
                        out);
        return;
    }
    convert_image(n, width, 1, 1, src, from, src_stride, AutoStride,
                  AutoStride, dst, to, dst_stride, AutoStride, AutoStride);
}

std::vector<ChannelRun>
channel_runs(const RowReader& rows, const std::vector<int>& indices)
{
    std::vector<ChannelRun> runs;
    for (size_t k = 0; k < indices.size(); ++k) {
        const int c = indices[k];
        if (!runs.empty()) {
            ChannelRun& r  = runs.back();
            const int prev = indices[size_t(r.first + r.count - 1)];
            if (rows.format(c) == rows.format(prev)
                && rows.adjacent(prev, c)) {
                ++r.count;
                continue;
            }
        }
        runs.push_back({ int(k), 1 });
    }
    return runs;
}

}  // namespace job
}  // namespace zdenoise
