// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// regression_filter(): the adaptive-radius five-plane regression with
// splatting (docs/FILTER.md sections 5-8).

#include <zdenoise/zdenoise.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <mutex>

#include <OpenImageIO/imagebufalgo_util.h>

#include "filter_inputs.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;
using namespace detail;

namespace {

constexpr double kEps       = 1e-8;
constexpr float kValueClamp = 30.0f;
constexpr double kMaxWm     = 1e6;

/// exp(-t) for t in [0, kValueClamp] (NaN gives 1), branch-free so that it
/// vectorises: Cephes' expf reduction and polynomial, relative error within
/// 2e-7 like libm's expf.
[[gnu::always_inline]] inline float
exp_neg(float t)
{
    t              = t > 0.0f ? (t < kValueClamp ? t : kValueClamp) : 0.0f;
    const float x  = -t;
    // round(x log2(e)) by the 1.5 * 2^23 trick (no SSE4.1 round needed)
    const float fn = (x * 1.44269504088896341f + 12582912.0f) - 12582912.0f;
    const float r  = (x - fn * 0.693359375f) - fn * -2.12194440e-4f;
    float p        = 1.9875691500e-4f;
    p              = p * r + 1.3981999507e-3f;
    p              = p * r + 8.3334519073e-3f;
    p              = p * r + 4.1665795894e-2f;
    p              = p * r + 1.6666665459e-1f;
    p              = p * r + 5.0000001201e-1f;
    const float e  = p * (r * r) + r + 1.0f;
    const uint32_t bits = uint32_t(int(fn) + 127) << 23;  // 2^fn, fn in [-44, 0]
    float scale;
    std::memcpy(&scale, &bits, sizeof scale);
    return e * scale;
}

/// The sums of one cell of a window's fit (section 5), kLanes partial sums
/// each, in pixel offsets dx, dy from the centre (window coordinates u =
/// dx/R, v = dy/R are applied once, in double, by FitMoments::add).
struct CellLanes {
    enum Sum {
        W, Wx, Wy, Wxx, Wxy, Wyy,  ///< w {1, dx, dy, dx^2, dx dy, dy^2}
        Z0, Z0x, Z0y, Z1, Z1x, Z1y, Z2, Z2x, Z2y,  ///< w z_c {1, dx, dy}
        N, Nx, Ny, Nxx, Nxy, Nyy,  ///< w^2 Vs {1, dx, dy, ...}
        S2,                        ///< w^2 sigma^2
        Count,                     ///< good points
        kSums
    };
    float lane[kSums][kLanes];
};

/// One row segment of a window for the fit: pointers at its first point.
struct FitRow {
    int n;              ///< points in the segment
    float dx0, dy;      ///< offset of the first point
    float ey;           ///< e(dy)
    float mean;         ///< <z>
    float value_scale;  ///< value_k / max(|<z>|, eps)
};

/// Add the points of one row segment to a cell, kLanes at a time; store
/// each point's value factor exp(-vt) in `values` (whole blocks: the
/// buffers are padded, and a store past the segment lands where a later
/// segment writes or nobody reads).
ZDENOISE_ROW_KERNEL void
fit_row(const float* __restrict fit_weight, const float* __restrict spatial,
        const float* __restrict zl, const float* __restrict z0,
        const float* __restrict z1, const float* __restrict z2,
        const float* __restrict vs, const float* __restrict sigma,
        float* __restrict values, CellLanes* __restrict cell,
        const FitRow& in)
{
    using S = CellLanes;
    const float dy = in.dy, ey = in.ey, mean = in.mean;
    const float value_scale = in.value_scale;
    const int n = in.n;
    for (int j = 0; j < n; j += kLanes) {
        for (int l = 0; l < kLanes; ++l) {
            // Every load unconditional, selects instead of branches: the
            // lanes vectorise.
            const int q       = j + l;
            const float fw    = fit_weight[q];
            const float sp    = spatial[q];
            const float vsq   = vs[q];
            const float sgq   = sigma[q];
            const float value = exp_neg(value_scale * std::fabs(zl[q] - mean));
            values[q]         = value;
            const bool use    = q < n && fw > 0.0f;
            const float w   = use ? fw * sp * ey * value : 0.0f;
            const float w2v = w * w * (use ? vsq : 0.0f);
            const float sg  = use ? sgq : 0.0f;
            const float dx  = in.dx0 + float(q);
            const float wx = w * dx, wy = w * dy;
            S& c = *cell;
            c.lane[S::W][l] += w;
            c.lane[S::Wx][l] += wx;
            c.lane[S::Wy][l] += wy;
            c.lane[S::Wxx][l] += wx * dx;
            c.lane[S::Wxy][l] += wx * dy;
            c.lane[S::Wyy][l] += wy * dy;
            const float zc[3] = { z0[q], z1[q], z2[q] };
#pragma GCC unroll 3
            for (int ch = 0; ch < 3; ++ch) {
                c.lane[S::Z0 + 3 * ch][l] += w * zc[ch];
                c.lane[S::Z0x + 3 * ch][l] += wx * zc[ch];
                c.lane[S::Z0y + 3 * ch][l] += wy * zc[ch];
            }
            const float nx = w2v * dx, ny = w2v * dy;
            c.lane[S::N][l] += w2v;
            c.lane[S::Nx][l] += nx;
            c.lane[S::Ny][l] += ny;
            c.lane[S::Nxx][l] += nx * dx;
            c.lane[S::Nxy][l] += nx * dy;
            c.lane[S::Nyy][l] += ny * dy;
            c.lane[S::S2][l] += w * w * sg * sg;
            c.lane[S::Count][l] += use ? 1.0f : 0.0f;
        }
    }
}

/// A solved plane's coefficients as floats, for the splat kernel.
struct PlaneCoeffs {
    float c[3] = {}, a[3] = {}, b[3] = {};
};

/// One row segment of a window's splat, all of it in one quadrant:
/// pointers at its first point.
struct SplatRow {
    const uint32_t* cls;
    const float* g;           ///< cached guide weights
    const float* spatial;     ///< e(dx)
    const float* fit_weight;  ///< cached; > 0 where `values` holds exp(-vt)
    const float* values;
    const float* zl;
    int n;
    float dx0, ey, inv_r, v;  ///< dx of the first point, e(dy), 1/R, dy/R
    float mean, value_scale;  ///< for exp(-vt) where the fit did not keep it
    PlaneCoeffs whole, quadrant;  ///< quadrant = whole where it has none
    float* s;     ///< receives each point's weight (0: receives nothing)
    float* a[3];  ///< receives weight times the blended plane value A
};

/// The splat weights and values of section 7 for one segment; kPower8 when
/// quadrant_power is 8 (the default: r^8 by multiplication vectorises,
/// std::pow does not).
// The pointers of a SplatRow again, as __restrict parameters: GCC gives up
// vectorising when it must check at run time that more than ten of them do
// not overlap, and only parameters carry restrict reliably.
#define ZDENOISE_SPLAT_POINTERS                                               \
    const uint32_t *__restrict cls, const float *__restrict gw,                \
        const float *__restrict fitw, const float *__restrict values,          \
        const float *__restrict spat, const float *__restrict zl,              \
        float *__restrict out_s, float *__restrict a0, float *__restrict a1,   \
        float *__restrict a2
#define ZDENOISE_SPLAT_ARGS(in)                                                \
    in.cls, in.g, in.fit_weight, in.values, in.spatial, in.zl, in.s, in.a[0], \
        in.a[1], in.a[2]

template<bool kPower8>
[[gnu::always_inline]] inline void
splat_lanes(ZDENOISE_SPLAT_POINTERS, const SplatRow& in, float power)
{
    float* const out_a[3] = { a0, a1, a2 };
    const PlaneCoeffs P = in.whole, Q = in.quadrant;
    const float ey = in.ey, inv_r = in.inv_r, v = in.v, dx0 = in.dx0;
    const float mean = in.mean, value_scale = in.value_scale;
    const int n = in.n;
    // Whole blocks of kLanes points (the inputs and outputs are padded):
    // segments are short, and a plain loop would spend most of its time in
    // its scalar remainder. No sums across points, so any vector width
    // computes every point alike.
    for (int j = 0; j < n; j += kLanes) {
        for (int l = 0; l < kLanes; ++l) {
            const int q       = j + l;
            const uint32_t cl = cls[q];
            const float g    = gw[q];
            const float fw   = fitw[q];
            const float kept = values[q];
            const float sp   = spat[q];
            // Receiving implies a surface (section 2). One bit test per
            // condition: GCC 12 vectorises no bitwise and of two of them.
            const bool use = (cl & kReceiveAny) && g > 0.0f;
            const bool fit = (cl & kFitPoint) != 0;
            const float fresh = exp_neg(value_scale * std::fabs(zl[q] - mean));
            const float value = fit ? (fw > 0.0f ? kept : fresh) : 1.0f;
            const float s = use ? g * sp * ey * value : 0.0f;
            const float u = (dx0 + float(q)) * inv_r;
#pragma GCC unroll 3
            for (int ch = 0; ch < 3; ++ch) {
                const float Z  = P.c[ch] + P.a[ch] * u + P.b[ch] * v;
                const float Zm = Q.c[ch] + Q.a[ch] * u + Q.b[ch] * v;
                // r = max(a/b, b/a) with one division
                const float a = std::fabs(Z) + float(kEps);
                const float b = std::fabs(Zm) + float(kEps);
                const float r = std::max(a, b) / std::min(a, b);
                float wm;
                if (kPower8) {
                    const float r2 = r * r, r4 = r2 * r2;
                    wm = r4 * r4;
                } else {
                    wm = std::pow(r, power);
                }
                wm = std::min(wm, float(kMaxWm));
                const bool opposite = (Z < 0.0f && Zm > 0.0f)
                                      || (Z > 0.0f && Zm < 0.0f);
                wm = opposite ? float(kMaxWm) : wm;
                // Without a quadrant plane Q is the whole one: Zm = Z, wm = 1
                // and A = (Z + Z) / 2 = Z exactly.
                out_a[ch][q] = s * ((Z + wm * Zm) / (1.0f + wm));
            }
            out_s[q] = s;
        }
    }
}

ZDENOISE_ROW_KERNEL void
splat_row_power8(ZDENOISE_SPLAT_POINTERS, const SplatRow& in)
{
    splat_lanes<true>(cls, gw, fitw, values, spat, zl, out_s, a0, a1, a2, in,
                      8.0f);
}

void
splat_row(ZDENOISE_SPLAT_POINTERS, const SplatRow& in, float power)
{
    splat_lanes<false>(cls, gw, fitw, values, spat, zl, out_s, a0, a1, a2, in,
                       power);
}

/// The splat of one row segment, by the kernel that fits quadrant_power.
void
splat_row(const SplatRow& in, float power)
{
    if (power == 8.0f)
        splat_row_power8(ZDENOISE_SPLAT_ARGS(in), in);
    else
        splat_row(ZDENOISE_SPLAT_ARGS(in), in, power);
}
#undef ZDENOISE_SPLAT_POINTERS
#undef ZDENOISE_SPLAT_ARGS

/// Weighted moments of one least-squares plane fit, in window coordinates
/// u = dx/R, v = dy/R.
struct FitMoments {
    double s[6] = {};     ///< sum w {1, u, v, uu, uv, vv}
    double t[3][3] = {};  ///< per channel: sum w z {1, u, v}
    double n[6] = {};     ///< sum w^2 Vs {1, u, v, uu, uv, vv}
    int count = 0;

    /// Set from a cell's lane sums (in pixel offsets) for radius R; also
    /// returns the cell's sum of w^2 sigma^2. The lanes are added as a
    /// fixed tree (l + l+4, then + l+2, then + l+1), which vectorises.
    double set(const CellLanes& c, int R)
    {
        using S = CellLanes;
        static_assert(kLanes == 8, "the tree below adds eight lanes");
        float half[S::kSums][4], quarter[S::kSums][2];
        for (int k = 0; k < S::kSums; ++k)
            for (int l = 0; l < 4; ++l)
                half[k][l] = c.lane[k][l] + c.lane[k][l + 4];
        for (int k = 0; k < S::kSums; ++k)
            for (int l = 0; l < 2; ++l)
                quarter[k][l] = half[k][l] + half[k][l + 2];
        double sum[S::kSums];
        for (int k = 0; k < S::kSums; ++k)
            sum[k] = double(quarter[k][0] + quarter[k][1]);
        const double i1 = 1.0 / R, i2 = i1 * i1;
        const double scale[6] = { 1.0, i1, i1, i2, i2, i2 };
        for (int k = 0; k < 6; ++k) {
            s[k] = sum[S::W + k] * scale[k];
            n[k] = sum[S::N + k] * scale[k];
        }
        for (int ch = 0; ch < 3; ++ch)
            for (int k = 0; k < 3; ++k)
                t[ch][k] = sum[S::Z0 + 3 * ch + k] * scale[k];
        count = int(sum[S::Count]);
        return sum[S::S2];
    }

    FitMoments& operator+=(const FitMoments& o)
    {
        for (int k = 0; k < 6; ++k) {
            s[k] += o.s[k];
            n[k] += o.n[k];
        }
        for (int ch = 0; ch < 3; ++ch)
            for (int k = 0; k < 3; ++k)
                t[ch][k] += o.t[ch][k];
        count += o.count;
        return *this;
    }
};

/// A solved plane per channel, Z_c = c + a u + b v.
struct Plane {
    bool present = false;
    double c[3] = {}, a[3] = {}, b[3] = {};
    double var0 = 0.0;  ///< predicted variance of the luminance at p0

    double at(int ch, double u, double v) const
    {
        return c[ch] + a[ch] * u + b[ch] * v;
    }
    double luminance0() const
    {
        return kLumaWeights[0] * c[0] + kLumaWeights[1] * c[1]
               + kLumaWeights[2] * c[2];
    }
};

Plane
solve(const FitMoments& m)
{
    Plane p;
    const double* s = m.s;
    if (!(s[0] > 0.0))
        return p;
    p.present = true;
    // Cofactors of the symmetric normal matrix [[s0 s1 s2][s1 s3 s4][s2 s4 s5]].
    const double c00 = s[3] * s[5] - s[4] * s[4];
    const double c01 = s[2] * s[4] - s[1] * s[5];
    const double c02 = s[1] * s[4] - s[2] * s[3];
    const double c11 = s[0] * s[5] - s[2] * s[2];
    const double c12 = s[1] * s[2] - s[0] * s[4];
    const double c22 = s[0] * s[3] - s[1] * s[1];
    const double det = s[0] * c00 + s[1] * c01 + s[2] * c02;
    if (m.count < 3 || !(det > 1e-6 * s[0] * s[0] * s[0])) {
        for (int ch = 0; ch < 3; ++ch)
            p.c[ch] = m.t[ch][0] / s[0];
        p.var0 = m.n[0] / (s[0] * s[0]);
        return p;
    }
    const double inv[3][3] = { { c00 / det, c01 / det, c02 / det },
                               { c01 / det, c11 / det, c12 / det },
                               { c02 / det, c12 / det, c22 / det } };
    for (int ch = 0; ch < 3; ++ch) {
        const double* t = m.t[ch];
        p.c[ch] = inv[0][0] * t[0] + inv[0][1] * t[1] + inv[0][2] * t[2];
        p.a[ch] = inv[1][0] * t[0] + inv[1][1] * t[1] + inv[1][2] * t[2];
        p.b[ch] = inv[2][0] * t[0] + inv[2][1] * t[1] + inv[2][2] * t[2];
    }
    // Sandwich variance of the value at p0: r^T N r with r = M^-1 e0.
    const double r[3] = { inv[0][0], inv[1][0], inv[2][0] };
    const double* n   = m.n;
    p.var0 = r[0] * (n[0] * r[0] + n[1] * r[1] + n[2] * r[2])
             + r[1] * (n[1] * r[0] + n[3] * r[1] + n[4] * r[2])
             + r[2] * (n[2] * r[0] + n[4] * r[1] + n[5] * r[2]);
    return p;
}


/// The five planes of one window and what the splat needs of it.
struct WindowFit {
    int radius  = 0;
    int values  = 0;     ///< which WindowFitter::m_value holds its exp(-vt)
    float mean  = 0.0f;  ///< <z>: mean luminance of the window's points
    double eta  = 0.0;   ///< predicted relative noise at the centre
    Plane whole;
    Plane quadrant[4];
};

enum class StopReason { Quality, Size, Edge };

/// Statistics of one block of centres, summed in block order so that totals do not
/// depend on the thread count.
struct BlockStats {
    int64_t windows = 0, stop_quality = 0, stop_size = 0, stop_edge = 0;
    int64_t radius_sum = 0;
};


/// Grows, fits and splats the windows of the centres of a range of rows.
/// One per block of centres: holds the per-centre scratch (guide weights of the
/// window) so that nothing is allocated per pixel.
class WindowFitter {
public:
    WindowFitter(const FilterInputs& in, const FilterOptions& opt,
                 const ROI& out, std::vector<double>& acc,
                 std::vector<double>& wsum)
        : m_in(in)
        , m_opt(opt)
        , m_out(out)
        , m_acc(acc)
        , m_wsum(wsum)
        , m_guide(in, opt)
        , m_side(2 * opt.r_max + 1)
        , m_g(cache_size(), 0.0f)
        , m_fit_weight(cache_size(), 0.0f)
        , m_value { std::vector<float>(cache_size(), 0.0f),
                    std::vector<float>(cache_size(), 0.0f) }
        , m_spatial_row(size_t(m_side) + kLanes, 0.0f)
        , m_cells(9)
        , m_splat_s(size_t(m_side) + kLanes, 0.0f)
        , m_splat_a { std::vector<float>(size_t(m_side) + kLanes, 0.0f),
                      std::vector<float>(size_t(m_side) + kLanes, 0.0f),
                      std::vector<float>(size_t(m_side) + kLanes, 0.0f) }
    {
    }

    /// Fit the window of fit point (x0, y0) and splat it (unless
    /// splat_window is false: a strided lattice point of the next block,
    /// fitted only for its stop reason).
    StopReason process(int x0, int y0, int& radius, bool splat_window = true);

    /// The radius tried after R: R + 1, or R * radius_growth (at least
    /// R + 1), never beyond r_max.
    int next_radius(int R) const
    {
        const int grown = int(float(R) * m_opt.radius_growth);
        return std::min(std::max(R + 1, grown), m_opt.r_max);
    }

private:
    /// The caches hold the largest window and kLanes of padding (the row
    /// kernels read whole blocks of lanes).
    size_t cache_size() const { return size_t(m_side) * m_side + kLanes; }
    size_t cache_index(int dx, int dy) const
    {
        return size_t(dy + m_opt.r_max) * m_side + (dx + m_opt.r_max);
    }
    float& g_at(int dx, int dy) { return m_g[cache_index(dx, dy)]; }
    /// Fill m_spatial_row for radius R: exp(-d^2/R^2) at index d + R.
    void set_spatial(int R)
    {
        for (int d = 0; d <= R; ++d)
            m_spatial_row[size_t(R + d)] = m_spatial_row[size_t(R - d)]
                = std::exp(-float(d * d) / float(R * R));
    }
    /// The value term's exponent is value_scale(<z>) |zl - <z>| (clamped
    /// in exp_neg so that weights never underflow).
    float value_scale(float mean) const
    {
        return m_opt.value_k / std::max(std::fabs(mean), float(kEps));
    }
    // noinline: the three stages stay separate in profiles
    // (docs/PERFORMANCE.md); a call per window or radius costs nothing.
    /// Extend the cached guide weights and point sums to radius R.
    [[gnu::noinline]] void grow_to(int R);
    /// Fit at radius R, keeping the value factors in m_value[values].
    [[gnu::noinline]] WindowFit fit(int R, int values);
    bool edge_fires(const WindowFit& w) const;
    [[gnu::noinline]] void splat(const WindowFit& w);

    const FilterInputs& m_in;
    const FilterOptions& m_opt;
    const ROI& m_out;
    std::vector<double>& m_acc;
    std::vector<double>& m_wsum;
    GuideWeight m_guide;
    int m_side;
    std::vector<float> m_g;  ///< g(q; p0) over the grown window
    /// g(q; p0) exp(-sigma(q)) for good fit points, 0 for the others: the
    /// part of the fit weight that does not change with R.
    std::vector<float> m_fit_weight;
    /// exp(-vt(q)) of the good points at the last two radii fitted (the
    /// splat of the final fit reuses them; an edge steps back one fit).
    std::vector<float> m_value[2];
    /// exp(-d^2/R^2) at d + R, d = -R..R (and kLanes of padding)
    std::vector<float> m_spatial_row;
    /// The lane sums of the nine cells of a fit.
    std::vector<CellLanes> m_cells;
    /// The splat kernel's output for one row segment (and kLanes padding).
    std::vector<float> m_splat_s, m_splat_a[3];
    int m_x0 = 0, m_y0 = 0, m_grown = -1;
    double m_zsum = 0.0;  ///< sum of zl over fit points with g > 0
    int m_zcount  = 0;
};


void
WindowFitter::grow_to(int R)
{
    if (R <= m_grown)
        return;
    const ROI& img = m_in.image;
    const int ya   = std::max(m_y0 - R, img.ybegin);
    const int yb   = std::min(m_y0 + R, img.yend - 1);
    // The square of radius R less the square already grown, a row segment
    // or two at a time, clipped to the image.
    auto add = [&](int y, int xa, int xb) {
        xa = std::max(xa, img.xbegin);
        xb = std::min(xb, img.xend - 1);
        if (xb < xa)
            return;
        const int dy   = y - m_y0;
        const size_t i = m_in.index(xa, y);
        const size_t c = cache_index(xa - m_x0, dy);
        const int n    = xb - xa + 1;
        float* g       = &m_g[c];
        m_guide.row(xa, y, n, g);
        // Locals: the sums must not go through memory at every point.
        double zsum = m_zsum;
        int zcount  = m_zcount;
        float* fit_weight = &m_fit_weight[c];
        for (int q = 0; q < n; ++q) {
            const size_t iq = i + size_t(q);
            float fw        = 0.0f;
            if (g[q] > 0.0f && (m_in.cls[iq] & kFitPoint)) {
                zsum += m_in.zl[iq];
                ++zcount;
                fw = g[q] * m_in.fit_prior[iq];
            }
            fit_weight[q] = fw;
        }
        m_zsum   = zsum;
        m_zcount = zcount;
    };
    for (int y = ya; y <= yb; ++y) {
        if (std::abs(y - m_y0) > m_grown) {
            add(y, m_x0 - R, m_x0 + R);
        } else {
            add(y, m_x0 - R, m_x0 - m_grown - 1);
            add(y, m_x0 + m_grown + 1, m_x0 + R);
        }
    }
    m_grown = R;
}


WindowFit
WindowFitter::fit(int R, int value_buffer)
{
    WindowFit wf;
    wf.radius = R;
    wf.values = value_buffer;
    float* values = m_value[value_buffer].data();
    wf.mean   = float(m_zsum / m_zcount);
    set_spatial(R);
    const ROI& img = m_in.image;
    const int ya   = std::max(m_y0 - R, img.ybegin);
    const int yb   = std::min(m_y0 + R, img.yend - 1);
    const int xa   = std::max(m_x0 - R, img.xbegin);
    const int xb   = std::min(m_x0 + R, img.xend - 1);

    // Nine disjoint cells, each point added once: open quadrants 0-3,
    // half-axes 4 (+y), 5 (-x), 6 (-y), 7 (+x), and the centre 8. The closed
    // quadrants and the whole window are sums of cells.
    CellLanes* cells = m_cells.data();
    std::memset(static_cast<void*>(cells), 0, 9 * sizeof(CellLanes));
    FitRow row;
    row.mean        = wf.mean;
    row.value_scale = value_scale(wf.mean);
    for (int y = ya; y <= yb; ++y) {
        const int dy = y - m_y0;
        row.dy       = float(dy);
        row.ey       = m_spatial_row[size_t(dy + R)];
        const int segments[3][3] = {
            { xa, m_x0 - 1, dy > 0 ? 1 : (dy < 0 ? 2 : 5) },
            { m_x0, m_x0, dy > 0 ? 4 : (dy < 0 ? 6 : 8) },
            { m_x0 + 1, xb, dy > 0 ? 0 : (dy < 0 ? 3 : 7) },
        };
        for (const auto& seg : segments) {
            if (seg[1] < seg[0])
                continue;
            const size_t i = m_in.index(seg[0], y);
            const size_t c = cache_index(seg[0] - m_x0, dy);
            row.n          = seg[1] - seg[0] + 1;
            row.dx0        = float(seg[0] - m_x0);
            fit_row(&m_fit_weight[c], &m_spatial_row[size_t(seg[0] - m_x0 + R)],
                    &m_in.zl[i], &m_in.zfit[0][i], &m_in.zfit[1][i],
                    &m_in.zfit[2][i], &m_in.vs[i], &m_in.sigma[i], values + c,
                    &cells[seg[2]], row);
        }
    }
    FitMoments cell[9];
    double w2s2 = 0.0;
    for (int k = 0; k < 9; ++k)
        w2s2 += cell[k].set(cells[k], R);
    static const int kQuadrantCells[4][4] = {
        { 0, 4, 7, 8 }, { 1, 4, 5, 8 }, { 2, 5, 6, 8 }, { 3, 6, 7, 8 }
    };
    FitMoments whole;
    for (const FitMoments& m : cell)
        whole += m;
    wf.whole = solve(whole);
    for (int q = 0; q < 4; ++q) {
        FitMoments quad;
        for (int k : kQuadrantCells[q])
            quad += cell[k];
        wf.quadrant[q] = solve(quad);
    }
    wf.eta = wf.whole.present ? std::sqrt(w2s2) / whole.s[0]
                              : std::numeric_limits<double>::infinity();
    return wf;
}


bool
WindowFitter::edge_fires(const WindowFit& w) const
{
    if (!w.whole.present)
        return false;
    const double zl  = w.whole.luminance0();
    const double azl = std::max(std::fabs(zl), kEps);
    for (const Plane& q : w.quadrant) {
        if (!q.present)
            continue;
        const double eta_m = std::sqrt(std::max(q.var0, 0.0)) / azl;
        const double tau   = std::max(double(m_opt.edge_k) * eta_m,
                                      double(m_opt.tau_min));
        if (std::fabs(zl - q.luminance0()) / azl > tau)
            return true;
    }
    return false;
}


void
WindowFitter::splat(const WindowFit& w)
{
    const int R = w.radius;
    set_spatial(R);
    auto coeffs = [](const Plane& p) {
        PlaneCoeffs k;
        for (int ch = 0; ch < 3; ++ch) {
            k.c[ch] = float(p.c[ch]);
            k.a[ch] = float(p.a[ch]);
            k.b[ch] = float(p.b[ch]);
        }
        return k;
    };
    const PlaneCoeffs whole = coeffs(w.whole);
    PlaneCoeffs quadrant[4];
    for (int q = 0; q < 4; ++q)
        quadrant[q] = w.quadrant[q].present ? coeffs(w.quadrant[q]) : whole;
    SplatRow row;
    row.values      = m_value[w.values].data();
    row.inv_r       = 1.0f / float(R);
    row.mean        = w.mean;
    row.value_scale = value_scale(w.mean);
    row.whole       = whole;
    row.s           = m_splat_s.data();
    for (int ch = 0; ch < 3; ++ch)
        row.a[ch] = m_splat_a[ch].data();
    const float* values = row.values;
    // Only output pixels receive.
    const int ya = std::max(m_y0 - R, m_out.ybegin);
    const int yb = std::min(m_y0 + R, m_out.yend - 1);
    const int xa = std::max(m_x0 - R, m_out.xbegin);
    const int xb = std::min(m_x0 + R, m_out.xend - 1);
    const size_t out_w = size_t(m_out.width());
    for (int y = ya; y <= yb; ++y) {
        const int dy = y - m_y0;
        row.v        = float(dy) * row.inv_r;
        row.ey       = m_spatial_row[size_t(dy + R)];
        // The row's two halves, each in one quadrant (dx < 0, dx >= 0).
        const int halves[2][3] = { { xa, std::min(xb, m_x0 - 1), dy >= 0 ? 1 : 2 },
                                   { std::max(xa, m_x0), xb, dy >= 0 ? 0 : 3 } };
        for (const auto& half : halves) {
            const int x0 = half[0], x1 = half[1];
            if (x1 < x0)
                continue;
            const size_t i = m_in.index(x0, y);
            const size_t c = cache_index(x0 - m_x0, dy);
            row.cls          = &m_in.cls[i];
            row.g            = &m_g[c];
            row.spatial      = &m_spatial_row[size_t(x0 - m_x0 + R)];
            row.fit_weight   = &m_fit_weight[c];
            row.values       = values + c;
            row.zl           = &m_in.zl[i];
            row.n            = x1 - x0 + 1;
            row.dx0          = float(x0 - m_x0);
            row.quadrant     = quadrant[half[2]];
            splat_row(row, m_opt.quadrant_power);
            size_t o = size_t(y - m_out.ybegin) * out_w
                       + size_t(x0 - m_out.xbegin);
            for (int q = 0; q < row.n; ++q, ++o) {
                const float sw = m_splat_s[size_t(q)];
                if (!(sw > 0.0f))
                    continue;
                double* acc = &m_acc[3 * o];
                for (int ch = 0; ch < 3; ++ch)
                    acc[ch] += double(m_splat_a[ch][size_t(q)]);
                m_wsum[o] += double(sw);
            }
        }
    }
}


StopReason
WindowFitter::process(int x0, int y0, int& radius, bool splat_window)
{
    m_x0    = x0;
    m_y0    = y0;
    m_grown = -1;
    m_zsum  = 0.0;
    m_zcount = 0;
    m_guide.centre(x0, y0);

    WindowFit previous, current;
    StopReason reason = StopReason::Size;
    int fits = 0;
    for (int R = m_opt.r_min;; R = next_radius(R)) {
        grow_to(R);
        current = fit(R, fits++ & 1);
        if (edge_fires(current)) {
            reason = StopReason::Edge;
            if (R > m_opt.r_min)
                current = previous;
            break;
        }
        if (current.eta <= m_opt.eta_target) {
            reason = StopReason::Quality;
            break;
        }
        if (R >= m_opt.r_max) {
            reason = StopReason::Size;
            break;
        }
        previous = current;
    }
    radius = current.radius;
    if (current.whole.present && splat_window)
        splat(current);
    return reason;
}


bool
check_options(ImageBuf& dst, const FilterOptions& o)
{
    auto bad = [&](const char* name, double value, const char* need) {
        dst.errorfmt("regression_filter: option {} = {} is invalid: {}", name,
                     value, need);
        return false;
    };
    if (o.r_min < 1)
        return bad("r_min", o.r_min, "needs >= 1");
    if (o.r_max < o.r_min || o.r_max > 256)
        return bad("r_max", o.r_max, "needs r_min <= r_max <= 256");
    auto finite_nonneg = [](float v) { return std::isfinite(v) && v >= 0.0f; };
    if (!finite_nonneg(o.eta_target))
        return bad("eta_target", o.eta_target, "needs a finite number >= 0");
    if (!finite_nonneg(o.edge_k))
        return bad("edge_k", o.edge_k, "needs a finite number >= 0");
    if (!finite_nonneg(o.tau_min))
        return bad("tau_min", o.tau_min, "needs a finite number >= 0");
    if (!finite_nonneg(o.value_k))
        return bad("value_k", o.value_k, "needs a finite number >= 0");
    if (!(o.sigma_good >= 0.0f))
        return bad("sigma_good", o.sigma_good, "needs a number >= 0");
    if (!(o.albedo_eps > 0.0f) || !std::isfinite(o.albedo_eps))
        return bad("albedo_eps", o.albedo_eps, "needs a finite number > 0");
    if (!finite_nonneg(o.depth_tolerance))
        return bad("depth_tolerance", o.depth_tolerance,
                   "needs a finite number >= 0");
    if (!(o.normal_cut >= -1.0f && o.normal_cut < 1.0f))
        return bad("normal_cut", o.normal_cut, "needs -1 <= normal_cut < 1");
    if (!(o.normal_power > 0.0f) || !std::isfinite(o.normal_power))
        return bad("normal_power", o.normal_power, "needs a finite number > 0");
    if (!(o.radius_growth >= 1.0f && o.radius_growth <= 4.0f))
        return bad("radius_growth", o.radius_growth, "needs 1 <= radius_growth <= 4");
    if (o.centre_stride < 1 || o.centre_stride > 64)
        return bad("centre_stride", o.centre_stride,
                   "needs 1 <= centre_stride <= 64");
    if (o.stride_edges != 0 && o.stride_edges != 1)
        return bad("stride_edges", o.stride_edges, "needs 0 or 1");
    if (!finite_nonneg(o.quadrant_power))
        return bad("quadrant_power", o.quadrant_power,
                   "needs a finite number >= 0");
    return true;
}



/// The stride the filter uses: centre_stride, at most r_min + 1 so that the
/// smallest windows of neighbouring lattice points still overlap (r_min 1
/// with the default stride 3 means stride 2, not an error).
int
effective_stride(const FilterOptions& o)
{
    return std::max(1, std::min(o.centre_stride, std::max(o.r_min, 1) + 1));
}


/// Totals over the tiles of one call.
struct FilterTotals {
    BlockStats windows;
    int64_t pixels = 0, passthrough = 0, nonfinite = 0;
};

/// Filter the output pixels `roi` (docs/FILTER.md sections 2-7), reading
/// the inputs over roi plus the halo everything depends on. `opt.frame` is
/// the image's data window.
bool
filter_tile(ImageBuf& dst, const ImageBuf& quotient, const ImageBuf& albedo,
            const Guides& guides, const FilterOptions& opt, ROI roi,
            int nthreads, FilterTotals& totals)
{
    const char* opname = "regression_filter";
    const ROI image    = opt.frame;
    const ROI region   = halo_region(roi, image, filter_halo(opt));

    FilterInputs in;
    if (!decode_filter_inputs(in, dst, quotient, albedo, guides, opt, region,
                              nthreads))
        return false;

    const size_t npix_out = size_t(roi.width()) * size_t(roi.height());
    std::vector<double> acc(3 * npix_out, 0.0), wsum(npix_out, 0.0);

    // Centres: fit points within r_max of the output.
    const int cy0 = std::max(image.ybegin, roi.ybegin - opt.r_max);
    const int cy1 = std::min(image.yend, roi.yend + opt.r_max);
    const int cx0 = std::max(image.xbegin, roi.xbegin - opt.r_max);
    const int cx1 = std::min(image.xend, roi.xend + opt.r_max);
    // Blocks of centres anchored at the data window's origin, at least
    // 2 r_max + 1 pixels on a side, in four phases by the parity of their
    // row and column: the splat footprints of the blocks of one phase never
    // overlap, so they run in parallel without locks, and every pixel
    // receives its contributions in a fixed order (phase, then centres in
    // row order within the one block of each phase that reaches it).
    // Blocks, not whole strips of rows, so that a phase has enough of them
    // to keep every thread busy to its end (section 8).
    // With a stride, multiples of it.
    const int stride  = effective_stride(opt);
    const int block_h = (std::max(2 * opt.r_max + 1, 32) + stride - 1) / stride * stride;
    const int block_w = (std::max(2 * opt.r_max + 1, 64) + stride - 1) / stride * stride;
    const int first_row = (cy0 - image.ybegin) / block_h;
    const int first_col = (cx0 - image.xbegin) / block_w;
    const int nrows = cy1 > cy0 ? (cy1 - 1 - image.ybegin) / block_h - first_row + 1
                                : 0;
    const int ncols = cx1 > cx0 ? (cx1 - 1 - image.xbegin) / block_w - first_col + 1
                                : 0;
    const int nblocks = nrows * ncols;
    std::vector<BlockStats> block_stats(static_cast<size_t>(nblocks));
    std::atomic<int64_t> blocks_done { 0 };
    std::mutex progress_mutex;

    auto run_block = [&](int b) {
        const int br = first_row + b / ncols, bc = first_col + b % ncols;
        const int ya = std::max(cy0, image.ybegin + br * block_h);
        const int yb = std::min(cy1, image.ybegin + (br + 1) * block_h);
        const int xa = std::max(cx0, image.xbegin + bc * block_w);
        const int xb = std::min(cx1, image.xbegin + (bc + 1) * block_w);
        const int by_end = image.ybegin + (br + 1) * block_h;
        const int bx_end = image.xbegin + (bc + 1) * block_w;
        WindowFitter fitter(in, opt, roi, acc, wsum);
        BlockStats& st = block_stats[size_t(b)];
        auto centre = [&](int x, int y, bool splat_window = true) {
            int radius        = 0;
            StopReason reason = fitter.process(x, y, radius, splat_window);
            if (splat_window && roi.contains(x, y)) {
                ++st.windows;
                st.radius_sum += radius;
                st.stop_quality += reason == StopReason::Quality;
                st.stop_size += reason == StopReason::Size;
                st.stop_edge += reason == StopReason::Edge;
            }
            return reason;
        };
        if (stride == 1) {
            for (int y = ya; y < yb; ++y)
                for (int x = xa; x < xb; ++x)
                    if (in.cls[in.index(x, y)] & kFitPoint)
                        centre(x, y);
        } else {
            // Strided centres (section 8): first the lattice points of the
            // block, then every other fit point that the lattice windows
            // of its cell cannot speak for: none of them is on its surface,
            // or (stride_edges) one on its surface stopped at an edge. The
            // block's sides are multiples of the stride, so the lattice
            // points of its cells are its own plus the first column and row
            // of the next blocks, which are fitted here only to decide (the
            // next blocks splat them). The decision is thus the same for any
            // tile, strip or thread count.
            const int lxa = xa - (xa - image.xbegin) % stride;
            const int lya = ya - (ya - image.ybegin) % stride;
            auto lattice_end = [&](int last, int origin, int image_end) {
                const int up = last + (stride - (last - origin) % stride) % stride;
                return std::min(up + 1, image_end);
            };
            const int lxb = lattice_end(xb - 1, image.xbegin, image.xend);
            const int lyb = lattice_end(yb - 1, image.ybegin, image.yend);
            const int nlx = (lxb - 1 - lxa) / stride + 1;
            const int nly = (lyb - 1 - lya) / stride + 1;
            enum LatticeWindow : uint8_t { kNone, kSmooth, kEdge };
            std::vector<uint8_t> lattice(size_t(nlx) * size_t(nly), kNone);
            for (int j = 0; j < nly; ++j)
                for (int i = 0; i < nlx; ++i) {
                    const int x = lxa + i * stride, y = lya + j * stride;
                    if (in.cls[in.index(x, y)] & kFitPoint) {
                        const bool own = x < bx_end && y < by_end;
                        lattice[size_t(j) * nlx + i]
                            = centre(x, y, own) == StopReason::Edge && opt.stride_edges
                                  ? kEdge
                                  : kSmooth;
                    }
                }
            GuideWeight lattice_guide(in, opt);
            for (int y = ya; y < yb; ++y) {
                for (int x = xa; x < xb; ++x) {
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
                    if (edge || !covered)
                        centre(x, y);
                }
            }
        }
        const int64_t done = ++blocks_done;
        if (opt.progress) {
            std::lock_guard<std::mutex> lock(progress_mutex);
            opt.progress(float(done) / float(nblocks));
        }
    };
    for (int phase = 0; phase < 4; ++phase) {
        std::vector<int> blocks;
        for (int b = 0; b < nblocks; ++b) {
            const int br = first_row + b / ncols, bc = first_col + b % ncols;
            if ((br % 2) * 2 + bc % 2 == phase)
                blocks.push_back(b);
        }
        parallel_for(int64_t(0), int64_t(blocks.size()),
                     [&](int64_t j) { run_block(blocks[size_t(j)]); },
                     paropt(nthreads, paropt::SplitDir::Y, 1));
    }

    // Output (section 7): RGB from acc/wsum, pass-through, or 0; other
    // channels copied.
    ROI all_ch = roi;
    all_ch.chbegin = 0;
    all_ch.chend   = quotient.nchannels();
    const int nch  = all_ch.nchannels();
    std::vector<float> out(npix_out * size_t(nch));
    quotient.get_pixels(all_ch, TypeFloat, out.data());
    std::atomic<int64_t> passthrough { 0 }, nonfinite { 0 };
    parallel_for(int64_t(roi.ybegin), int64_t(roi.yend), [&](int64_t y) {
        int64_t pt = 0, nf = 0;
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t i   = in.index(x, int(y));
            const size_t o   = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            const uint8_t cl = in.cls[i];
            bool passed      = false;
            for (int ch = 0; ch < 3; ++ch) {
                float& v = out[o * nch + ch];
                if ((cl & (kReceiveR << ch)) && wsum[o] > 0.0) {
                    v = float(acc[3 * o + ch] / wsum[o]);
                } else {
                    passed = true;
                    if (!std::isfinite(v))
                        v = 0.0f;
                }
            }
            pt += passed;
            nf += (cl & kNonFinite) != 0;
        }
        passthrough += pt;
        nonfinite += nf;
    }, paropt(nthreads));
    if (!dst.set_pixels(all_ch, TypeFloat, out.data())) {
        if (!dst.has_error())
            dst.errorfmt("{}: could not store the result", opname);
        return false;
    }

    for (const BlockStats& s : block_stats) {
        totals.windows.windows += s.windows;
        totals.windows.stop_quality += s.stop_quality;
        totals.windows.stop_size += s.stop_size;
        totals.windows.stop_edge += s.stop_edge;
        totals.windows.radius_sum += s.radius_sum;
    }
    totals.pixels += int64_t(npix_out);
    totals.passthrough += passthrough;
    totals.nonfinite += nonfinite;
    return true;
}

}  // namespace


int
filter_halo(const FilterOptions& options)
{
    // Everything an output pixel depends on lies within 2*r_max (centres up
    // to r_max away, their windows r_max further) plus the noise estimate's
    // footprint (3x3 residual, 5x5 median, 3x3 smoothing) of 4. With a
    // stride, the lattice points deciding a centre lie up to stride - 1
    // further.
    return 2 * std::max(options.r_max, 0) + 4
           + effective_stride(options) - 1;
}


bool
regression_filter(ImageBuf& dst, const ImageBuf& quotient,
                  const ImageBuf& albedo, const Guides& guides,
                  const FilterOptions& options, FilterStats* stats, ROI roi,
                  int nthreads)
{
    const char* opname = "regression_filter";
    if (!prepare_dst(dst, quotient, roi, opname)
        || !check_input(dst, quotient, opname, "quotient", roi, 3)
        || !check_options(dst, options))
        return false;
    // The inputs must hold what the output depends on: with the frame given,
    // roi and its halo; else their data windows are the frame.
    FilterOptions tile_opt = options;
    if (!tile_opt.frame.defined())
        tile_opt.frame = quotient.roi();
    if (!check_frame(dst, opname, roi, tile_opt.frame))
        return false;
    const ROI need = options.frame.defined()
                         ? halo_region(roi, options.frame, filter_halo(options))
                         : quotient.roi();
    if (!check_input(dst, quotient, opname, "quotient", need, 3)
        || !check_input(dst, albedo, opname, "albedo", need, 3))
        return false;
    struct NamedGuide {
        const ImageBuf* buf;
        const char* name;
        int minchannels;
    } named[] = { { guides.normal, "normal guide", 3 },
                  { guides.depth, "depth guide", 1 },
                  { guides.object_id, "object id guide", 1 },
                  { guides.variance, "variance guide", 1 },
                  { guides.half_a, "half buffer A", 3 },
                  { guides.half_b, "half buffer B", 3 } };
    for (const NamedGuide& g : named)
        if (g.buf
            && !check_input(dst, *g.buf, opname, g.name, need,
                            g.minchannels))
            return false;
    if (!guides.variance && (!guides.half_a != !guides.half_b)) {
        dst.errorfmt("{}: half buffers need both A and B", opname);
        return false;
    }

    // Tiles bound the working memory (about 100 bytes per pixel of a tile
    // and its halo) whatever the frame size; the result is exactly the
    // whole-image one (section 8), so the tile size is not a parameter.
    constexpr int kTile = 1024;
    const int ntx = (roi.width() + kTile - 1) / kTile;
    const int nty = (roi.height() + kTile - 1) / kTile;
    const int ntiles = ntx * nty;
    FilterTotals totals;
    for (int t = 0; t < ntiles; ++t) {
        ROI tile(roi.xbegin + (t % ntx) * kTile, 0, roi.ybegin + (t / ntx) * kTile, 0,
                 roi.zbegin, roi.zend, roi.chbegin, roi.chend);
        tile.xend = std::min(tile.xbegin + kTile, roi.xend);
        tile.yend = std::min(tile.ybegin + kTile, roi.yend);
        if (options.progress)
            tile_opt.progress = [&](float f) {
                options.progress((float(t) + f) / float(ntiles));
            };
        if (!filter_tile(dst, quotient, albedo, guides, tile_opt, tile,
                         nthreads, totals))
            return false;
    }
    if (stats) {
        FilterStats st;
        st.windows            = totals.windows.windows;
        st.stop_quality       = totals.windows.stop_quality;
        st.stop_size          = totals.windows.stop_size;
        st.stop_edge          = totals.windows.stop_edge;
        st.radius_sum         = totals.windows.radius_sum;
        st.mean_radius        = st.windows ? double(st.radius_sum) / st.windows
                                           : 0.0;
        st.pixels             = totals.pixels;
        st.passthrough_pixels = totals.passthrough;
        st.nonfinite_pixels   = totals.nonfinite;
        *stats                = st;
    }
    return true;
}


ImageBuf
regression_filter(const ImageBuf& quotient, const ImageBuf& albedo,
                  const Guides& guides, const FilterOptions& options,
                  FilterStats* stats, ROI roi, int nthreads)
{
    ImageBuf result;
    if (!regression_filter(result, quotient, albedo, guides, options, stats,
                           roi, nthreads)
        && !result.has_error())
        result.errorfmt("regression_filter error");
    return result;
}

}  // namespace zdenoise
