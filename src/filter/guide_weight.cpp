// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The guide weight of docs/FILTER.md section 4: decoding the normal and id
// guides, and g(q; p0) for a centre and a row of pixels (the row loop
// itself is the guide kernel, guide_kernel.cpp).

#include "guide_weight.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "guide_kernel.h"

namespace zdenoise {
namespace detail {

void
decode_normals(FilterInputs& in, const ImageBuf& guide)
{
    const size_t npix = in.region.npixels();
    const std::vector<float> xyz = read_channels(guide, in.region, 0, 3);
    for (std::vector<float>& plane : in.normal)
        plane.assign(npix + kPlanePadding, 0.0f);
    for (size_t i = 0; i < npix; ++i) {
        const float* n  = &xyz[3 * i];
        const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len >= 1e-6f) || !std::isfinite(len))
            continue;
        for (int c = 0; c < 3; ++c)
            in.normal[c][i] = n[c] / len;
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
    const std::vector<float> px = read_channels(guide, in.region, 0, nch);
    in.id_pairs = nch == 1 ? -1 : nch / 2;
    in.ids.assign(size_t(nch), std::vector<float>(npix + kPlanePadding, 0.0f));
    for (size_t i = 0; i < npix; ++i) {
        const float* p = &px[size_t(nch) * i];
        if (in.id_pairs < 0) {
            in.ids[0][i] = p[0];
            continue;
        }
        float sum = 0.0f;
        for (int j = 0; j < in.id_pairs; ++j) {
            const float c = p[2 * j + 1];
            sum += c > 0.0f && std::isfinite(c) ? c : 0.0f;
        }
        for (int j = 0; j < in.id_pairs; ++j) {
            const float c = p[2 * j + 1];
            in.ids[size_t(2 * j)][i] = p[2 * j];
            in.ids[size_t(2 * j + 1)][i]
                = sum > 0.0f && c > 0.0f && std::isfinite(c) ? c / sum : 0.0f;
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
    for (int c = 0; c < 3; ++c)
        m_n0[c] = m_in.has_normal() ? m_in.normal[c][i0] : 0.0f;
    for (size_t k = 0; k < m_pairs0.size(); ++k)
        m_pairs0[k] = m_in.ids[k][i0];
    if (m_in.id_pairs == -1)
        m_id0 = m_in.ids[0][i0];
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
    std::copy(fine.m_n0, fine.m_n0 + 3, m_n0);
    m_pairs0 = fine.m_pairs0;
    m_id0   = fine.m_id0;
    m_zeta0 = fine.m_zeta0;
    m_gx    = fine.m_gx * scale;
    m_gy    = fine.m_gy * scale;
}


void
GuideWeight::row(int x, int y, int n, float* g) const
{
    const size_t i = m_in.index(x, y);
    GuideRow r;
    r.cls = &m_in.cls[i];
    if (m_in.has_normal())
        for (int c = 0; c < 3; ++c)
            r.normal[c] = &m_in.normal[c][i];
    if (!m_in.invdepth.empty())
        r.invdepth = &m_in.invdepth[i];
    r.ids      = m_in.ids.data();
    r.first    = i;
    r.id_pairs = m_in.id_pairs;
    r.n        = n;
    std::copy(m_n0, m_n0 + 3, r.n0);
    r.zeta0           = m_zeta0;
    r.gx              = m_gx;
    r.gy              = m_gy;
    r.depth_tolerance = m_depth_tol;
    r.normal_cut      = m_cut;
    std::memcpy(&r.id0, &m_id0, sizeof r.id0);
    r.pairs0 = m_pairs0.data();
    r.dx0    = float(x) - m_x0;
    r.dy     = float(y) - m_y0;
    r.normal_power = m_power;
    r.g            = g;
    guide_row(r);
}

}  // namespace detail
}  // namespace zdenoise
