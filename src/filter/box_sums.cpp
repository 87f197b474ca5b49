// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// box_sum_planes(): separable box sums, each 1-D pass the van Herk /
// Gil-Werman split of the line into blocks of the box's width 2r+1,
// anchored at the frame's origin. A box [i-r, i+r] then covers the end of
// one block and the start of the next (or one block exactly), so its sum
// is suffix(i-r) + prefix(i+r), each added from its block's edge: the
// same additions in the same order wherever the region starts. A summed
// area table would subtract large running totals (cancellation, and an
// order that depends on where the region starts).

#include "box_sums.h"

#include <algorithm>

namespace zdenoise {
namespace detail {

namespace {

/// Columns of one task of the vertical pass: enough to run in lanes.
constexpr int kColumnChunk = 64;

/// The 1-D box sums of one line `src` of n values (`x0` the frame
/// coordinate of its first) into `dst` (which may be `src`); `line`, `pre`
/// and `suf` hold n + 2r. A block starts where the frame coordinate is a
/// multiple of 2r + 1; `phase` is the position within it.
template<class T>
void
box_line(const T* src, T* dst, int n, int x0, int r, T* line, T* pre, T* suf)
{
    const int w = 2 * r + 1, len = n + 2 * r;
    std::fill(line, line + r, T(0));
    std::copy(src, src + n, line + r);
    std::fill(line + r + n, line + len, T(0));
    const int first = ((x0 - r) % w + w) % w;  // phase of line[0]
    int phase = first;
    for (int k = 0; k < len; ++k) {
        pre[k] = (k > 0 && phase != 0) ? pre[k - 1] + line[k] : line[k];
        phase  = phase + 1 == w ? 0 : phase + 1;
    }
    phase = (first + len - 1) % w;
    for (int k = len - 1; k >= 0; --k) {
        suf[k] = (k + 1 < len && phase != w - 1) ? line[k] + suf[k + 1] : line[k];
        phase  = phase == 0 ? w - 1 : phase - 1;
    }
    phase = first;
    for (int i = 0; i < n; ++i) {
        dst[i] = phase == 0 ? suf[i] : suf[i] + pre[i + 2 * r];
        phase  = phase + 1 == w ? 0 : phase + 1;
    }
}

/// The vertical pass over columns [c0, c1) of one plane (height h, width
/// `width`): the same split as box_line() with whole rows of the chunk in
/// lanes; `pre` and `suf` hold (h + 2r) * kColumnChunk.
template<class T>
void
box_columns(const T* src, T* dst, int width, int h, int y0, int r, int c0,
            int c1, T* pre, T* suf)
{
    const int w = 2 * r + 1, len = h + 2 * r, nc = c1 - c0;
    auto block  = [&](int k) { return floor_div(y0 + k - r, w); };
    auto row_in = [&](int k) -> const T* {
        return k >= r && k < r + h ? src + size_t(k - r) * size_t(width) + c0
                                   : nullptr;
    };
    for (int k = 0; k < len; ++k) {
        const T* in = row_in(k);
        T* p        = pre + size_t(k) * kColumnChunk;
        const bool go_on = k > 0 && block(k) == block(k - 1);
        for (int c = 0; c < nc; ++c) {
            const T v = in ? in[c] : T(0);
            p[c]      = go_on ? p[c - kColumnChunk] + v : v;
        }
    }
    for (int k = len - 1; k >= 0; --k) {
        const T* in = row_in(k);
        T* s        = suf + size_t(k) * kColumnChunk;
        const bool go_on = k + 1 < len && block(k) == block(k + 1);
        for (int c = 0; c < nc; ++c) {
            const T v = in ? in[c] : T(0);
            s[c]      = go_on ? v + s[c + kColumnChunk] : v;
        }
    }
    for (int i = 0; i < h; ++i) {
        T* out       = dst + size_t(i) * size_t(width) + c0;
        const T* s   = suf + size_t(i) * kColumnChunk;
        const T* p   = pre + size_t(i + 2 * r) * kColumnChunk;
        const bool one_block = block(i) == block(i + 2 * r);
        for (int c = 0; c < nc; ++c)
            out[c] = one_block ? s[c] : s[c] + p[c];
    }
}

}  // namespace


template<class T>
void
box_sum_planes(const Planes<T>& in, Planes<T>& out, int x0, int y0, int r,
               int nthreads)
{
    const int wd = in.width, h = in.height;
    // In place (&in == &out) is allowed: each pass reads a whole line
    // into its prefix and suffix before it writes the line.
    if (out.width != wd || out.height != h || out.count != in.count)
        out = Planes<T>(wd, h, in.count);
    if (wd == 0 || h == 0)
        return;
    // Horizontal pass into out, one task a row of a plane.
    const int64_t rows = int64_t(h) * in.count;
    OIIO::parallel_for(int64_t(0), rows, [&](int64_t t) {
        thread_local std::vector<T> line, pre, suf;
        line.resize(size_t(wd + 2 * r));
        pre.resize(size_t(wd + 2 * r));
        suf.resize(size_t(wd + 2 * r));
        const int k = int(t / h), y = int(t % h);
        box_line(in.plane(k) + size_t(y) * size_t(wd),
                 out.plane(k) + size_t(y) * size_t(wd), wd, x0, r, line.data(),
                 pre.data(), suf.data());
    }, paropt_any_length(nthreads));
    // Vertical pass in place, one task a chunk of columns of a plane: a
    // chunk's column sums read only its own columns.
    const int chunks = (wd + kColumnChunk - 1) / kColumnChunk;
    OIIO::parallel_for(int64_t(0), int64_t(chunks) * in.count, [&](int64_t t) {
        thread_local std::vector<T> pre, suf;
        const size_t need = size_t(h + 2 * r) * kColumnChunk;
        pre.resize(need);
        suf.resize(need);
        const int k = int(t / chunks), c0 = int(t % chunks) * kColumnChunk;
        const int c1 = std::min(c0 + kColumnChunk, wd);
        box_columns(out.plane(k), out.plane(k), wd, h, y0, r, c0, c1, pre.data(),
                    suf.data());
    }, paropt_any_length(nthreads));
}

template void box_sum_planes<double>(const Planes<double>&, Planes<double>&,
                                     int, int, int, int);
template void box_sum_planes<float>(const Planes<float>&, Planes<float>&, int,
                                    int, int, int);

}  // namespace detail
}  // namespace zdenoise
