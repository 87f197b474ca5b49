// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Reading an input file a band of rows at a time, in its own pixel types:
// what lets a job stream a frame of any size through bounded memory
// (docs/PERFORMANCE.md, "Memory").

#pragma once

#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

namespace zdenoise {
namespace job {

/// Some channels of one scanline or tiled file, all its parts (a multipart
/// EXR's parts cover the same pixels), over a band of rows that moves down
/// the image. Channels are numbered as in the file's channel list: part 0's,
/// then part 1's, and so on. Each row is decoded once, however many bands
/// hold it.
class RowReader {
public:
    /// `parts`: each part's native spec (all with the same data window);
    /// `wanted[c]`: whether channel c is ever asked for. Each part reads the
    /// range of channels from its first to its last wanted one in one call,
    /// so that a compressed block is decoded once.
    RowReader(const std::string& path, const std::vector<OIIO::ImageSpec>& parts,
              const std::vector<bool>& wanted);
    ~RowReader();

    /// Bytes held per pixel of a row, and besides the rows (a tiled file's
    /// row of tiles), for the memory estimate.
    size_t pixel_bytes() const;
    size_t fixed_bytes() const;

    /// Make room for bands of up to `rows` rows, once: a buffer growing by
    /// steps would briefly hold its old and new copies.
    void reserve(int rows);

    /// Hold rows [ybegin, yend) (within the data window): rows already held
    /// are kept, the rest are read; rows above ybegin are let go. Bands must
    /// not move up. On failure `error` says why (without the file's name).
    bool hold(int ybegin, int yend, int nthreads, std::string& error);

    /// The pixel type of channel c in the file.
    OIIO::TypeDesc format(int c) const;

    /// Whether channel b follows channel a in the held pixels (same part,
    /// the next bytes), so that the two move as one.
    bool adjacent(int a, int b) const;

    /// Whether channel c's values lie at addresses its type may be read
    /// from (a file's pixels are packed: a float after three halves does
    /// not).
    bool aligned(int c) const;

    /// Channel c of row y (held), pixel x: its first byte; pixels of a row
    /// are `stride(c)` bytes apart, rows `row_stride(c)`.
    const unsigned char* at(int c, int x, int y) const;
    OIIO::stride_t stride(int c) const;
    OIIO::stride_t row_stride(int c) const;

private:
    struct Part;
    bool read_tiled(int part, int ybegin, int yend, unsigned char* dst);
    std::string m_path;
    std::unique_ptr<OIIO::ImageInput> m_input;
    std::vector<Part> m_parts;
    std::vector<std::pair<int, int>> m_channel;  ///< c -> (part, index in it)
};

}  // namespace job
}  // namespace zdenoise
