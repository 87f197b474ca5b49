// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Decoding of the filter's inputs and the noise estimate
// (docs/FILTER.md sections 2-4).

#include "filter_inputs.h"

#include <algorithm>
#include <cmath>

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

    in.z                   = read_channels(quotient, region, 0, 3);
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
                const bool finite = std::isfinite(in.z[3 * i + c]);
                if (!finite)
                    cls |= kNonFinite;
                const bool demod = albedo_demodulated(alb[3 * i + c], eps_a);
                if (surface && demod)
                    cls |= uint8_t(kReceiveR << c);
                all_fit = all_fit && demod
                          && std::fabs(in.z[3 * i + c]) <= kLargestFitQuotient;
            }
            if (all_fit) {
                cls |= kFitPoint;
                const float* zp = &in.z[3 * i];
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
    return true;
}


void
GuideWeight::centre(int x0, int y0)
{
    m_x0 = x0;
    m_y0 = y0;
    m_i0 = m_in.index(x0, y0);
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


float
GuideWeight::operator()(int x, int y) const
{
    const size_t i = m_in.index(x, y);
    float g        = 1.0f;
    if (!m_in.normal.empty()) {
        const float* n  = &m_in.normal[3 * i];
        const float* n0 = &m_in.normal[3 * m_i0];
        const bool z    = no_normal(n), z0 = no_normal(n0);
        if (z != z0)
            return 0.0f;
        if (!z) {
            // Unit vectors, but rounding can put d a hair above 1, which
            // a large normal_power turns into Inf (and the weights NaN).
            const float d = std::min(
                1.0f, n[0] * n0[0] + n[1] * n0[1] + n[2] * n0[2]);
            if (!(d > m_cut))
                return 0.0f;
            if (m_power == 4.0f) {
                const float d2 = d * d;
                g              = d2 * d2;
            } else {
                g = std::pow(d, m_power);
            }
        }
    }
    if (!m_in.invdepth.empty()) {
        const float zhat = m_zeta0 + m_gx * float(x - m_x0)
                           + m_gy * float(y - m_y0);
        if (!(zhat > 0.0f)
            || std::fabs(m_in.invdepth[i] - zhat) > m_depth_tol * zhat)
            return 0.0f;
    }
    if (m_in.id_pairs == -1) {
        if (!same_id(m_in.ids[i], m_in.ids[m_i0]))
            return 0.0f;
    } else if (m_in.id_pairs > 0) {
        const int k     = m_in.id_pairs;
        const float* p  = &m_in.ids[size_t(2 * k) * i];
        const float* p0 = &m_in.ids[size_t(2 * k) * m_i0];
        float overlap = 0.0f, cover = 0.0f, cover0 = 0.0f;
        for (int a = 0; a < k; ++a) {
            cover += p[2 * a + 1];
            cover0 += p0[2 * a + 1];
            if (p[2 * a + 1] <= 0.0f)
                continue;
            for (int b = 0; b < k; ++b)
                if (p0[2 * b + 1] > 0.0f && same_id(p[2 * a], p0[2 * b]))
                    overlap += std::min(p[2 * a + 1], p0[2 * b + 1]);
        }
        if (cover == 0.0f || cover0 == 0.0f)
            overlap = (cover == 0.0f && cover0 == 0.0f) ? 1.0f : 0.0f;
        g *= std::min(overlap, 1.0f);
    }
    return g;
}

}  // namespace detail
}  // namespace zdenoise
