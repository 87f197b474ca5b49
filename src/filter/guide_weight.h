// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The guide weight g(q; p0) = w_n w_d w_id of docs/FILTER.md section 4, and
// the decoding of the normal and object id guides it reads.

#pragma once

#include <vector>

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// Normals of `guide` over in.region into in.normal: unit vectors, all zero
/// where a pixel has none (shorter than 1e-6 or not finite).
void
decode_normals(FilterInputs& in, const ImageBuf& guide);

/// Object ids of `guide` over in.region into in.ids: a plain id (1
/// channel), or (id, coverage) pairs with the coverages normalised to sum
/// 1 a pixel. False (message in dst) for an odd number of channels.
bool
decode_object_ids(FilterInputs& in, ImageBuf& dst, const ImageBuf& guide);

/// The guide weight g(q; p0) of docs/FILTER.md section 4, with what depends
/// on the centre alone computed once per centre.
class GuideWeight {
public:
    GuideWeight(const FilterInputs& in, const FilterOptions& opt)
        : m_in(in)
        , m_cut(opt.normal_cut)
        , m_power(opt.normal_power)
        , m_depth_tol(opt.depth_tolerance)
        , m_pairs0(size_t(2 * std::max(in.id_pairs, 0)), 0.0f)
    {
    }

    /// Set the centre p0.
    void centre(int x0, int y0);

    /// Take `fine`'s centre, placed at (x0, y0) in this level's pixels, one
    /// of which spans `scale` of the fine level's (the pyramid's coarse
    /// fits, docs/FILTER.md 5.1): the centre's own guides stay the fine
    /// pixel's, its depth slopes are scaled to this level's pixels.
    void centre_as(const GuideWeight& fine, float x0, float y0, float scale);

    /// g(q; p0) for a surface pixel q = (x, y).
    float operator()(int x, int y) const
    {
        float g;
        row(x, y, 1, &g);
        return g;
    }

    /// g(q; p0) of the n pixels from (x, y) along row y into g[0, n), 0 for
    /// pixels that are no surface.
    void row(int x, int y, int n, float* g) const;

private:
    const FilterInputs& m_in;
    float m_cut, m_power, m_depth_tol;
    float m_x0 = 0, m_y0 = 0;  ///< the centre, in this level's pixels
    float m_n0[3] = {};        ///< its normal (0: none or no normal guide)
    std::vector<float> m_pairs0;  ///< its (id, coverage) pairs
    float m_zeta0 = 0, m_gx = 0, m_gy = 0;
    float m_id0 = 0;  ///< the centre's plain id
};

}  // namespace detail
}  // namespace zdenoise
