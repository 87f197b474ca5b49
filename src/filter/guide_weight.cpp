// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The guide weight of docs/FILTER.md section 4: decoding the normal and id
// guides, and g(q; p0) for a centre and a row of pixels (the row loops
// themselves are row kernels, row_kernels.cpp).

#include "guide_weight.h"

#include <cmath>
#include <cstring>

#include "row_kernels.h"

namespace zdenoise {
namespace detail {

void
decode_normals(FilterInputs& in, const ImageBuf& guide)
{
    const size_t npix = in.region.npixels();
    in.normal = read_channels(guide, in.region, 0, 3);
    for (size_t i = 0; i < npix; ++i) {
        float* n = &in.normal[3 * i];
        float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len >= 1e-6f) || !std::isfinite(len))
            n[0] = n[1] = n[2] = 0.0f;
        else
            n[0] /= len, n[1] /= len, n[2] /= len;
    }
}


bool
decode_object_ids(FilterInputs& in, ImageBuf& dst, const ImageBuf& guide)
{
    const size_t npix = in.region.npixels();
    const int nch = guide.nchannels();
    if (nch != 1 && nch % 2 != 0) {
        dst.errorfmt("{}: the object id guide has {} channels; it needs "
                     "1 (a plain id) or an even number ((id, coverage) "
                     "pairs)",
                     "regression_filter", nch);
        return false;
    }
    in.ids      = read_channels(guide, in.region, 0, nch);
    in.id_pairs = nch == 1 ? -1 : nch / 2;
    if (in.id_pairs > 0) {
        const int k = in.id_pairs;
        for (size_t i = 0; i < npix; ++i) {
            float* p  = &in.ids[size_t(2 * k) * i];
            float sum = 0.0f;
            for (int j = 0; j < k; ++j) {
                float& c = p[2 * j + 1];
                if (!(c > 0.0f) || !std::isfinite(c))
                    c = 0.0f;
                sum += c;
            }
            for (int j = 0; j < k; ++j)
                p[2 * j + 1] = sum > 0.0f ? p[2 * j + 1] / sum : 0.0f;
        }
    }
    return true;
}


void
GuideWeight::centre(int x0, int y0)
{
    m_x0 = float(x0);
    m_y0 = float(y0);
    const size_t i0 = m_in.index(x0, y0);
    m_n0   = m_in.normal.empty() ? nullptr : &m_in.normal[3 * i0];
    m_ids0 = m_in.id_pairs > 0 ? &m_in.ids[size_t(2 * m_in.id_pairs) * i0]
                               : nullptr;
    if (m_in.id_pairs == -1)
        m_id0 = m_in.ids[i0];
    if (m_in.invdepth.empty())
        return;
    m_zeta0 = m_in.invdepth[i0];
    // Minmod of the forward and backward differences to surface neighbours.
    auto diff = [&](int dx, int dy, float& d) {
        const int x = x0 + dx, y = y0 + dy;
        if (!m_in.in_region(x, y))
            return false;
        const size_t j = m_in.index(x, y);
        if (!(m_in.cls[j] & kSurface))
            return false;
        d = (m_in.invdepth[j] - m_zeta0) * float(dx + dy);
        return true;
    };
    auto gradient = [&](int dx, int dy) {
        float f = 0, b = 0;
        const bool hf = diff(dx, dy, f), hb = diff(-dx, -dy, b);
        if (hf && hb)
            return (f > 0) == (b > 0) && f != 0 && b != 0
                       ? (std::fabs(f) < std::fabs(b) ? f : b)
                       : 0.0f;
        return hf ? f : (hb ? b : 0.0f);
    };
    m_gx = gradient(1, 0);
    m_gy = gradient(0, 1);
}


void
GuideWeight::centre_as(const GuideWeight& fine, float x0, float y0,
                       float scale)
{
    m_x0    = x0;
    m_y0    = y0;
    m_n0    = fine.m_n0;
    m_ids0  = fine.m_ids0;
    m_id0   = fine.m_id0;
    m_zeta0 = fine.m_zeta0;
    m_gx    = fine.m_gx * scale;
    m_gy    = fine.m_gy * scale;
}


void
GuideWeight::row(int x, int y, int n, float* g) const
{
    const size_t i = m_in.index(x, y);
    GuideCentre c;
    const bool normals = !m_in.normal.empty();
    for (int k = 0; k < 3; ++k)
        c.n0[k] = normals ? m_n0[k] : 0.0f;
    c.zeta0           = m_zeta0;
    c.gx              = m_gx;
    c.gy              = m_gy;
    c.depth_tolerance = m_depth_tol;
    c.normal_cut      = m_cut;
    std::memcpy(&c.id0, &m_id0, sizeof c.id0);
    c.dx0 = float(x) - m_x0;
    c.dy  = float(y) - m_y0;
    // Absent guides read the zero plane: no normal anywhere gives d = 1.
    const float* zeros = m_in.zeros.data();
    const bool depth   = !m_in.invdepth.empty();
    const bool plain   = m_in.id_pairs == -1;
    guide_row(&m_in.cls[i], normals ? &m_in.normal[3 * i] : zeros,
              depth ? &m_in.invdepth[i] : zeros, plain ? &m_in.ids[i] : zeros,
              g, n, c, depth, plain);
    if (m_power == 4.0f) {
        for (int q = 0; q < n; ++q) {
            const float d2 = g[q] * g[q];
            g[q]           = d2 * d2;
        }
    } else {
        for (int q = 0; q < n; ++q)
            if (g[q] > 0.0f)
                g[q] = std::pow(g[q], m_power);
    }
    if (m_in.id_pairs > 0)
        coverage_row(&m_in.ids[size_t(2 * m_in.id_pairs) * i],
                     m_ids0, g, n,
                     m_in.id_pairs);
}

}  // namespace detail
}  // namespace zdenoise
