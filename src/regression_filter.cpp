// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// regression_filter(): the adaptive-radius five-plane regression with
// splatting (docs/FILTER.md sections 5-8).

#include <zdenoise/zdenoise.h>

#include <algorithm>
#include <atomic>
#include <cmath>
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

/// Sums over the points of one row segment of a window, in powers of dx.
struct RowSums {
    double w[3]     = {};  ///< sum w {1, dx, dx^2}
    double wz[3][2] = {};  ///< per channel: sum w z {1, dx}
    double w2v[3]   = {};  ///< sum w^2 Vs {1, dx, dx^2}
    int count       = 0;
};

/// Weighted moments of one least-squares plane fit, in window coordinates
/// u = dx/R, v = dy/R.
struct FitMoments {
    double s[6] = {};     ///< sum w {1, u, v, uu, uv, vv}
    double t[3][3] = {};  ///< per channel: sum w z {1, u, v}
    double n[6] = {};     ///< sum w^2 Vs {1, u, v, uu, uv, vv}
    int count = 0;

    /// Add the points of one row segment, given its sums over the points
    /// in powers of dx (v = dy/R is the same for all of them, so the
    /// moments in v follow from these: 13 sums per point instead of 22).
    void add_row(const RowSums& r, double inv_r, double v)
    {
        const double i2 = inv_r * inv_r;
        s[0] += r.w[0];
        s[1] += r.w[1] * inv_r;
        s[2] += r.w[0] * v;
        s[3] += r.w[2] * i2;
        s[4] += r.w[1] * inv_r * v;
        s[5] += r.w[0] * v * v;
        for (int ch = 0; ch < 3; ++ch) {
            t[ch][0] += r.wz[ch][0];
            t[ch][1] += r.wz[ch][1] * inv_r;
            t[ch][2] += r.wz[ch][0] * v;
        }
        n[0] += r.w2v[0];
        n[1] += r.w2v[1] * inv_r;
        n[2] += r.w2v[0] * v;
        n[3] += r.w2v[2] * i2;
        n[4] += r.w2v[1] * inv_r * v;
        n[5] += r.w2v[0] * v * v;
        count += r.count;
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

/// Statistics of one strip, summed in strip order so that totals do not
/// depend on the thread count.
struct StripStats {
    int64_t windows = 0, stop_quality = 0, stop_size = 0, stop_edge = 0;
    int64_t radius_sum = 0;
};


/// Grows, fits and splats the windows of the centres of a range of rows.
/// One per strip: holds the per-centre scratch (guide weights of the
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
        , m_g(size_t(m_side) * m_side, 0.0f)
        , m_fit_weight(size_t(m_side) * m_side, 0.0f)
        , m_value { std::vector<float>(size_t(m_side) * m_side, 0.0f),
                    std::vector<float>(size_t(m_side) * m_side, 0.0f) }
        , m_spatial(size_t(opt.r_max) + 1, 0.0f)
    {
    }

    /// Fit and splat the window of fit point (x0, y0).
    StopReason process(int x0, int y0, int& radius);

    /// The radius tried after R: R + 1, or R * radius_growth (at least
    /// R + 1), never beyond r_max.
    int next_radius(int R) const
    {
        const int grown = int(float(R) * m_opt.radius_growth);
        return std::min(std::max(R + 1, grown), m_opt.r_max);
    }

private:
    size_t cache_index(int dx, int dy) const
    {
        return size_t(dy + m_opt.r_max) * m_side + (dx + m_opt.r_max);
    }
    float& g_at(int dx, int dy) { return m_g[cache_index(dx, dy)]; }
    /// Fill m_spatial for radius R: exp(-(dx^2+dy^2)/R^2) = e(dx) e(dy).
    void set_spatial(int R)
    {
        m_spatial.resize(size_t(R) + 1);
        for (int d = 0; d <= R; ++d)
            m_spatial[size_t(d)] = std::exp(-float(d * d) / float(R * R));
    }
    /// The value term's exponent k |zl - <z>| / |<z>|, clamped so that
    /// weights never underflow.
    float value_exponent(float zl, float mean) const
    {
        const float am = std::max(std::fabs(mean), float(kEps));
        return std::min(m_opt.value_k * std::fabs(zl - mean) / am,
                        kValueClamp);
    }
    /// Add the good points of row y, columns [xa, xb], to `m`.
    /// `values` receives the value factor exp(-vt) of each good point.
    void accumulate(FitMoments& m, int R, int y, int xa, int xb, float mean,
                    double& w2s2, float* values) const;
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
    std::vector<float> m_spatial;  ///< exp(-d^2/R^2), d = 0..R
    int m_x0 = 0, m_y0 = 0, m_grown = -1;
    double m_zsum = 0.0;  ///< sum of zl over fit points with g > 0
    int m_zcount  = 0;
};


void
WindowFitter::grow_to(int R)
{
    const ROI& img = m_in.image;
    for (int r = m_grown + 1; r <= R; ++r) {
        // The ring at Chebyshev distance r, clipped to the image.
        const int ya = std::max(m_y0 - r, img.ybegin);
        const int yb = std::min(m_y0 + r, img.yend - 1);
        for (int y = ya; y <= yb; ++y) {
            const bool edge_row = (y == m_y0 - r || y == m_y0 + r);
            const int step      = edge_row ? 1 : 2 * r;
            for (int x = m_x0 - r; x <= m_x0 + r; x += std::max(step, 1)) {
                if (x < img.xbegin || x >= img.xend)
                    continue;
                const size_t i = m_in.index(x, y);
                const uint8_t cls = m_in.cls[i];
                float g = 0.0f;
                if (cls & kSurface)
                    g = m_guide(x, y);
                const size_t c = cache_index(x - m_x0, y - m_y0);
                m_g[c]          = g;
                m_fit_weight[c] = 0.0f;
                if (g > 0.0f && (cls & kFitPoint)) {
                    m_zsum += m_in.zl[i];
                    ++m_zcount;
                    const float sigma = m_in.sigma[i];
                    if (sigma <= m_opt.sigma_good)
                        m_fit_weight[c] = g * std::exp(-sigma);
                }
            }
        }
    }
    m_grown = std::max(m_grown, R);
}


void
WindowFitter::accumulate(FitMoments& m, int R, int y, int xa, int xb,
                         float mean, double& w2s2, float* values) const
{
    if (xb < xa)
        return;
    const int dy   = y - m_y0;
    const float ey = m_spatial[size_t(std::abs(dy))];
    size_t i       = m_in.index(xa, y);
    size_t c       = cache_index(xa - m_x0, dy);
    RowSums r;
    for (int x = xa; x <= xb; ++x, ++i, ++c) {
        const float fw = m_fit_weight[c];
        if (!(fw > 0.0f))
            continue;
        const double dx    = x - m_x0;
        const float value  = std::exp(-value_exponent(m_in.zl[i], mean));
        values[c]          = value;
        const double w     = fw * m_spatial[size_t(std::abs(x - m_x0))] * ey
                             * value;
        const double wdx   = w * dx;
        const double sigma = m_in.sigma[i];
        const float* z     = &m_in.z[3 * i];
        const double w2v   = w * w * double(m_in.vs[i]);
        r.w[0] += w;
        r.w[1] += wdx;
        r.w[2] += wdx * dx;
        for (int ch = 0; ch < 3; ++ch) {
            r.wz[ch][0] += w * z[ch];
            r.wz[ch][1] += wdx * z[ch];
        }
        r.w2v[0] += w2v;
        r.w2v[1] += w2v * dx;
        r.w2v[2] += w2v * dx * dx;
        w2s2 += w * w * sigma * sigma;
        ++r.count;
    }
    m.add_row(r, 1.0 / R, double(dy) / R);
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
    FitMoments cell[9];
    double w2s2 = 0.0;
    for (int y = ya; y <= yb; ++y) {
        const int dy = y - m_y0;
        const int left  = dy > 0 ? 1 : (dy < 0 ? 2 : 5);
        const int mid   = dy > 0 ? 4 : (dy < 0 ? 6 : 8);
        const int right = dy > 0 ? 0 : (dy < 0 ? 3 : 7);
        accumulate(cell[left], R, y, xa, m_x0 - 1, wf.mean, w2s2, values);
        accumulate(cell[mid], R, y, m_x0, m_x0, wf.mean, w2s2, values);
        accumulate(cell[right], R, y, m_x0 + 1, xb, wf.mean, w2s2, values);
    }
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
    const int R        = w.radius;
    const double inv_r = 1.0 / R;
    const float power  = m_opt.quadrant_power;
    const float* values = m_value[w.values].data();
    set_spatial(R);
    // Only output pixels receive.
    const int ya = std::max(m_y0 - R, m_out.ybegin);
    const int yb = std::min(m_y0 + R, m_out.yend - 1);
    const int xa = std::max(m_x0 - R, m_out.xbegin);
    const int xb = std::min(m_x0 + R, m_out.xend - 1);
    const size_t out_w = size_t(m_out.width());
    for (int y = ya; y <= yb; ++y) {
        const int dy   = y - m_y0;
        const double v = dy * inv_r;
        const float ey = m_spatial[size_t(std::abs(dy))];
        size_t i       = m_in.index(xa, y);
        for (int x = xa; x <= xb; ++x, ++i) {
            const uint8_t cls = m_in.cls[i];
            if (!(cls & kSurface) || !(cls & kReceiveAny))
                continue;
            const int dx  = x - m_x0;
            const float g = g_at(dx, dy);
            if (!(g > 0.0f))
                continue;
            float s = g * m_spatial[size_t(std::abs(dx))] * ey;
            if (cls & kFitPoint) {
                const size_t c = cache_index(dx, dy);
                s *= m_fit_weight[c] > 0.0f
                         ? values[c]
                         : std::exp(-value_exponent(m_in.zl[i], w.mean));
            }
            const int qi   = dx >= 0 ? (dy >= 0 ? 0 : 3) : (dy >= 0 ? 1 : 2);
            const Plane& quad = w.quadrant[qi];
            const double u    = dx * inv_r;
            const size_t o = size_t(y - m_out.ybegin) * out_w
                             + size_t(x - m_out.xbegin);
            double* acc = &m_acc[3 * o];
            for (int ch = 0; ch < 3; ++ch) {
                const double Z = w.whole.at(ch, u, v);
                double A       = Z;
                if (quad.present) {
                    const double Zm = quad.at(ch, u, v);
                    double wm;
                    if ((Z < 0 && Zm > 0) || (Z > 0 && Zm < 0)) {
                        wm = kMaxWm;
                    } else {
                        double r = (std::fabs(Z) + kEps) / (std::fabs(Zm) + kEps);
                        r        = std::max(r, 1.0 / r);
                        if (power == 8.0f) {
                            const double r2 = r * r, r4 = r2 * r2;
                            wm = r4 * r4;
                        } else {
                            wm = std::pow(r, double(power));
                        }
                        wm = std::min(wm, kMaxWm);
                    }
                    A = (Z + wm * Zm) / (1.0 + wm);
                }
                acc[ch] += s * A;
            }
            m_wsum[o] += s;
        }
    }
}


StopReason
WindowFitter::process(int x0, int y0, int& radius)
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
    if (current.whole.present)
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
    if (o.centre_stride < 1 || o.centre_stride > o.r_min + 1)
        return bad("centre_stride", o.centre_stride,
                   "needs 1 <= centre_stride <= r_min + 1 (windows must "
                   "overlap)");
    if (!finite_nonneg(o.quadrant_power))
        return bad("quadrant_power", o.quadrant_power,
                   "needs a finite number >= 0");
    return true;
}



/// Totals over the tiles of one call.
struct FilterTotals {
    StripStats windows;
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
    // Strips anchored at the data window's origin; strips of one parity have
    // disjoint splat footprints and run in parallel (section 8).
    const int strip_h   = std::max(2 * opt.r_max + 1, 32);
    const int first     = (cy0 - image.ybegin) / strip_h;
    const int last      = (cy1 - 1 - image.ybegin) / strip_h;
    const int nstrips   = std::max(last - first + 1, 0);
    std::vector<StripStats> strip_stats(static_cast<size_t>(nstrips));
    std::atomic<int64_t> rows_done { 0 };
    const int64_t rows_total = std::max(cy1 - cy0, 0);
    std::mutex progress_mutex;

    auto run_strip = [&](int s) {
        const int k  = first + s;
        const int ya = std::max(cy0, image.ybegin + k * strip_h);
        const int yb = std::min(cy1, image.ybegin + (k + 1) * strip_h);
        WindowFitter fitter(in, opt, roi, acc, wsum);
        GuideWeight lattice_guide(in, opt);
        StripStats& st = strip_stats[size_t(s)];
        const int stride = opt.centre_stride;
        for (int y = ya; y < yb; ++y) {
            for (int x = cx0; x < cx1; ++x) {
                if (!(in.cls[in.index(x, y)] & kFitPoint))
                    continue;
                if (stride > 1) {
                    // Strided centres: a fit point is a centre when it is
                    // on the lattice, or when its cell's lattice point
                    // cannot speak for it (not a fit point, or another
                    // surface), so that no surface is left without windows.
                    const int lx = x - (x - image.xbegin) % stride;
                    const int ly = y - (y - image.ybegin) % stride;
                    if (lx != x || ly != y) {
                        if (in.cls[in.index(lx, ly)] & kFitPoint) {
                            lattice_guide.centre(lx, ly);
                            if (lattice_guide(x, y) > 0.0f)
                                continue;
                        }
                    }
                }
                int radius        = 0;
                StopReason reason = fitter.process(x, y, radius);
                if (!roi.contains(x, y))
                    continue;
                ++st.windows;
                st.radius_sum += radius;
                st.stop_quality += reason == StopReason::Quality;
                st.stop_size += reason == StopReason::Size;
                st.stop_edge += reason == StopReason::Edge;
            }
            const int64_t done = ++rows_done;
            if (opt.progress) {
                std::lock_guard<std::mutex> lock(progress_mutex);
                opt.progress(float(done) / float(rows_total));
            }
        }
    };
    for (int parity = 0; parity < 2; ++parity) {
        std::vector<int> strips;
        for (int s = 0; s < nstrips; ++s)
            if ((first + s) % 2 == parity)
                strips.push_back(s);
        parallel_for(int64_t(0), int64_t(strips.size()),
                     [&](int64_t j) { run_strip(strips[size_t(j)]); },
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

    for (const StripStats& s : strip_stats) {
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
    // footprint (3x3 residual, 5x5 median, 3x3 smoothing) of 4.
    return 2 * std::max(options.r_max, 0) + 4;
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
        st.mean_radius        = st.windows ? double(totals.windows.radius_sum) / st.windows
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
