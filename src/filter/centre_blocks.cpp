// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Blocks of centres and strided centres (docs/FILTER.md section 8).

#include "centre_blocks.h"

#include <algorithm>
#include <vector>

#include "guide_weight.h"

namespace zdenoise {
namespace detail {

int
effective_stride(const FilterOptions& o)
{
    return std::max(1, std::min(o.centre_stride, std::max(o.r_min, 1) + 1));
}


CentreBlocks::CentreBlocks(const FilterOptions& opt, const ROI& image_,
                           const ROI& out)
    : image(image_)
    , stride(effective_stride(opt))
{
    // Centres: fit points within r_max of the output.
    cy0 = std::max(image.ybegin, out.ybegin - opt.r_max);
    cy1 = std::min(image.yend, out.yend + opt.r_max);
    cx0 = std::max(image.xbegin, out.xbegin - opt.r_max);
    cx1 = std::min(image.xend, out.xend + opt.r_max);
    // Blocks, not whole strips of rows, so that a phase has enough of them
    // to keep every thread busy to its end.
    block_h   = (std::max(2 * opt.r_max + 1, 32) + stride - 1) / stride * stride;
    block_w   = (std::max(2 * opt.r_max + 1, 64) + stride - 1) / stride * stride;
    first_row = (cy0 - image.ybegin) / block_h;
    first_col = (cx0 - image.xbegin) / block_w;
    nrows = cy1 > cy0 ? (cy1 - 1 - image.ybegin) / block_h - first_row + 1 : 0;
    ncols = cx1 > cx0 ? (cx1 - 1 - image.xbegin) / block_w - first_col + 1 : 0;
}


namespace {

/// The centres of one block: [xa, xb) x [ya, yb), within the blocks' bounds
/// of centres; the block itself ends at bx_end, by_end.
struct BlockCentres {
    int xa, xb, ya, yb;
    int bx_end, by_end;
};

BlockCentres
block_centres(const CentreBlocks& blocks, int b)
{
    const ROI& image = blocks.image;
    const int br = blocks.row(b), bc = blocks.col(b);
    BlockCentres c;
    c.ya     = std::max(blocks.cy0, image.ybegin + br * blocks.block_h);
    c.yb     = std::min(blocks.cy1, image.ybegin + (br + 1) * blocks.block_h);
    c.xa     = std::max(blocks.cx0, image.xbegin + bc * blocks.block_w);
    c.xb     = std::min(blocks.cx1, image.xbegin + (bc + 1) * blocks.block_w);
    c.by_end = image.ybegin + (br + 1) * blocks.block_h;
    c.bx_end = image.xbegin + (bc + 1) * blocks.block_w;
    return c;
}

/// Fit (and unless splat_window is false, splat) the window of one centre,
/// counting it when it is an output pixel's.
StopReason
fit_centre(WindowFitter& fitter, const ROI& out, int x, int y,
           bool splat_window, FilterStats& st)
{
    int radius        = 0;
    StopReason reason = fitter.process(x, y, radius, splat_window);
    if (splat_window && out.contains(x, y)) {
        ++st.windows;
        st.radius_sum += radius;
        st.stop_quality += reason == StopReason::Quality;
        st.stop_size += reason == StopReason::Size;
        st.stop_edge += reason == StopReason::Edge;
    }
    return reason;
}

/// Stride 1: every fit point of the block is a centre, in raster order.
void
fit_every_centre(const BlockCentres& c, const FilterInputs& in,
                 const ROI& out, WindowFitter& fitter, FilterStats& st)
{
    for (int y = c.ya; y < c.yb; ++y)
        for (int x = c.xa; x < c.xb; ++x)
            if (in.cls[in.index(x, y)] & kFitPoint)
                fit_centre(fitter, out, x, y, true, st);
}

/// One past the lattice point at or after `last` (lattice origin `origin`),
/// within the image.
int
lattice_end(int last, int origin, int image_end, int stride)
{
    const int up = last + (stride - (last - origin) % stride) % stride;
    return std::min(up + 1, image_end);
}

/// Strided centres: first the lattice points of the block, then every
/// other fit point that the lattice windows of its cell cannot speak for:
/// none of them is on its surface, or (stride_edges) one on its surface
/// stopped at an edge (stride_edges 2: of these, the fit points of a
/// checkerboard, x + y even from the frame's origin). The block's sides
/// are multiples of the stride, so the lattice points of its cells are
/// its own plus the first column and row of the next blocks, which are
/// fitted here only to decide (the next blocks splat them). The decision
/// is thus the same for any tile, strip or thread count.
void
fit_strided_centres(const BlockCentres& c, const ROI& image, int stride,
                    const FilterInputs& in, const FilterOptions& opt,
                    const ROI& out, WindowFitter& fitter, FilterStats& st)
{
    const int lxa = c.xa - (c.xa - image.xbegin) % stride;
    const int lya = c.ya - (c.ya - image.ybegin) % stride;
    const int lxb = lattice_end(c.xb - 1, image.xbegin, image.xend, stride);
    const int lyb = lattice_end(c.yb - 1, image.ybegin, image.yend, stride);
    const int nlx = (lxb - 1 - lxa) / stride + 1;
    const int nly = (lyb - 1 - lya) / stride + 1;
    enum LatticeWindow : uint8_t { kNone, kSmooth, kEdge };
    std::vector<uint8_t> lattice(size_t(nlx) * size_t(nly), kNone);
    for (int j = 0; j < nly; ++j)
        for (int i = 0; i < nlx; ++i) {
            const int x = lxa + i * stride, y = lya + j * stride;
            if (in.cls[in.index(x, y)] & kFitPoint) {
                const bool own = x < c.bx_end && y < c.by_end;
                lattice[size_t(j) * nlx + i]
                    = fit_centre(fitter, out, x, y, own, st) == StopReason::Edge
                              && opt.stride_edges
                          ? kEdge
                          : kSmooth;
            }
        }
    GuideWeight lattice_guide(in, opt);
    for (int y = c.ya; y < c.yb; ++y) {
        for (int x = c.xa; x < c.xb; ++x) {
            const int ox = (x - image.xbegin) % stride;
            const int oy = (y - image.ybegin) % stride;
            if ((ox == 0 && oy == 0) || !(in.cls[in.index(x, y)] & kFitPoint))
                continue;
            // The up to four lattice points of the cell around it.
            const int i0 = (x - ox - lxa) / stride;
            const int j0 = (y - oy - lya) / stride;
            bool covered = false, edge = false;
            for (int j = j0; j <= std::min(j0 + (oy != 0), nly - 1); ++j)
                for (int i = i0; i <= std::min(i0 + (ox != 0), nlx - 1); ++i) {
                    const uint8_t l = lattice[size_t(j) * nlx + i];
                    if (l == kNone)
                        continue;
                    lattice_guide.centre(lxa + i * stride, lya + j * stride);
                    if (lattice_guide(x, y) > 0.0f) {
                        covered = true;
                        edge |= l == kEdge;
                    }
                }
            // stride_edges 2: beside an edge, every other fit point (a
            // checkerboard), whose windows' splats reach the points between.
            const bool edge_centre
                = edge
                  && (opt.stride_edges == 1
                      || ((x - image.xbegin + y - image.ybegin) & 1) == 0);
            if (edge_centre || !covered)
                fit_centre(fitter, out, x, y, true, st);
        }
    }
}

}  // namespace


void
fit_block(const CentreBlocks& blocks, int b, const FilterInputs& in,
          const FilterOptions& opt, const ROI& out, WindowFitter& fitter,
          FilterStats& st)
{
    const BlockCentres c = block_centres(blocks, b);
    if (blocks.stride == 1)
        fit_every_centre(c, in, out, fitter, st);
    else
        fit_strided_centres(c, blocks.image, blocks.stride, in, opt, out,
                            fitter, st);
}

}  // namespace detail
}  // namespace zdenoise
