// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The centres of one tile in blocks (docs/FILTER.md section 8): their
// geometry, the four phases that run in parallel without locks, and the
// order of the centres within a block, every fit point or strided.

#pragma once

#include <zdenoise/zdenoise.h>

#include "filter_inputs.h"
#include "window_fitter.h"

namespace zdenoise {
namespace detail {

/// The stride the filter uses: centre_stride, at most r_min + 1 so that the
/// smallest windows of neighbouring lattice points still overlap (r_min 1
/// with the default stride 3 means stride 2, not an error).
int
effective_stride(const FilterOptions& o);

/// The blocks of centres of the output pixels `out`: the fit points within
/// r_max of them, in blocks anchored at the image's data-window origin, at
/// least 2 r_max + 1 pixels on a side (multiples of the stride), so that
/// the splat footprints of the blocks of one phase never overlap.
struct CentreBlocks {
    ROI image;                   ///< the whole image (its origin anchors)
    int stride = 1;
    int block_w = 0, block_h = 0;
    int cx0 = 0, cx1 = 0, cy0 = 0, cy1 = 0;  ///< the centres' bounds
    int first_row = 0, first_col = 0, nrows = 0, ncols = 0;

    CentreBlocks(const FilterOptions& opt, const ROI& image, const ROI& out);

    int count() const { return nrows * ncols; }
    int row(int b) const { return first_row + b / ncols; }
    int col(int b) const { return first_col + b % ncols; }
    /// The phase of block b (0-3), by the parity of its row and column.
    int phase(int b) const { return (row(b) % 2) * 2 + col(b) % 2; }
};

/// Fit and splat the centres of block b in their fixed order: every fit
/// point in raster order, or with a stride first the lattice points and
/// then the fit points the lattice does not speak for. Counts the windows
/// of centres in `out` into st.
void
fit_block(const CentreBlocks& blocks, int b, const FilterInputs& in,
          const FilterOptions& opt, const ROI& out, WindowFitter& fitter,
          FilterStats& st);

}  // namespace detail
}  // namespace zdenoise
