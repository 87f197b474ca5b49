// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// build_pyramid_level(): the fit points averaged 2x2 (docs/FILTER.md 5.1).

#include "pyramid_level.h"

#include <cmath>
#include <cstring>

namespace zdenoise {
namespace detail {

namespace {

/// Do the four pixels carry the same object id data, bit for bit?
bool
same_ids(const FilterInputs& fine, const size_t (&px)[4])
{
    for (const std::vector<float>& plane : fine.ids)
        for (int j = 1; j < 4; ++j)
            if (std::memcmp(&plane[px[0]], &plane[px[j]], sizeof(float)) != 0)
                return false;
    return true;
}

/// The normalised mean of the four pixels' normals (0: none). A block on
/// a crease keeps its mean normal: measured on the public set, leaving
/// such blocks out of the fits loses more than their mixed normal costs.
void
mean_normal(const FilterInputs& fine, const size_t (&px)[4], float (&n)[3])
{
    for (size_t i : px)
        for (int c = 0; c < 3; ++c)
            n[c] += fine.normal[c][i];
    const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int c = 0; c < 3; ++c)
        n[c] = len >= 1e-6f ? n[c] / len : 0.0f;
}

}  // namespace


void
build_pyramid_level(PyramidLevel& level, const FilterInputs& fine,
                    const FilterOptions& opt, int nthreads)
{
    FilterInputs& in = level.in;
    const ROI& fr    = fine.region;
    const int ox = fine.image.xbegin, oy = fine.image.ybegin;
    in.region = ROI(block_of(fr.xbegin - ox), block_of(fr.xend - 1 - ox) + 1,
                    block_of(fr.ybegin - oy), block_of(fr.yend - 1 - oy) + 1);
    in.image         = in.region;
    in.width         = in.region.width();
    in.height        = in.region.height();
    const size_t npix = in.region.npixels() + kPlanePadding;
    in.zl.assign(npix, 0.0f);
    in.cls.assign(npix, 0);
    in.sigma.assign(npix, 0.0f);
    in.vs.assign(npix, 0.0f);
    in.fit_prior.assign(npix, 0.0f);
    for (int c = 0; c < 3; ++c) {
        in.zfit[c].assign(npix, 0.0f);
        in.lfit[c].assign(npix, 0.0f);
    }
    if (fine.has_normal())
        for (std::vector<float>& plane : in.normal)
            plane.assign(npix, 0.0f);
    if (!fine.invdepth.empty())
        in.invdepth.assign(npix, 0.0f);
    in.id_pairs = fine.id_pairs;
    in.ids.assign(fine.ids.size(), std::vector<float>(npix, 0.0f));
    level.zl_sum.assign(npix, 0.0f);
    level.fit_points.assign(npix, 0.0f);

    const float tol = opt.depth_tolerance;
    for_rows(in.region, nthreads, [&](int by) {
        for (int bx = in.region.xbegin; bx < in.region.xend; ++bx) {
            const int x = ox + 2 * bx, y = oy + 2 * by;
            if (!fine.in_region(x, y) || !fine.in_region(x + 1, y + 1))
                continue;
            const size_t px[4] = { fine.index(x, y), fine.index(x + 1, y),
                                   fine.index(x, y + 1),
                                   fine.index(x + 1, y + 1) };
            bool surface = true;
            for (size_t i : px)
                surface = surface && (fine.cls[i] & kSurface);
            if (!surface || !same_ids(fine, px))
                continue;
            float zeta = 0.0f;
            if (!fine.invdepth.empty()) {
                for (size_t i : px)
                    zeta += 0.25f * fine.invdepth[i];
                bool planar = true;
                for (size_t i : px)
                    planar = planar
                             && std::fabs(fine.invdepth[i] - zeta)
                                    <= tol * std::fabs(zeta);
                if (!planar)
                    continue;
            }
            float normal[3] = {};
            if (fine.has_normal())
                mean_normal(fine, px, normal);
            double P = 0.0, P2v = 0.0, P2s = 0.0, zl = 0.0, zsum = 0.0;
            double z[3] = {}, l[3] = {};
            int points = 0;
            for (size_t i : px) {
                if (!(fine.cls[i] & kFitPoint))
                    continue;
                ++points;
                zsum += fine.zl[i];
                const double p = fine.fit_prior[i];
                P += p;
                P2v += p * p * fine.vs[i];
                P2s += p * p * double(fine.sigma[i]) * fine.sigma[i];
                zl += p * fine.zl[i];
                for (int c = 0; c < 3; ++c) {
                    z[c] += p * fine.zfit[c][i];
                    l[c] += p * fine.lfit[c][i];
                }
            }
            const size_t b = in.index(bx, by);
            in.cls[b]      = kSurface;
            if (!in.invdepth.empty())
                in.invdepth[b] = zeta;
            if (in.has_normal())
                for (int c = 0; c < 3; ++c)
                    in.normal[c][b] = normal[c];
            for (size_t k = 0; k < in.ids.size(); ++k)
                in.ids[k][b] = fine.ids[k][px[0]];
            level.zl_sum[b]     = float(zsum);
            level.fit_points[b] = float(points);
            if (!(P > 0.0))
                continue;
            in.cls[b] |= kFitPoint;
            in.fit_prior[b] = float(P);
            in.zl[b]        = float(zl / P);
            in.vs[b]        = float(P2v / (P * P));
            in.sigma[b]     = float(std::sqrt(P2s) / P);
            for (int c = 0; c < 3; ++c) {
                in.zfit[c][b] = float(z[c] / P);
                in.lfit[c][b] = float(l[c] / P);
            }
        }
    });
}

}  // namespace detail
}  // namespace zdenoise
