// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Decoding of the filter's inputs and the noise estimate
// (docs/FILTER.md sections 2-4).

#include "filter_inputs.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <OpenImageIO/imagebufalgo_util.h>

#include "internal.h"

namespace zdenoise {
namespace detail {

using namespace OIIO;

namespace {

constexpr float kEps = 1e-8f;
// Median of the chi-square distribution with one degree of freedom: turns
// the median of squared residuals into a variance.
constexpr float kChi2Median = 0.4549364f;

/// Channels [chbegin, chend) of `img` over `region` as floats.
std::vector<float>
read_channels(const ImageBuf& img, ROI region, int chbegin, int chend)
{
    region.chbegin = chbegin;
    region.chend   = chend;
    std::vector<float> px(region.npixels() * size_t(chend - chbegin));
    img.get_pixels(region, TypeFloat, px.data());
    return px;
}

/// Run `row(y)` for every row of the region, in parallel.
template<class F>
void
for_rows(const ROI& region, int nthreads, F&& row)
{
    parallel_for(int64_t(region.ybegin), int64_t(region.yend),
                 [&](int64_t y) { row(int(y)); }, paropt(nthreads));
}

/// Are two pixels on the same surface for the noise estimate: same (plain
/// or primary Cryptomatte) id, and close normals when normals are given.
bool
same_surface(const FilterInputs& in, size_t a, size_t b)
{
    if (!in.normal.empty()) {
        const float* na = &in.normal[3 * a];
        const float* nb = &in.normal[3 * b];
        const bool za = no_normal(na), zb = no_normal(nb);
        if (za != zb)
            return false;
        if (!za && na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2] <= 0.9f)
            return false;
    }
    if (in.id_pairs == -1)
        return same_id(in.ids[a], in.ids[b]);
    if (in.id_pairs > 0) {
        // Primary id: the rank of largest coverage (the first of equals).
        auto primary = [&](size_t i, float& id) {
            const float* p = &in.ids[size_t(2 * in.id_pairs) * i];
            float best     = 0.0f;
            bool any       = false;
            for (int k = 0; k < in.id_pairs; ++k)
                if (p[2 * k + 1] > best) {
                    best = p[2 * k + 1];
                    id   = p[2 * k];
                    any  = true;
                }
            return any;
        };
        float ida = 0, idb = 0;
        const bool ha = primary(a, ida), hb = primary(b, idb);
        if (ha != hb || (ha && !same_id(ida, idb)))
            return false;
    }
    return true;
}

}  // namespace


bool
decode_filter_inputs(FilterInputs& in, ImageBuf& dst, const ImageBuf& quotient,
                     const ImageBuf& albedo, const Guides& guides,
                     const FilterOptions& opt, ROI region, int nthreads)
{
    const char* opname = "regression_filter";
    in.region          = region;
    in.image           = opt.frame;  // regression_filter() always sets it
    in.width           = region.width();
    in.height          = region.height();
    const size_t npix  = region.npixels();

    // The RGB quotient, 3 per pixel: kept as zfit for the fit points.
    const std::vector<float> z = read_channels(quotient, region, 0, 3);
    std::vector<float> alb = read_channels(albedo, region, 0, 3);
    std::vector<float> alpha;
    const int alpha_ch = quotient.spec().alpha_channel;
    if (alpha_ch >= 3)
        alpha = read_channels(quotient, region, alpha_ch, alpha_ch + 1);
    std::vector<float> depth;
    if (guides.depth)
        depth = read_channels(*guides.depth, region, 0, 1);

    // Guides.
    if (guides.normal) {
        in.normal = read_channels(*guides.normal, region, 0, 3);
        for (size_t i = 0; i < npix; ++i) {
            float* n = &in.normal[3 * i];
            float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (!(len >= 1e-6f) || !std::isfinite(len))
                n[0] = n[1] = n[2] = 0.0f;
            else
                n[0] /= len, n[1] /= len, n[2] /= len;
        }
    }
    if (guides.object_id) {
        const int nch = guides.object_id->nchannels();
        if (nch != 1 && nch % 2 != 0) {
            dst.errorfmt("{}: the object id guide has {} channels; it needs "
                         "1 (a plain id) or an even number ((id, coverage) "
                         "pairs)",
                         opname, nch);
            return false;
        }
        in.ids      = read_channels(*guides.object_id, region, 0, nch);
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
    }

    // Pixel classes, inverse depth and luminance.
    in.cls.assign(npix, 0);
    in.zl.assign(npix, 0.0f);
    if (guides.depth)
        in.invdepth.assign(npix, 0.0f);
    const float eps_a = opt.albedo_eps;
    for_rows(region, nthreads, [&](int y) {
        for (size_t i = in.index(region.xbegin, y), e = i + in.width; i < e;
             ++i) {
            bool surface = alpha.empty() || alpha[i] > 0.0f;
            if (!depth.empty()) {
                const float d = depth[i];
                surface       = surface && std::isfinite(d) && d > 0.0f
                          && d < 1e9f;
                if (surface)
                    in.invdepth[i] = 1.0f / d;
            }
            uint8_t cls  = surface ? kSurface : 0;
            bool all_fit = surface;
            for (int c = 0; c < 3; ++c) {
                const bool finite = std::isfinite(z[3 * i + c]);
                if (!finite)
                    cls |= kNonFinite;
                const bool demod = albedo_demodulated(alb[3 * i + c], eps_a);
                if (surface && demod)
                    cls |= uint8_t(kReceiveR << c);
                all_fit = all_fit && demod
                          && std::fabs(z[3 * i + c]) <= kLargestFitQuotient;
            }
            if (all_fit) {
                cls |= kFitPoint;
                const float* zp = &z[3 * i];
                in.zl[i] = kLumaWeights[0] * zp[0] + kLumaWeights[1] * zp[1]
                           + kLumaWeights[2] * zp[2];
            }
            in.cls[i] = cls;
        }
    });

    // Raw variance V of zl at fit points; NaN = undefined.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<float> var(npix, nan);
    auto fit = [&](size_t i) { return (in.cls[i] & kFitPoint) != 0; };
    auto quotient_variance = [&](size_t i, const float* varL, int stride) {
        // Luminance-weighted mean of the per-channel quotient variances.
        float v = 0.0f;
        for (int c = 0; c < 3; ++c) {
            const float vl = varL[stride == 1 ? 0 : c];
            const float a  = alb[3 * i + c] + eps_a;
            v += kLumaWeights[c] * vl / (a * a);
        }
        return (std::isfinite(v) && v >= 0.0f) ? v : nan;
    };
    if (guides.variance) {
        const int nch = guides.variance->nchannels() >= 3 ? 3 : 1;
        std::vector<float> vl = read_channels(*guides.variance, region, 0, nch);
        for (size_t i = 0; i < npix; ++i)
            if (fit(i))
                var[i] = quotient_variance(i, &vl[size_t(nch) * i], nch);
    } else if (guides.half_a && guides.half_b) {
        std::vector<float> a = read_channels(*guides.half_a, region, 0, 3);
        std::vector<float> b = read_channels(*guides.half_b, region, 0, 3);
        for (size_t i = 0; i < npix; ++i) {
            if (!fit(i))
                continue;
            float vl[3];
            for (int c = 0; c < 3; ++c) {
                const float d = a[3 * i + c] - b[3 * i + c];
                vl[c]         = 0.25f * d * d;
            }
            var[i] = quotient_variance(i, vl, 3);
        }
    } else {
        // Estimated from z: squared residuals against the 8-neighbour mean
        // on the same surface, then a robust (median) 5x5 estimate.
        std::vector<float> resid(npix, nan);
        for_rows(region, nthreads, [&](int y) {
            for (int x = region.xbegin; x < region.xend; ++x) {
                const size_t i = in.index(x, y);
                if (!fit(i))
                    continue;
                double sum = 0.0;
                int n      = 0;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        if ((dx | dy) == 0 || !in.in_region(x + dx, y + dy))
                            continue;
                        const size_t j = in.index(x + dx, y + dy);
                        if (fit(j) && same_surface(in, i, j)) {
                            sum += in.zl[j];
                            ++n;
                        }
                    }
                if (n > 0) {
                    const double r = in.zl[i] - sum / n;
                    resid[i]       = float(r * r * n / (n + 1));
                }
            }
        });
        for_rows(region, nthreads, [&](int y) {
            float window[25];
            for (int x = region.xbegin; x < region.xend; ++x) {
                const size_t i = in.index(x, y);
                if (!fit(i))
                    continue;
                int n = 0;
                for (int dy = -2; dy <= 2; ++dy)
                    for (int dx = -2; dx <= 2; ++dx)
                        if (in.in_region(x + dx, y + dy)) {
                            const float e = resid[in.index(x + dx, y + dy)];
                            if (!std::isnan(e))
                                window[n++] = e;
                        }
                if (n == 0) {
                    var[i] = 0.0f;
                    continue;
                }
                // Median; for an even count, the mean of the middle two.
                std::sort(window, window + n);
                const float med = (n & 1) ? window[n / 2]
                                          : 0.5f
                                                * (window[n / 2 - 1]
                                                   + window[n / 2]);
                var[i] = med / kChi2Median;
            }
        });
    }

    // 3x3 smoothing of variance and value, and the relative noise sigma.
    in.vs.assign(npix, 0.0f);
    in.sigma.assign(npix, 0.0f);
    for_rows(region, nthreads, [&](int y) {
        for (int x = region.xbegin; x < region.xend; ++x) {
            const size_t i = in.index(x, y);
            if (!fit(i))
                continue;
            double vsum = 0.0, zsum = 0.0;
            int nv = 0, nz = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    if (!in.in_region(x + dx, y + dy))
                        continue;
                    const size_t j = in.index(x + dx, y + dy);
                    if (!fit(j))
                        continue;
                    zsum += in.zl[j];
                    ++nz;
                    if (!std::isnan(var[j])) {
                        vsum += var[j];
                        ++nv;
                    }
                }
            const float vs = nv ? float(vsum / nv) : 0.0f;
            const float zs = float(zsum / nz);
            in.vs[i]       = vs;
            in.sigma[i]    = std::sqrt(vs) / std::max(std::fabs(zs), kEps);
        }
    });

    // The fit's planes, padded for the row kernels (kPlanePadding).
    for (int c = 0; c < 3; ++c)
        in.zfit[c].assign(npix + kPlanePadding, 0.0f);
    in.fit_prior.assign(npix + kPlanePadding, 0.0f);
    for_rows(region, nthreads, [&](int y) {
        for (size_t i = in.index(region.xbegin, y), e = i + in.width; i < e;
             ++i) {
            if (!fit(i))
                continue;
            for (int c = 0; c < 3; ++c)
                in.zfit[c][i] = z[3 * i + c];
            if (in.sigma[i] <= opt.sigma_good)
                in.fit_prior[i] = std::exp(-in.sigma[i]);
        }
    });
    in.zl.resize(npix + kPlanePadding, 0.0f);
    in.vs.resize(npix + kPlanePadding, 0.0f);
    in.sigma.resize(npix + kPlanePadding, 0.0f);
    in.cls.resize(npix + kPlanePadding, 0);
    in.zeros.assign(3 * (size_t(in.width) + kPlanePadding), 0.0f);
    return true;
}


void
GuideWeight::centre(int x0, int y0)
{
    m_x0 = x0;
    m_y0 = y0;
    m_i0 = m_in.index(x0, y0);
    if (m_in.id_pairs == -1)
        m_id0 = m_in.ids[m_i0];
    if (m_in.invdepth.empty())
        return;
    m_zeta0 = m_in.invdepth[m_i0];
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


namespace {

/// What the guide weight of a row needs of its centre.
struct GuideCentre {
    float n0[3];           ///< the centre's normal (0: none)
    float zeta0, gx, gy;   ///< its inverse depth and the plane's slopes
    float depth_tolerance;
    float normal_cut;
    uint32_t id0;          ///< its plain id's bits
    float dx0, dy;         ///< offset of the row's first pixel
};

/// g of section 4 for n pixels, before the normal power and Cryptomatte
/// coverage: d (the normals' cosine, 1 where neither has one) where every
/// test passes, else 0. Each test is its own select: GCC 12 vectorises
/// these, not a conjunction of them.
template<bool kDepth, bool kPlainId>
[[gnu::always_inline]] inline void
guide_lanes(const uint32_t* __restrict cls, const float* __restrict normal,
            const float* __restrict invdepth, const float* __restrict ids,
            float* __restrict g, int n, const GuideCentre& c)
{
    // A decoded normal is a unit vector or all zero (none).
    const bool none0 = c.n0[0] * c.n0[0] + c.n0[1] * c.n0[1]
                           + c.n0[2] * c.n0[2]
                       == 0.0f;
    for (int q = 0; q < n; ++q) {
        const float nx = normal[3 * q], ny = normal[3 * q + 1],
                    nz = normal[3 * q + 2];
        const bool none = nx * nx + ny * ny + nz * nz == 0.0f;
        // Unit vectors, but rounding can put d a hair above 1, which a
        // large normal_power turns into Inf.
        const float d = std::min(1.0f, nx * c.n0[0] + ny * c.n0[1]
                                           + nz * c.n0[2]);
        const float with_normal = d > c.normal_cut ? d : 0.0f;
        float w = none0 ? (none ? 1.0f : 0.0f) : (none ? 0.0f : with_normal);
        if (kDepth) {
            const float zhat = c.zeta0 + c.gx * (c.dx0 + float(q))
                               + c.gy * c.dy;
            w = zhat > 0.0f ? w : 0.0f;
            w = std::fabs(invdepth[q] - zhat) <= c.depth_tolerance * zhat
                    ? w
                    : 0.0f;
        }
        if (kPlainId) {
            uint32_t id;
            std::memcpy(&id, &ids[q], sizeof id);
            w = id == c.id0 ? w : 0.0f;
        }
        g[q] = (cls[q] & kSurface) ? w : 0.0f;
    }
}

ZDENOISE_ROW_KERNEL void
guide_row(const uint32_t* __restrict cls, const float* __restrict normal,
          const float* __restrict invdepth, const float* __restrict ids,
          float* __restrict g, int n, const GuideCentre& c, bool depth,
          bool plain_id)
{
    if (depth && plain_id)
        guide_lanes<true, true>(cls, normal, invdepth, ids, g, n, c);
    else if (depth)
        guide_lanes<true, false>(cls, normal, invdepth, ids, g, n, c);
    else if (plain_id)
        guide_lanes<false, true>(cls, normal, invdepth, ids, g, n, c);
    else
        guide_lanes<false, false>(cls, normal, invdepth, ids, g, n, c);
}

/// Multiply g by the Cryptomatte overlap of each pixel with the centre p0:
/// the sum over equal ids of the smaller normalised coverage, at most 1 (1
/// where neither has coverage, 0 where one has none). Coverages are >= 0,
/// so a rank without coverage adds min(c, 0) = 0 and needs no test. K > 0
/// is k known when compiling (its loops unroll and the pixels vectorise).
template<int K>
[[gnu::always_inline]] inline void
coverage_lanes(const float* __restrict ids, const float* __restrict p0,
               float* __restrict g, int n, int k)
{
    static_assert(K <= 4, "the centre's ranks are held in registers");
    const int kk = K > 0 ? K : k;
    uint32_t id0[4] = {};
    float c0[4]     = {};
    float cover0    = 0.0f;
    for (int b = 0; b < kk; ++b) {
        if (K > 0) {
            std::memcpy(&id0[b], &p0[2 * b], sizeof(uint32_t));
            c0[b] = p0[2 * b + 1];
        }
        cover0 += p0[2 * b + 1];
    }
    // The centre's rank b (from p0 itself when k is not known).
    auto centre_id = [&](int b) {
        uint32_t id = id0[K > 0 ? b : 0];
        if (K == 0)
            std::memcpy(&id, &p0[2 * b], sizeof id);
        return id;
    };
    auto centre_cover = [&](int b) {
        return K > 0 ? c0[b] : p0[2 * b + 1];
    };
    for (int q = 0; q < n; ++q) {
        const float* p = &ids[size_t(2 * kk) * size_t(q)];
        float overlap = 0.0f, cover = 0.0f;
        for (int a = 0; a < kk; ++a) {
            const float ca = p[2 * a + 1];
            uint32_t ida;
            std::memcpy(&ida, &p[2 * a], sizeof ida);
            cover += ca;
            for (int b = 0; b < kk; ++b)
                overlap += ida == centre_id(b) ? std::min(ca, centre_cover(b))
                                               : 0.0f;
        }
        const float none = cover == 0.0f ? 1.0f : 0.0f;
        overlap = cover0 == 0.0f ? none : (cover == 0.0f ? 0.0f : overlap);
        g[q] *= std::min(overlap, 1.0f);
    }
}

ZDENOISE_ROW_KERNEL void
coverage_row(const float* __restrict ids, const float* __restrict p0,
             float* __restrict g, int n, int k)
{
    switch (k) {
    case 1: coverage_lanes<1>(ids, p0, g, n, k); break;
    case 2: coverage_lanes<2>(ids, p0, g, n, k); break;
    case 3: coverage_lanes<3>(ids, p0, g, n, k); break;
    default: coverage_lanes<0>(ids, p0, g, n, k); break;
    }
}

}  // namespace


void
GuideWeight::row(int x, int y, int n, float* g) const
{
    const size_t i = m_in.index(x, y);
    GuideCentre c;
    const bool normals = !m_in.normal.empty();
    for (int k = 0; k < 3; ++k)
        c.n0[k] = normals ? m_in.normal[3 * m_i0 + size_t(k)] : 0.0f;
    c.zeta0           = m_zeta0;
    c.gx              = m_gx;
    c.gy              = m_gy;
    c.depth_tolerance = m_depth_tol;
    c.normal_cut      = m_cut;
    std::memcpy(&c.id0, &m_id0, sizeof c.id0);
    c.dx0 = float(x - m_x0);
    c.dy  = float(y - m_y0);
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
                     &m_in.ids[size_t(2 * m_in.id_pairs) * m_i0], g, n,
                     m_in.id_pairs);
}

}  // namespace detail
}  // namespace zdenoise
