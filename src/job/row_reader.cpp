// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "row_reader.h"

#include <algorithm>
#include <cstring>

#include <OpenImageIO/strutil.h>

namespace zdenoise {
namespace job {

using namespace OIIO;

/// One part's held rows: channels [chbegin, chend) in their native types,
/// pixels interleaved as ImageInput's native scanlines are.
struct RowReader::Part {
    ImageSpec spec;
    int chbegin = 0, chend = 0;  ///< empty: nothing wanted from this part
    size_t pixel_bytes = 0, row_bytes = 0;
    std::vector<size_t> offset;  ///< byte offset of channel chbegin + i
    int ybegin = 0, yend = 0;    ///< rows held
    std::vector<unsigned char> rows;
    /// A tiled part's last row of tiles read (its first row), kept: the
    /// next band may start inside it.
    int tile_row = -1;
    std::vector<unsigned char> tiles;
};


RowReader::RowReader(const std::string& path,
                     const std::vector<ImageSpec>& parts,
                     const std::vector<bool>& wanted)
    : m_path(path)
{
    size_t first = 0;
    for (size_t p = 0; p < parts.size(); ++p) {
        Part part;
        part.spec   = parts[p];
        const int n = part.spec.nchannels;
        int lo = n, hi = -1;
        for (int k = 0; k < n; ++k) {
            m_channel.emplace_back(int(p), k);
            if (first + size_t(k) < wanted.size() && wanted[first + size_t(k)]) {
                lo = std::min(lo, k);
                hi = std::max(hi, k);
            }
        }
        if (hi >= lo) {
            part.chbegin     = lo;
            part.chend       = hi + 1;
            part.pixel_bytes = part.spec.pixel_bytes(lo, hi + 1, true);
            part.row_bytes   = part.pixel_bytes * size_t(part.spec.width);
            for (int k = lo; k <= hi; ++k)
                part.offset.push_back(part.spec.pixel_bytes(lo, k, true));
        }
        part.ybegin = part.yend = part.spec.y;
        m_parts.push_back(std::move(part));
        first += size_t(n);
    }
}


RowReader::~RowReader() = default;


size_t
RowReader::pixel_bytes() const
{
    size_t n = 0;
    for (const Part& p : m_parts)
        n += p.pixel_bytes;
    return n;
}


void
RowReader::reserve(int rows)
{
    for (Part& p : m_parts)
        p.rows.reserve(size_t(rows) * p.row_bytes);
}


size_t
RowReader::fixed_bytes() const
{
    size_t n = 0;
    for (const Part& p : m_parts)
        if (p.spec.tile_width)
            n += size_t(p.spec.tile_height) * p.row_bytes;
    return n;
}


bool
RowReader::hold(int ybegin, int yend, int nthreads, std::string& error)
{
    if (!m_input) {
        m_input = ImageInput::open(m_path);
        if (!m_input) {
            error = OIIO::geterror();
            return false;
        }
        m_input->threads(nthreads);
    }
    for (size_t p = 0; p < m_parts.size(); ++p) {
        Part& part = m_parts[p];
        if (part.chend == part.chbegin)
            continue;
        // Keep the rows both bands share, moved to the front.
        const int keep_begin = std::max(part.ybegin, ybegin);
        const int keep_end   = std::min(part.yend, yend);
        const size_t rows    = size_t(yend - ybegin);
        if (keep_end > keep_begin) {
            if (keep_begin > part.ybegin)
                std::memmove(part.rows.data(),
                             part.rows.data()
                                 + size_t(keep_begin - part.ybegin)
                                       * part.row_bytes,
                             size_t(keep_end - keep_begin) * part.row_bytes);
        }
        const int first_new = keep_end > keep_begin ? keep_end : ybegin;
        part.rows.resize(rows * part.row_bytes);
        part.ybegin = ybegin;
        part.yend   = first_new;
        if (first_new < yend) {
            unsigned char* dst = part.rows.data()
                                 + size_t(first_new - ybegin) * part.row_bytes;
            const bool ok = part.spec.tile_width
                                ? read_tiled(int(p), first_new, yend, dst)
                                : m_input->read_scanlines(
                                    int(p), 0, first_new, yend, part.spec.z,
                                    part.chbegin, part.chend, TypeUnknown,
                                    dst);
            if (!ok) {
                error = m_input->geterror();
                if (error.empty())
                    error = Strutil::fmt::format("could not read rows {}-{}",
                                                 first_new, yend - 1);
                return false;
            }
        }
        part.yend = yend;
    }
    return true;
}


bool
RowReader::read_tiled(int p, int ybegin, int yend, unsigned char* dst)
{
    // ImageInput reads a tiled file by whole tiles: a row of tiles at a
    // time, the rows wanted copied out of it.
    Part& part   = m_parts[size_t(p)];
    const int th = part.spec.tile_height;
    const int y0 = part.spec.y, ylast = part.spec.y + part.spec.height;
    for (int y = ybegin; y < yend;) {
        const int row = y0 + (y - y0) / th * th;
        const int end = std::min(row + th, ylast);
        if (row != part.tile_row) {
            part.tiles.resize(size_t(end - row) * part.row_bytes);
            part.tile_row = -1;
            if (!m_input->read_tiles(p, 0, part.spec.x,
                                     part.spec.x + part.spec.width, row, end,
                                     part.spec.z, part.spec.z + 1,
                                     part.chbegin, part.chend, TypeUnknown,
                                     part.tiles.data()))
                return false;
            part.tile_row = row;
        }
        const int copy_end = std::min(end, yend);
        std::memcpy(dst + size_t(y - ybegin) * part.row_bytes,
                    part.tiles.data() + size_t(y - row) * part.row_bytes,
                    size_t(copy_end - y) * part.row_bytes);
        y = copy_end;
    }
    return true;
}


TypeDesc
RowReader::format(int c) const
{
    const auto [p, k] = m_channel[size_t(c)];
    return m_parts[size_t(p)].spec.channelformat(k);
}


bool
RowReader::adjacent(int a, int b) const
{
    const auto [pa, ka] = m_channel[size_t(a)];
    const auto [pb, kb] = m_channel[size_t(b)];
    if (pa != pb)
        return false;
    const Part& part = m_parts[size_t(pa)];
    if (ka < part.chbegin || ka >= part.chend || kb < part.chbegin
        || kb >= part.chend)
        return false;
    return part.offset[size_t(kb - part.chbegin)]
           == part.offset[size_t(ka - part.chbegin)]
                  + part.spec.channelformat(ka).size();
}


bool
RowReader::aligned(int c) const
{
    const auto [p, k] = m_channel[size_t(c)];
    const Part& part  = m_parts[size_t(p)];
    const size_t a    = part.spec.channelformat(k).basesize();
    // The rows' buffer comes from the allocator: aligned for any type.
    return part.offset[size_t(k - part.chbegin)] % a == 0
           && part.pixel_bytes % a == 0 && part.row_bytes % a == 0;
}


const unsigned char*
RowReader::at(int c, int x, int y) const
{
    const auto [p, k] = m_channel[size_t(c)];
    const Part& part  = m_parts[size_t(p)];
    return part.rows.data() + size_t(y - part.ybegin) * part.row_bytes
           + size_t(x - part.spec.x) * part.pixel_bytes
           + part.offset[size_t(k - part.chbegin)];
}


stride_t
RowReader::stride(int c) const
{
    return stride_t(m_parts[size_t(m_channel[size_t(c)].first)].pixel_bytes);
}


stride_t
RowReader::row_stride(int c) const
{
    return stride_t(m_parts[size_t(m_channel[size_t(c)].first)].row_bytes);
}

}  // namespace job
}  // namespace zdenoise
