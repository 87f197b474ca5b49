// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// radiance_bounds() (docs/FILTER.md section 13.2), by sliding extrema
// (sliding_extrema.h) over the rows, then the columns.

#include "radiance_bounds.h"
#include "sliding_extrema.h"

#include <algorithm>
#include <cstdint>
#include <limits>

namespace zdenoise {
namespace detail {

using namespace OIIO;

void
radiance_bounds(const FilterInputs& in, const ROI& out, int r_max,
                std::vector<float>& lo, std::vector<float>& hi,
                std::vector<float>& inv_albedo, int nthreads,
                const std::atomic<bool>* cancel)
{
    const float inf = std::numeric_limits<float>::infinity();
    const ROI rows(out.xbegin, out.xend, std::max(out.ybegin - r_max, in.region.ybegin),
                   std::min(out.yend + r_max, in.region.yend));
    const size_t w = size_t(out.width()), n = out.npixels();
    const int rw = in.region.width();
    // Per channel: the extremes over each row's window, rows.height() rows
    // of w, then over the columns of those.
    std::vector<float> rlo(3 * w * size_t(rows.height())), rhi(rlo.size());
    for_rows(rows, nthreads, [&](int y) {
        if (cancel_requested(cancel))
            return;
        const size_t nrow = size_t(rw);
        std::vector<float> vlo(nrow), vhi(nrow), elo(nrow), ehi(nrow);
        SlidingExtrema ext;
        for (int c = 0; c < 3; ++c) {
            for (int u = 0; u < rw; ++u) {
                const size_t i = in.index(in.region.xbegin + u, y);
                const bool fit = (in.cls[i] & kFitPoint) != 0;
                vlo[size_t(u)] = fit ? in.lfit[c][i] : inf;
                vhi[size_t(u)] = fit ? in.lfit[c][i] : -inf;
            }
            ext.run(vlo.data(), vhi.data(), rw, 1, r_max, elo.data(), ehi.data());
            const size_t k = (size_t(c) * size_t(rows.height()) + size_t(y - rows.ybegin)) * w;
            std::copy_n(&elo[size_t(out.xbegin - in.region.xbegin)], w, &rlo[k]);
            std::copy_n(&ehi[size_t(out.xbegin - in.region.xbegin)], w, &rhi[k]);
        }
    });
    lo.assign(3 * n, inf);
    hi.assign(3 * n, -inf);
    inv_albedo.assign(3 * n, 0.0f);
    const int rh = rows.height();
    parallel_for(int64_t(0), int64_t(3 * w), [&](int64_t col) {
        if (cancel_requested(cancel))
            return;
        const size_t c = size_t(col) / w, x = size_t(col) % w;
        const size_t ncol = size_t(rh);
        std::vector<float> elo(ncol), ehi(ncol);
        SlidingExtrema ext;
        const size_t first = c * size_t(rh) * w + x;
        ext.run(&rlo[first], &rhi[first], rh, w, r_max, elo.data(), ehi.data());
        for (int y = out.ybegin; y < out.yend; ++y) {
            const size_t k = 3 * (size_t(y - out.ybegin) * w + x) + c;
            lo[k] = elo[size_t(y - rows.ybegin)];
            hi[k] = ehi[size_t(y - rows.ybegin)];
            inv_albedo[k] = in.inv_albedo[c][in.index(out.xbegin + int(x), y)];
        }
    }, paropt_any_length(nthreads));
}

}  // namespace detail
}  // namespace zdenoise
