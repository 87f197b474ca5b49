// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Reference implementation of docs/FILTER.md sections 1-7. See
// reference_filter.h. Deliberately naive: no caching across radii or
// centres beyond the per-pixel quantities that section 3 itself defines as
// per-pixel images (V, Vs, sigma). All arithmetic in double.

#include "reference_filter.h"
#include "reference_box_core.h"

#include <zdenoise/highlights.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace zdenoise_ref {

using zdenoise::FilterOptions;

// ---------------------------------------------------------------------------
// ImageBuf <-> RefImage

RefImage
from_imagebuf(const OIIO::ImageBuf& buf)
{
    const OIIO::ImageSpec& spec = buf.spec();
    RefImage img(spec.width, spec.height, spec.nchannels);
    img.x0    = spec.x;
    img.y0    = spec.y;
    img.alpha = spec.alpha_channel;
    OIIO::ROI roi(spec.x, spec.x + spec.width, spec.y, spec.y + spec.height,
                  spec.z, spec.z + 1, 0, spec.nchannels);
    if (!buf.get_pixels(roi, OIIO::TypeFloat, img.px.data()))
        throw std::runtime_error("from_imagebuf: get_pixels failed: "
                                 + buf.geterror());
    return img;
}

OIIO::ImageBuf
to_imagebuf(const RefImage& img)
{
    OIIO::ImageSpec spec(img.w, img.h, img.nch, OIIO::TypeFloat);
    spec.x = spec.full_x = img.x0;
    spec.y = spec.full_y = img.y0;
    spec.alpha_channel   = img.alpha;
    OIIO::ImageBuf buf(spec);
    buf.set_pixels(buf.roi(), OIIO::TypeFloat, img.px.data());
    return buf;
}

// ---------------------------------------------------------------------------
// Section 1: demodulation and remodulation

namespace {

constexpr double EPS    = 1e-8;
constexpr double LW[3]  = { 0.2126, 0.7152, 0.0722 };
constexpr double INF    = std::numeric_limits<double>::infinity();
// The median of chi-square with one degree of freedom (0.454936423...), to
// the 7 digits FILTER.md section 3 gives.
constexpr double CHI2_MEDIAN = 0.4549364;

bool
demod_channel(const RefImage& La, int x, int y, int c, float albedo_eps)
{
    float a = La.at(x, y, c);
    return std::isfinite(a) && a >= albedo_eps && a * albedo_eps <= 1.0f;
}

}  // namespace

RefImage
demodulate(const RefImage& L, const RefImage& La, float albedo_eps)
{
    RefImage z = L;
    for (int y = 0; y < L.h; ++y)
        for (int x = 0; x < L.w; ++x)
            for (int c = 0; c < 3; ++c)
                if (demod_channel(La, x, y, c, albedo_eps))
                    z.at(x, y, c) = L.at(x, y, c) / (La.at(x, y, c) + albedo_eps);
    return z;
}

RefImage
remodulate(const RefImage& z, const RefImage& La, float albedo_eps)
{
    RefImage L = z;
    for (int y = 0; y < z.h; ++y)
        for (int x = 0; x < z.w; ++x)
            for (int c = 0; c < 3; ++c)
                if (demod_channel(La, x, y, c, albedo_eps))
                    L.at(x, y, c) = z.at(x, y, c) * (La.at(x, y, c) + albedo_eps);
    return L;
}

RefImage
bound_highlights(const RefImage& out, const RefImage& L)
{
    const int r = zdenoise::kHighlightRadius;
    RefImage b  = out;
    for (int y = 0; y < out.h; ++y)
        for (int x = 0; x < out.w; ++x)
            for (int c = 0; c < 3; ++c) {
                float m = -std::numeric_limits<float>::infinity();
                for (int v = std::max(y - r, 0); v <= std::min(y + r, L.h - 1); ++v)
                    for (int u = std::max(x - r, 0); u <= std::min(x + r, L.w - 1); ++u)
                        if (std::isfinite(L.at(u, v, c)))
                            m = std::max(m, L.at(u, v, c));
                float& o = b.at(x, y, c);
                if (std::isfinite(m) && std::isfinite(o) && o > m)
                    o = m;
            }
    return b;
}

// ---------------------------------------------------------------------------
// Sections 2-7

namespace {

/// Section 3a's t = Phi^-1(1 - 1 / (2 r_max + 1)^2).
double outlier_t(int r_max);

struct Normal {
    bool none = true;
    double n[3] = { 0, 0, 0 };
};

/// Everything the filter needs, with the per-pixel facts of sections 2 and 3.
class Filter {
public:
    Filter(const RefImage& z, const RefImage& La, const RefGuides& g,
           const FilterOptions& opt)
        : z(z), z_in(z), La(La), g(g), opt(opt), w(z.w), h(z.h)
        , value_noise_t(opt.value_noise ? outlier_t(opt.r_max) : 0.0)
    {
    }

    RefImage run(RefStats* stats, RefImage* diagnostics);
    /// docs/FILTER.md section 1: the box core between sections 2-3 and 3a/7.
    RefImage run_box(RefStats* stats);

private:
    RefImage z;               // the quotient the fits read (outliers capped)
    const RefImage& z_in;     // as given: what passes through
    const RefImage& La;
    const RefGuides& g;
    const FilterOptions& opt;
    int w, h;
    double value_noise_t;  // section 5's t, 0 without value_noise

    // per-pixel facts
    std::vector<char> surface_, fitpt_, receiver_;  // receiver_: 3 per pixel
    std::vector<double> zl_, V_, Vs_, sigma_;
    struct Outlier {
        int x, y;
        double excess[3];  // radiance
    };
    std::vector<Outlier> outliers_;  // section 3a, raster order
    void split_outliers();
    void classify_and_estimate(RefStats& st);  // sections 2 and 3
    /// Sections 3a and 7: the outliers' spread added to acc / wsum.
    RefImage finish(const std::vector<double>& acc, const std::vector<double>& wsum,
                    RefStats& st);

    size_t idx(int x, int y) const { return size_t(y) * w + x; }

    // ---- section 2 ----
    bool depth_valid(int x, int y) const
    {
        float d = g.depth->at(x, y, 0);
        return std::isfinite(d) && d > 0.0f && d < 1e9f;
    }
    bool compute_surface(int x, int y) const
    {
        if (z.alpha >= 0 && !(z.at(x, y, z.alpha) > 0.0f))
            return false;
        if (g.depth && !depth_valid(x, y))
            return false;
        return true;
    }
    bool demod(int x, int y, int c) const
    {
        return demod_channel(La, x, y, c, opt.albedo_eps);
    }
    bool surface(int x, int y) const { return surface_[idx(x, y)]; }
    bool fitpt(int x, int y) const { return fitpt_[idx(x, y)]; }
    bool receiver(int x, int y, int c) const { return receiver_[idx(x, y) * 3 + c]; }
    double zl(int x, int y) const { return zl_[idx(x, y)]; }
    double sigma(int x, int y) const { return sigma_[idx(x, y)]; }
    double Vs(int x, int y) const { return Vs_[idx(x, y)]; }

    // ---- section 4: guides ----
    Normal normal_at(int x, int y) const
    {
        Normal n;
        double v[3] = { g.normal->at(x, y, 0), g.normal->at(x, y, 1),
                        g.normal->at(x, y, 2) };
        double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (!std::isfinite(len) || len < 1e-6)
            return n;  // none
        n.none = false;
        for (int i = 0; i < 3; ++i)
            n.n[i] = v[i] / len;
        return n;
    }
    static double dot(const Normal& a, const Normal& b)
    {
        return a.n[0] * b.n[0] + a.n[1] * b.n[1] + a.n[2] * b.n[2];
    }
    double weight_normal(int xq, int yq, int x0, int y0) const
    {
        Normal a = normal_at(xq, yq), b = normal_at(x0, y0);
        if (a.none && b.none)
            return 1.0;
        if (a.none || b.none)
            return 0.0;
        double d = std::min(1.0, dot(a, b));  // rounding can exceed 1
        return d > opt.normal_cut ? std::pow(d, double(opt.normal_power)) : 0.0;
    }

    double zeta(int x, int y) const { return 1.0 / double(g.depth->at(x, y, 0)); }
    static double minmod(double a, double b)
    {
        if (a > 0 && b > 0)
            return std::min(a, b);
        if (a < 0 && b < 0)
            return std::max(a, b);
        return 0.0;
    }
    // gradient of inverse depth at p0 along (sx, sy) = (1,0) or (0,1)
    double zeta_gradient(int x0, int y0, int sx, int sy) const
    {
        bool has_f = inside_surface(x0 + sx, y0 + sy);
        bool has_b = inside_surface(x0 - sx, y0 - sy);
        double z0  = zeta(x0, y0);
        double f   = has_f ? zeta(x0 + sx, y0 + sy) - z0 : 0.0;
        double b   = has_b ? z0 - zeta(x0 - sx, y0 - sy) : 0.0;
        if (has_f && has_b)
            return minmod(f, b);
        if (has_f)
            return f;
        if (has_b)
            return b;
        return 0.0;
    }
    bool inside_surface(int x, int y) const
    {
        return x >= 0 && x < w && y >= 0 && y < h && surface(x, y);
    }
    double weight_depth(int xq, int yq, int x0, int y0) const
    {
        double gx   = zeta_gradient(x0, y0, 1, 0);
        double gy   = zeta_gradient(x0, y0, 0, 1);
        double zhat = zeta(x0, y0) + gx * (xq - x0) + gy * (yq - y0);
        if (zhat <= 0.0)
            return 0.0;
        if (std::abs(zeta(xq, yq) - zhat) > double(opt.depth_tolerance) * zhat)
            return 0.0;
        return 1.0;
    }

    // Cryptomatte-style (id, normalised coverage) pairs of a pixel
    std::vector<std::pair<float, double>> id_pairs(int x, int y) const
    {
        const RefImage& id = *g.object_id;
        int k = id.nch / 2;
        std::vector<std::pair<float, double>> p(k);
        double sum = 0.0;
        for (int i = 0; i < k; ++i) {
            double c = id.at(x, y, 2 * i + 1);
            if (!std::isfinite(c) || c < 0.0)
                c = 0.0;
            p[i] = { id.at(x, y, 2 * i), c };
            sum += c;
        }
        if (sum > 0.0)
            for (auto& e : p)
                e.second /= sum;
        return p;
    }
    double weight_id(int xq, int yq, int x0, int y0) const
    {
        const RefImage& id = *g.object_id;
        if (id.nch == 1)
            return id.at(xq, yq, 0) == id.at(x0, y0, 0) ? 1.0 : 0.0;
        auto pq = id_pairs(xq, yq), p0 = id_pairs(x0, y0);
        double sq = 0, s0 = 0;
        for (auto& e : pq)
            sq += e.second;
        for (auto& e : p0)
            s0 += e.second;
        if (sq == 0.0 || s0 == 0.0)  // no coverage matches only no coverage
            return (sq == 0.0 && s0 == 0.0) ? 1.0 : 0.0;
        double sum = 0.0;
        for (auto& a : pq)
            for (auto& b : p0)
                if (a.first == b.first)
                    sum += std::min(a.second, b.second);
        return sum;
    }

    /// The plain id, or the "primary" Cryptomatte id, read as the id of the
    /// largest normalised coverage (the first such pair on ties). FILTER.md
    /// does not say; for Cryptomatte, whose ranks are sorted by coverage,
    /// this is rank 0 whenever rank 0 has coverage.
    float primary_id(int x, int y) const
    {
        const RefImage& id = *g.object_id;
        if (id.nch == 1)
            return id.at(x, y, 0);
        auto pairs = id_pairs(x, y);
        size_t best = 0;
        for (size_t i = 1; i < pairs.size(); ++i)
            if (pairs[i].second > pairs[best].second)
                best = i;
        return pairs[best].first;
    }

    /// g(q; p0) of section 4.
    double guide_weight(int xq, int yq, int x0, int y0) const
    {
        if (xq == x0 && yq == y0)
            return 1.0;
        double wn = g.normal ? weight_normal(xq, yq, x0, y0) : 1.0;
        double wd = g.depth ? weight_depth(xq, yq, x0, y0) : 1.0;
        double wi = g.object_id ? weight_id(xq, yq, x0, y0) : 1.0;
        return wn * wd * wi;
    }

    // ---- section 3: noise ----
    bool same_surface_for_noise(int xa, int ya, int xb, int yb) const
    {
        if (g.object_id && primary_id(xa, ya) != primary_id(xb, yb))
            return false;
        if (g.normal) {
            Normal a = normal_at(xa, ya), b = normal_at(xb, yb);
            if (a.none != b.none)
                return false;
            if (!a.none && !(dot(a, b) > 0.9))
                return false;
        }
        return true;
    }
    void compute_noise();

    // ---- section 5: one window ----
    struct Pt {
        int x, y;
        double u, v;     // dx/R, dy/R
        double w;        // fit weight
        double z[3];     // quotient
        double vs;       // smoothed variance Vs
        double sigma;
    };
    struct Fit {
        bool present  = false;
        bool constant = false;
        double c[3] = { 0, 0, 0 }, a[3] = { 0, 0, 0 }, b[3] = { 0, 0, 0 };
        double var0 = 0.0;  // predicted variance of the luminance value at p0
        double at(int ch, double u, double v) const
        {
            return c[ch] + a[ch] * u + b[ch] * v;
        }
        double lum0() const { return LW[0] * c[0] + LW[1] * c[1] + LW[2] * c[2]; }
    };
    struct Window {
        int R = 0;
        double m = 0.0;  // mean zl over P_R
        Fit whole, quad[4];
        double llo[3] = { INF, INF, INF }, lhi[3] = { -INF, -INF, -INF };  // radiance over G_R
        double eta  = INF;
        bool edge   = false;
    };
    static Fit fit(const std::vector<Pt>& pts);
    Window window(int x0, int y0, int R) const;
    /// Section 5.1: radius R fitted on the 2x2 blocks (else as window()).
    Window window_on_pyramid(int x0, int y0, int R) const;
    Window window_at(int x0, int y0, int R) const
    {
        return opt.pyramid_radius > 0 && R >= opt.pyramid_radius
                   ? window_on_pyramid(x0, y0, R)
                   : window(x0, y0, R);
    }
    /// eta and the edge test of section 5 for W's fit over `good`.
    void stop_tests(Window& W, const std::vector<Pt>& good) const;
    /// Section 5's value term of point q in the window of (x0, y0) with
    /// mean m: its scale is |m| and, with value_noise, t s(p0).
    double value_term(double zlq, int x0, int y0, double m) const
    {
        double den = std::max(std::abs(m), EPS);
        const double v0 = Vs(x0, y0);
        if (v0 > 0.0 && v0 < INF)
            den += value_noise_t * std::sqrt(v0);
        return std::min(double(opt.value_k) * std::abs(zlq - m) / den, 30.0);
    }
};

// Section 3.
void
Filter::compute_noise()
{
    const float eps = opt.albedo_eps;
    std::vector<double> V(size_t(w) * h, 0.0);

    // The robust 5x5 estimate: median of the defined e over the 5x5 / the
    // median of chi-square(1); V = 0 where none is defined.
    auto robust = [&](const std::vector<double>& e,
                      const std::vector<char>& e_def) {
        std::vector<double> R(size_t(w) * h, 0.0);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                if (!fitpt(x, y))
                    continue;
                std::vector<double> vals;
                for (int dy = -2; dy <= 2; ++dy)
                    for (int dx = -2; dx <= 2; ++dx) {
                        int xn = x + dx, yn = y + dy;
                        if (z.inside(xn, yn) && e_def[idx(xn, yn)])
                            vals.push_back(e[idx(xn, yn)]);
                    }
                if (vals.empty())
                    continue;  // V = 0
                std::sort(vals.begin(), vals.end());
                size_t n = vals.size();
                // median; for an even count the mean of the two middle values
                double med = (n % 2) ? vals[n / 2]
                                     : 0.5 * (vals[n / 2 - 1] + vals[n / 2]);
                R[idx(x, y)] = med / CHI2_MEDIAN;
            }
        return R;
    };
    // Estimated from z: e(p) from the 8 same-surface neighbours.
    auto from_image = [&]() {
        std::vector<double> e(size_t(w) * h, 0.0);
        std::vector<char> e_def(size_t(w) * h, 0);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                if (!fitpt(x, y))
                    continue;
                int n      = 0;
                double sum = 0.0;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        int xn = x + dx, yn = y + dy;
                        if ((dx == 0 && dy == 0) || !z.inside(xn, yn))
                            continue;
                        if (!fitpt(xn, yn) || !same_surface_for_noise(x, y, xn, yn))
                            continue;
                        ++n;
                        sum += zl(xn, yn);
                    }
                if (n == 0)
                    continue;
                double r        = zl(x, y) - sum / n;
                e[idx(x, y)]     = r * r * n / (n + 1.0);
                e_def[idx(x, y)] = 1;
            }
        return robust(e, e_def);
    };

    // Section 14's estimate on the fit points' zl: per direction the mean
    // over the 5x5 on the pixel's surface of the squared second differences
    // over 1.5, the smallest of the four (each with at least 3) over 0.743;
    // NaN where none has 3.
    auto directional = [&]() {
        static const int dirs[4][2] = { { 1, 0 }, { 0, 1 }, { 1, 1 }, { 1, -1 } };
        auto second = [&](int x, int y, int d, double& out) {
            const int ax = x - dirs[d][0], ay = y - dirs[d][1];
            const int bx = x + dirs[d][0], by = y + dirs[d][1];
            if (!z.inside(ax, ay) || !z.inside(bx, by) || !fitpt(x, y)
                || !fitpt(ax, ay) || !fitpt(bx, by)
                || !same_surface_for_noise(x, y, ax, ay)
                || !same_surface_for_noise(x, y, bx, by))
                return false;
            const double dd = zl(x, y) - 0.5 * (zl(ax, ay) + zl(bx, by));
            out = dd * dd / 1.5;
            return true;
        };
        std::vector<double> D(size_t(w) * h, std::nan(""));
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                if (!fitpt(x, y))
                    continue;
                double sum[4] = { 0, 0, 0, 0 };
                int count[4]  = { 0, 0, 0, 0 };
                for (int v = y - 2; v <= y + 2; ++v)
                    for (int u = x - 2; u <= x + 2; ++u) {
                        if (!z.inside(u, v) || !fitpt(u, v)
                            || !same_surface_for_noise(x, y, u, v))
                            continue;
                        for (int d = 0; d < 4; ++d) {
                            double e2;
                            if (second(u, v, d, e2)) {
                                sum[d] += e2;
                                ++count[d];
                            }
                        }
                    }
                double best = std::nan("");
                for (int d = 0; d < 4; ++d)
                    if (count[d] >= 3 && !(best <= sum[d] / count[d]))
                        best = sum[d] / count[d];
                D[idx(x, y)] = best / 0.743;
            }
        return D;
    };
    // With directional_noise the smaller of the two; where the directional
    // estimate is NaN (no direction has 3), the median's.
    auto own = [&]() {
        std::vector<double> v = from_image();
        if (opt.directional_noise) {
            const std::vector<double> d = directional();
            for (size_t i = 0; i < v.size(); ++i)
                if (d[i] < v[i])
                    v[i] = d[i];
        }
        return v;
    };

    if (g.variance || (g.half_a && g.half_b)) {
        std::vector<char> defined(size_t(w) * h, 0);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                if (!fitpt(x, y))
                    continue;
                double sum = 0.0;
                for (int c = 0; c < 3; ++c) {
                    double varL;
                    if (g.variance) {
                        int vc = g.variance->nch >= 3 ? c : 0;
                        varL   = g.variance->at(x, y, vc);
                    } else {
                        double d = double(g.half_a->at(x, y, c))
                                   - double(g.half_b->at(x, y, c));
                        varL = d * d / 4.0;
                    }
                    double den = double(La.at(x, y, c)) + double(eps);
                    sum += LW[c] * varL / (den * den);
                }
                V[idx(x, y)]       = sum;
                defined[idx(x, y)] = std::isfinite(sum) && sum >= 0.0;
            }
        if (!g.variance) {
            // Halves: the robust estimate of the pairs' squared differences,
            // and never below the image's own (which also sees structure).
            V = robust(V, defined);
            const std::vector<double> image = own();
            for (size_t i = 0; i < V.size(); ++i)
                if (image[i] > V[i] || std::isnan(V[i]))
                    V[i] = image[i];
        }
    } else {
        V = own();
    }
    V_ = V;
    if (opt.outlier_spread)
        split_outliers();

    // 3x3 smoothing over fit points, and sigma
    Vs_.assign(size_t(w) * h, 0.0);
    sigma_.assign(size_t(w) * h, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (!fitpt(x, y))
                continue;
            int n = 0, nv = 0;
            double sv = 0.0, sz = 0.0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    int xn = x + dx, yn = y + dy;
                    if (!z.inside(xn, yn) || !fitpt(xn, yn))
                        continue;
                    ++n;
                    sz += zl(xn, yn);
                    // An undefined V (NaN) takes no part, as in the library.
                    if (!std::isnan(V[idx(xn, yn)])) {
                        sv += V[idx(xn, yn)];
                        ++nv;
                    }
                }
            double vs = nv ? sv / nv : 0.0, zs = sz / n;
            Vs_[idx(x, y)]    = vs;
            sigma_[idx(x, y)] = std::sqrt(vs) / std::max(std::abs(zs), EPS);
        }
}

// A weighted least-squares plane c + a u + b v (section 5).
Filter::Fit
Filter::fit(const std::vector<Pt>& pts)
{
    Fit f;
    double sumw = 0.0;
    int npos    = 0;
    double M[3][3] = {}, S[3][3] = {}, rhs[3][3] = {};  // rhs[channel][k]
    double sumw2vs = 0.0, sumwz[3] = { 0, 0, 0 };
    for (const Pt& p : pts) {
        double basis[3] = { 1.0, p.u, p.v };
        sumw += p.w;
        if (p.w > 0.0)
            ++npos;
        sumw2vs += p.w * p.w * p.vs;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                M[i][j] += p.w * basis[i] * basis[j];
                S[i][j] += p.w * p.w * p.vs * basis[i] * basis[j];
            }
        for (int c = 0; c < 3; ++c) {
            sumwz[c] += p.w * p.z[c];
            for (int i = 0; i < 3; ++i)
                rhs[c][i] += p.w * p.z[c] * basis[i];
        }
    }
    if (sumw == 0.0)
        return f;  // absent
    f.present = true;

    double det = M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1])
                 - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0])
                 + M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]);
    if (npos < 3 || det <= 1e-6 * sumw * sumw * sumw) {
        f.constant = true;
        for (int c = 0; c < 3; ++c)
            f.c[c] = sumwz[c] / sumw;
        f.var0 = sumw2vs / (sumw * sumw);
        return f;
    }
    // inverse by cofactors (M is symmetric)
    double inv[3][3];
    inv[0][0] = (M[1][1] * M[2][2] - M[1][2] * M[2][1]) / det;
    inv[0][1] = (M[0][2] * M[2][1] - M[0][1] * M[2][2]) / det;
    inv[0][2] = (M[0][1] * M[1][2] - M[0][2] * M[1][1]) / det;
    inv[1][0] = (M[1][2] * M[2][0] - M[1][0] * M[2][2]) / det;
    inv[1][1] = (M[0][0] * M[2][2] - M[0][2] * M[2][0]) / det;
    inv[1][2] = (M[0][2] * M[1][0] - M[0][0] * M[1][2]) / det;
    inv[2][0] = (M[1][0] * M[2][1] - M[1][1] * M[2][0]) / det;
    inv[2][1] = (M[0][1] * M[2][0] - M[0][0] * M[2][1]) / det;
    inv[2][2] = (M[0][0] * M[1][1] - M[0][1] * M[1][0]) / det;
    for (int c = 0; c < 3; ++c) {
        double coef[3];
        for (int i = 0; i < 3; ++i)
            coef[i] = inv[i][0] * rhs[c][0] + inv[i][1] * rhs[c][1]
                      + inv[i][2] * rhs[c][2];
        f.c[c] = coef[0];
        f.a[c] = coef[1];
        f.b[c] = coef[2];
    }
    // var = e0^T M^-1 S M^-1 e0 = k^T S k with k = M^-1 e0
    double k[3] = { inv[0][0], inv[1][0], inv[2][0] };
    double var  = 0.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            var += k[i] * S[i][j] * k[j];
    f.var0 = var;
    return f;
}

// Section 5, one radius, everything from scratch.
Filter::Window
Filter::window(int x0, int y0, int R) const
{
    Window W;
    W.R = R;
    const int xa = std::max(x0 - R, 0), xb = std::min(x0 + R, w - 1);
    const int ya = std::max(y0 - R, 0), yb = std::min(y0 + R, h - 1);

    // P_R and its mean
    std::vector<std::pair<int, int>> P;
    std::vector<double> gw;
    for (int y = ya; y <= yb; ++y)
        for (int x = xa; x <= xb; ++x) {
            if (!fitpt(x, y))
                continue;
            double gq = guide_weight(x, y, x0, y0);
            if (gq > 0.0) {
                P.push_back({ x, y });
                gw.push_back(gq);
            }
        }
    double sum = 0.0;
    for (auto& p : P)
        sum += zl(p.first, p.second);
    W.m = sum / double(P.size());  // never empty: p0 is in P

    // good points with their fit weights
    std::vector<Pt> good;
    const double R2 = double(R) * R;
    for (size_t i = 0; i < P.size(); ++i) {
        int x = P[i].first, y = P[i].second;
        if (!(sigma(x, y) <= double(opt.sigma_good)))
            continue;
        int dx = x - x0, dy = y - y0;
        Pt p;
        p.x = x;
        p.y = y;
        p.u = double(dx) / R;
        p.v = double(dy) / R;
        double vt = value_term(zl(x, y), x0, y0, W.m);
        p.w = gw[i] * std::exp(-(vt + sigma(x, y) + (dx * dx + dy * dy) / R2));
        for (int c = 0; c < 3; ++c)
            p.z[c] = z.at(x, y, c);
        p.vs    = Vs(x, y);
        p.sigma = sigma(x, y);
        for (int c = 0; c < 3; ++c) {
            const double L = p.z[c] * (double(La.at(x, y, c)) + double(opt.albedo_eps));
            W.llo[c] = std::min(W.llo[c], L);
            W.lhi[c] = std::max(W.lhi[c], L);
        }
        good.push_back(p);
    }

    // five fits over closed quadrants
    W.whole = fit(good);
    for (int m = 0; m < 4; ++m) {
        std::vector<Pt> q;
        for (const Pt& p : good) {
            int dx = p.x - x0, dy = p.y - y0;
            bool in = (m == 0) ? (dx >= 0 && dy >= 0)
                    : (m == 1) ? (dx <= 0 && dy >= 0)
                    : (m == 2) ? (dx <= 0 && dy <= 0)
                               : (dx >= 0 && dy <= 0);
            if (in)
                q.push_back(p);
        }
        W.quad[m] = fit(q);
    }

    stop_tests(W, good);
    return W;
}


void
Filter::stop_tests(Window& W, const std::vector<Pt>& good) const
{
    // eta
    if (W.whole.present) {
        double sw = 0.0, sw2s2 = 0.0;
        for (const Pt& p : good) {
            sw += p.w;
            sw2s2 += p.w * p.w * p.sigma * p.sigma;
        }
        W.eta = std::sqrt(sw2s2) / sw;
    }

    // edge test
    if (W.whole.present) {
        double Zl = W.whole.lum0();
        double sc = std::max(std::abs(Zl), EPS);
        for (int m = 0; m < 4; ++m) {
            if (!W.quad[m].present)
                continue;
            double Zlm   = W.quad[m].lum0();
            double eta_m = std::sqrt(W.quad[m].var0) / sc;
            double tau   = std::max(double(opt.edge_k) * eta_m, double(opt.tau_min));
            if (std::abs(Zl - Zlm) / sc > tau)
                W.edge = true;
        }
    }
}


// Section 5.1: the same fit on the blocks of 2x2 pixels (anchored at pixel
// 0) that lie wholly in the window and the image, are surface, share their
// id and have a planar inverse depth, each standing for its good fit
// points with their weights summed; the range stays the fine points' (the
// blocks' where the window has no fine good point).
Filter::Window
Filter::window_on_pyramid(int x0, int y0, int R) const
{
    auto floor_half = [](int v) { return v >= 0 ? v / 2 : -((1 - v) / 2); };
    const int bxa = floor_half(std::max(x0 - R, 0) + 1);
    const int bxb = floor_half(std::min(x0 + R, w - 1) - 1);
    const int bya = floor_half(std::max(y0 - R, 0) + 1);
    const int byb = floor_half(std::min(y0 + R, h - 1) - 1);
    const double gx = g.depth ? zeta_gradient(x0, y0, 1, 0) : 0.0;
    const double gy = g.depth ? zeta_gradient(x0, y0, 0, 1) : 0.0;
    struct Block {
        double dx, dy, g, P = 0.0, zl = 0.0, z[3] = {}, l[3] = {}, vs = 0.0, s2 = 0.0;
    };
    std::vector<Block> blocks;
    double zsum = 0.0;
    int zcount  = 0;
    for (int by = bya; by <= byb; ++by)
        for (int bx = bxa; bx <= bxb; ++bx) {
            const int px[4][2] = { { 2 * bx, 2 * by }, { 2 * bx + 1, 2 * by },
                                   { 2 * bx, 2 * by + 1 },
                                   { 2 * bx + 1, 2 * by + 1 } };
            bool valid = true;
            for (auto& p : px)
                valid = valid && inside_surface(p[0], p[1]);
            if (!valid)
                continue;
            if (g.object_id)
                for (auto& p : px)
                    for (int c = 0; c < g.object_id->nch; ++c)
                        valid = valid
                                && g.object_id->at(p[0], p[1], c)
                                       == g.object_id->at(px[0][0], px[0][1], c);
            Block b;
            b.dx = 2.0 * bx + 0.5 - x0;
            b.dy = 2.0 * by + 0.5 - y0;
            b.g  = 1.0;
            if (g.depth) {
                double zeta_mean = 0.0;
                for (auto& p : px)
                    zeta_mean += 0.25 * zeta(p[0], p[1]);
                for (auto& p : px)
                    valid = valid
                            && std::abs(zeta(p[0], p[1]) - zeta_mean)
                                   <= double(opt.depth_tolerance)
                                          * std::abs(zeta_mean);
                const double zhat = zeta(x0, y0) + gx * b.dx + gy * b.dy;
                if (zhat <= 0.0
                    || std::abs(zeta_mean - zhat)
                           > double(opt.depth_tolerance) * zhat)
                    b.g = 0.0;
            }
            if (!valid)
                continue;
            if (g.normal) {
                Normal n;
                for (auto& p : px) {
                    const Normal np = normal_at(p[0], p[1]);
                    for (int c = 0; c < 3; ++c)
                        n.n[c] += np.n[c];
                }
                const double len = std::sqrt(dot(n, n));
                n.none = !(len >= 1e-6);
                for (int c = 0; c < 3; ++c)
                    n.n[c] = n.none ? 0.0 : n.n[c] / len;
                const Normal n0 = normal_at(x0, y0);
                double wn = 1.0;
                if (n.none != n0.none)
                    wn = 0.0;
                else if (!n.none) {
                    const double d = std::min(1.0, dot(n, n0));
                    wn = d > opt.normal_cut
                             ? std::pow(d, double(opt.normal_power))
                             : 0.0;
                }
                b.g *= wn;
            }
            if (g.object_id)
                b.g *= weight_id(px[0][0], px[0][1], x0, y0);
            if (!(b.g > 0.0))
                continue;
            for (auto& p : px) {
                if (!fitpt(p[0], p[1]))
                    continue;
                zsum += zl(p[0], p[1]);
                ++zcount;
                const double sg = sigma(p[0], p[1]);
                if (!(sg <= double(opt.sigma_good)))
                    continue;
                const double pw = std::exp(-sg);
                b.P += pw;
                b.zl += pw * zl(p[0], p[1]);
                for (int c = 0; c < 3; ++c) {
                    b.z[c] += pw * z.at(p[0], p[1], c);
                    b.l[c] += pw * z.at(p[0], p[1], c)
                              * (double(La.at(p[0], p[1], c)) + double(opt.albedo_eps));
                }
                b.vs += pw * pw * Vs(p[0], p[1]);
                b.s2 += pw * pw * sg * sg;
            }
            if (b.P > 0.0)
                blocks.push_back(b);
        }
    if (zcount == 0 || blocks.empty())
        return window(x0, y0, R);
    Window W;
    W.R = R;
    W.m = zsum / zcount;
    std::vector<Pt> good;
    const double R2 = double(R) * R;
    for (const Block& b : blocks) {
        Pt p;
        p.x = p.y = 0;  // unused: quadrants by the signs of u, v below
        p.u     = b.dx / R;
        p.v     = b.dy / R;
        const double zlb = b.zl / b.P;
        const double vt  = value_term(zlb, x0, y0, W.m);
        p.w = b.g * b.P * std::exp(-(vt + (b.dx * b.dx + b.dy * b.dy) / R2));
        for (int c = 0; c < 3; ++c)
            p.z[c] = b.z[c] / b.P;
        p.vs    = b.vs / (b.P * b.P);
        p.sigma = std::sqrt(b.s2) / b.P;
        good.push_back(p);
    }
    W.whole = fit(good);
    if (!W.whole.present)
        return window(x0, y0, R);
    for (int m = 0; m < 4; ++m) {
        std::vector<Pt> q;
        for (const Pt& p : good) {
            const bool in = (m == 0)   ? (p.u > 0 && p.v > 0)
                            : (m == 1) ? (p.u < 0 && p.v > 0)
                            : (m == 2) ? (p.u < 0 && p.v < 0)
                                       : (p.u > 0 && p.v < 0);
            if (in)
                q.push_back(p);
        }
        W.quad[m] = fit(q);
    }
    // The range of the fine good points, as the exact window has it; where
    // the window has none (a block's mean normal can pass the centre's test
    // where none of its pixels does), the range of the blocks' radiance.
    const Window fine = window(x0, y0, R);
    const bool fine_points = fine.llo[0] <= fine.lhi[0];
    for (int c = 0; c < 3; ++c) {
        W.llo[c] = fine.llo[c];
        W.lhi[c] = fine.lhi[c];
        if (fine_points)
            continue;
        W.llo[c] = INF, W.lhi[c] = -INF;
        for (const Block& b : blocks) {
            W.llo[c] = std::min(W.llo[c], b.l[c] / b.P);
            W.lhi[c] = std::max(W.lhi[c], b.l[c] / b.P);
        }
    }
    stop_tests(W, good);
    return W;
}

// Section 3a: a fit point whose luminance exceeds both its 5x5 same-surface
// neighbourhood's median by t standard deviations (sqrt of the median of V
// there) and its brightest same-surface 3x3 neighbour is capped at the
// larger of the two; t = Phi^-1(1 - 1 / (2 r_max + 1)^2). Decided on the
// original values, then applied.
double
outlier_t(int r_max)
{
    const double n = double(2 * r_max + 1) * double(2 * r_max + 1);
    // Phi^-1(1 - 1/n) by Newton's method on the normal tail Q(t) = 1/n.
    double t = 3.0;
    for (int k = 0; k < 50; ++k) {
        const double q   = 0.5 * std::erfc(t / std::sqrt(2.0));
        const double pdf = std::exp(-0.5 * t * t) / std::sqrt(2.0 * M_PI);
        t += (q - 1.0 / n) / pdf;
    }
    return t;
}

void
Filter::split_outliers()
{
    const double t = outlier_t(opt.r_max);
    auto med = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        const size_t k = v.size();
        return (k % 2) ? v[k / 2] : 0.5 * (v[k / 2 - 1] + v[k / 2]);
    };
    std::vector<double> cap(size_t(w) * h, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (!fitpt(x, y))
                continue;
            std::vector<double> level, var;
            double neighbour = -INF;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx) {
                    const int xn = x + dx, yn = y + dy;
                    if (!z.inside(xn, yn) || !fitpt(xn, yn)
                        || !same_surface_for_noise(x, y, xn, yn))
                        continue;
                    level.push_back(zl(xn, yn));
                    if (!std::isnan(V_[idx(xn, yn)]))
                        var.push_back(V_[idx(xn, yn)]);
                    if ((dx || dy) && std::abs(dx) <= 1 && std::abs(dy) <= 1)
                        neighbour = std::max(neighbour, zl(xn, yn));
                }
            if (var.empty())
                continue;
            const double top = std::max(med(level) + t * std::sqrt(med(var)), neighbour);
            if (zl(x, y) > top && top > 0.0)
                cap[idx(x, y)] = top;
        }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (!(cap[idx(x, y)] > 0.0))
                continue;
            const double keep = cap[idx(x, y)] / zl(x, y);
            Outlier o { x, y, { 0, 0, 0 } };
            for (int c = 0; c < 3; ++c) {
                const double zc = z.at(x, y, c);
                o.excess[c] = zc * (1.0 - keep) * (double(La.at(x, y, c)) + double(opt.albedo_eps));
                z.at(x, y, c) = float(zc * keep);
            }
            zl_[idx(x, y)] = cap[idx(x, y)];
            outliers_.push_back(o);
        }
}

void
Filter::classify_and_estimate(RefStats& st)
{
    // ---- section 2: pixel classes ----
    surface_.assign(size_t(w) * h, 0);
    fitpt_.assign(size_t(w) * h, 0);
    receiver_.assign(size_t(w) * h * 3, 0);
    zl_.assign(size_t(w) * h, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool s             = compute_surface(x, y);
            surface_[idx(x, y)] = s;
            bool fp            = s;
            bool nonfinite     = false;
            for (int c = 0; c < 3; ++c) {
                bool d = demod(x, y, c);
                receiver_[idx(x, y) * 3 + c] = s && d;
                bool fin                     = std::isfinite(z.at(x, y, c));
                if (!fin)
                    nonfinite = true;
                if (!d || !(std::fabs(z.at(x, y, c)) <= 1e18f))
                    fp = false;
            }
            fitpt_[idx(x, y)] = fp;
            if (fp)
                zl_[idx(x, y)] = LW[0] * z.at(x, y, 0) + LW[1] * z.at(x, y, 1)
                                 + LW[2] * z.at(x, y, 2);
            if (nonfinite)
                ++st.nonfinite_pixels;
        }

    // ---- section 3 ----
    compute_noise();
}

RefImage
Filter::run(RefStats* stats, RefImage* diagnostics)
{
    RefStats st;
    classify_and_estimate(st);
    // ---- sections 5 and 6: centres in raster order (or strided) ----
    std::vector<double> acc(size_t(w) * h * 3, 0.0), wsum(size_t(w) * h, 0.0);
    // Diagnostics (zdenoise.h, diagnostic_channels()): per pixel the sums
    // of s R, s eta and s per stop code 1-3.
    std::vector<double> diag(size_t(w) * h * 5, 0.0);
    double radius_sum = 0.0;
    // One centre: its window grown and splatted; whether an edge stopped it.
    auto centre = [&](int x0, int y0) {
        ++st.windows;
        bool edge = false;
        int code  = 0;
        Window fin;
        // Radii r_min, then max(R + 1, floor(R * radius_growth)) up
        // to r_max; an edge steps back to the radius tried before.
        int before = 0;
        for (int R = opt.r_min;;) {
            Window W = window_at(x0, y0, R);
            if (W.edge) {
                fin = (R > opt.r_min) ? window_at(x0, y0, before) : W;
                ++st.stop_edge;
                edge = true;
                code = 3;
                break;
            }
            if (W.eta <= double(opt.eta_target)) {
                fin = W;
                ++st.stop_quality;
                code = 1;
                break;
            }
            if (R == opt.r_max) {
                fin = W;
                ++st.stop_size;
                code = 2;
                break;
            }
            before = R;
            R = std::min(std::max(R + 1, int(float(R) * opt.radius_growth)), opt.r_max);
        }
        radius_sum += fin.R;
        if (!fin.whole.present) {
            ++st.absent_windows;
            return edge;  // contributes nothing
        }

        // section 6: combination and splatting over W_R
        const int R  = fin.R;
        const double R2 = double(R) * R;
        const int xa = std::max(x0 - R, 0), xb = std::min(x0 + R, w - 1);
        const int ya = std::max(y0 - R, 0), yb = std::min(y0 + R, h - 1);
        for (int yq = ya; yq <= yb; ++yq)
            for (int xq = xa; xq <= xb; ++xq) {
                if (!surface(xq, yq))
                    continue;
                if (!receiver(xq, yq, 0) && !receiver(xq, yq, 1)
                    && !receiver(xq, yq, 2))
                    continue;
                double gq = guide_weight(xq, yq, x0, y0);
                if (!(gq > 0.0))
                    continue;
                int dx = xq - x0, dy = yq - y0;
                double u = double(dx) / R, v = double(dy) / R;
                int m = (dx >= 0 && dy >= 0) ? 0
                      : (dx < 0 && dy >= 0)  ? 1
                      : (dx < 0 && dy < 0)   ? 2
                                             : 3;
                double vt = fitpt(xq, yq) ? value_term(zl(xq, yq), x0, y0, fin.m) : 0.0;
                double s  = gq * std::exp(-(vt + (dx * dx + dy * dy) / R2));
                for (int c = 0; c < 3; ++c) {
                    double Z = fin.whole.at(c, u, v);
                    double A = Z;
                    if (fin.quad[m].present) {
                        double Zm = fin.quad[m].at(c, u, v);
                        double wm;
                        if (Z * Zm < 0.0) {
                            wm = 1e6;
                        } else {
                            double r = (std::abs(Z) + EPS) / (std::abs(Zm) + EPS);
                            wm = std::min(std::pow(std::max(r, 1.0 / r),
                                                   double(opt.quadrant_power)),
                                          1e6);
                        }
                        A = (Z + wm * Zm) / (1.0 + wm);
                    }
                    // within the radiance of the window's good points, at
                    // this pixel's albedo
                    if (receiver_[idx(xq, yq) * 3 + c]) {
                        const double a = double(La.at(xq, yq, c)) + double(opt.albedo_eps);
                        A = std::min(std::max(A, fin.llo[c] / a), fin.lhi[c] / a);
                    }
                    acc[idx(xq, yq) * 3 + c] += s * A;
                }
                wsum[idx(xq, yq)] += s;
                double* d = &diag[idx(xq, yq) * 5];
                d[0] += s * R;
                d[1] += s * fin.eta;
                d[1 + code] += s;
            }
        return edge;
    };
    const int stride = std::max(1, std::min(opt.centre_stride, std::max(opt.r_min, 1) + 1));
    if (stride == 1) {
        for (int y0 = 0; y0 < h; ++y0)
            for (int x0 = 0; x0 < w; ++x0)
                if (fitpt(x0, y0))
                    centre(x0, y0);
    } else {
        // Strided centres (docs/FILTER.md section 8), in two sweeps: the
        // lattice, then each other fit point that no lattice point of its
        // cell on its surface speaks for, or one of which stopped at an
        // edge (stride_edges).
        enum { kNone, kSmooth, kEdge };
        std::vector<int> lattice(size_t(w) * h, kNone);
        for (int y0 = 0; y0 < h; y0 += stride)
            for (int x0 = 0; x0 < w; x0 += stride)
                if (fitpt(x0, y0))
                    lattice[idx(x0, y0)] = centre(x0, y0) && opt.stride_edges ? kEdge
                                                                              : kSmooth;
        for (int y0 = 0; y0 < h; ++y0)
            for (int x0 = 0; x0 < w; ++x0) {
                if ((x0 % stride == 0 && y0 % stride == 0) || !fitpt(x0, y0))
                    continue;
                bool covered = false, edge = false;
                for (int dj = 0; dj <= (y0 % stride != 0); ++dj)
                    for (int di = 0; di <= (x0 % stride != 0); ++di) {
                        const int lx = x0 - x0 % stride + di * stride, ly = y0 - y0 % stride + dj * stride;
                        if (lx >= w || ly >= h)
                            continue;
                        const int l = lattice[idx(lx, ly)];
                        if (l != kNone && guide_weight(x0, y0, lx, ly) > 0.0) {
                            covered = true;
                            edge |= l == kEdge;
                        }
                    }
                // stride_edges 2: beside an edge, a checkerboard of the cell.
                const bool every = opt.stride_edges == 1 || (x0 + y0) % 2 == 0;
                if ((edge && every) || !covered)
                    centre(x0, y0);
            }
    }

    RefImage out = finish(acc, wsum, st);

    if (diagnostics) {
        *diagnostics = RefImage(w, h, 4, 0.0f);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const double* d = &diag[idx(x, y) * 5];
                const double ws = wsum[idx(x, y)];
                if (fitpt(x, y))
                    diagnostics->at(x, y, 2) = float(sigma(x, y));
                if (!(ws > 0.0))
                    continue;
                int code = 1;  // the most splat weight; ties to the lower
                for (int k = 2; k <= 3; ++k)
                    if (d[1 + k] > d[1 + code])
                        code = k;
                diagnostics->at(x, y, 0) = float(d[0] / ws);
                diagnostics->at(x, y, 1) = float(code);
                diagnostics->at(x, y, 3) = float(d[1] / ws);
            }
    }
    st.pixels      = int64_t(w) * h;
    st.mean_radius = st.windows ? radius_sum / double(st.windows) : 0.0;
    if (stats)
        *stats = st;
    return out;
}

RefImage
Filter::run_box(RefStats* stats)
{
    RefStats st;
    classify_and_estimate(st);
    BoxInputs in;
    in.w = w, in.h = h;
    const size_t np = size_t(w) * h;
    in.fit.assign(np, 0);
    in.z.assign(3 * np, 0.0);
    in.zl.assign(np, 0.0);
    in.vs.assign(np, 0.0);
    in.normal.assign(3 * np, 0.0);
    in.invdepth.assign(np, 0.0);
    in.albedo.assign(3 * np, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = idx(x, y);
            in.fit[i] = fitpt(x, y);
            for (int c = 0; c < 3; ++c) {
                if (in.fit[i])
                    in.z[3 * i + c] = z.at(x, y, c);
                if (receiver(x, y, c))
                    in.albedo[3 * i + c] = double(La.at(x, y, c)) + double(opt.albedo_eps);
            }
            if (in.fit[i])
                in.zl[i] = zl(x, y), in.vs[i] = Vs(x, y);
            if (g.normal) {
                const Normal n = normal_at(x, y);
                for (int c = 0; c < 3 && !n.none; ++c)
                    in.normal[3 * i + c] = n.n[c];
            }
            if (g.depth && surface(x, y))
                in.invdepth[i] = zeta(x, y);
        }
    std::vector<double> acc, wsum;
    box_core_light(in, opt, acc, wsum);
    RefImage out = finish(acc, wsum, st);
    st.pixels = int64_t(w) * h;
    if (stats)
        *stats = st;
    return out;
}

RefImage
Filter::finish(const std::vector<double>& acc, const std::vector<double>& wsum,
               RefStats& st)
{
    // ---- section 3a: the outliers' excess, spread ----
    std::vector<double> spread(size_t(w) * h * 3, 0.0);
    for (const Outlier& o : outliers_) {
        const int R = opt.r_max;
        double norm[3] = { 0, 0, 0 };
        auto weight = [&](int xq, int yq) {
            if (!surface(xq, yq))
                return 0.0;
            const int dx = xq - o.x, dy = yq - o.y;
            return guide_weight(xq, yq, o.x, o.y)
                   * std::exp(-double(dx * dx + dy * dy) / (double(R) * R));
        };
        for (int yq = std::max(o.y - R, 0); yq <= std::min(o.y + R, h - 1); ++yq)
            for (int xq = std::max(o.x - R, 0); xq <= std::min(o.x + R, w - 1); ++xq)
                for (int c = 0; c < 3; ++c)
                    if (receiver(xq, yq, c))
                        norm[c] += weight(xq, yq)
                                   * (double(La.at(xq, yq, c)) + double(opt.albedo_eps));
        for (int yq = std::max(o.y - R, 0); yq <= std::min(o.y + R, h - 1); ++yq)
            for (int xq = std::max(o.x - R, 0); xq <= std::min(o.x + R, w - 1); ++xq)
                for (int c = 0; c < 3; ++c)
                    if (receiver(xq, yq, c) && norm[c] > 0.0)
                        spread[idx(xq, yq) * 3 + c]
                            += o.excess[c] * weight(xq, yq) / norm[c];
    }

    // ---- section 7: output ----
    RefImage out = z_in;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool passthrough = false;
            for (int c = 0; c < 3; ++c) {
                double ws = wsum[idx(x, y)];
                // A sum a splat overflowed is no value (section 7); the
                // rest saturates at the largest float.
                const double v = receiver(x, y, c) && ws > 0.0
                                     ? acc[idx(x, y) * 3 + c] / ws + spread[idx(x, y) * 3 + c]
                                     : std::numeric_limits<double>::quiet_NaN();
                if (std::isfinite(v)) {
                    const double largest = std::numeric_limits<float>::max();
                    out.at(x, y, c) = float(std::clamp(v, -largest, largest));
                } else {
                    passthrough = true;
                    float zc    = z_in.at(x, y, c);
                    out.at(x, y, c) = std::isfinite(zc) ? zc : 0.0f;
                    if (!std::isfinite(zc) && receiver(x, y, c)) {
                        // A hole: the plane through the light of the fit
                        // points within 2 r_max, weights g exp(-d^2 / r_max^2),
                        // at the hole, within their range.
                        const int R = 2 * opt.r_max;
                        std::vector<Pt> pts;
                        double lo = INF, hi = -INF;
                        for (int yq = std::max(y - R, 0); yq <= std::min(y + R, h - 1); ++yq)
                            for (int xq = std::max(x - R, 0); xq <= std::min(x + R, w - 1); ++xq) {
                                if (!fitpt(xq, yq))
                                    continue;
                                const double gq = guide_weight(xq, yq, x, y);
                                if (!(gq > 0.0))
                                    continue;
                                const int dx = xq - x, dy = yq - y;
                                Pt p {};
                                p.x = xq;
                                p.y = yq;
                                p.u = double(dx) / R;
                                p.v = double(dy) / R;
                                p.w = gq * std::exp(-double(dx * dx + dy * dy)
                                                    / (double(opt.r_max) * opt.r_max));
                                for (int k = 0; k < 3; ++k)
                                    p.z[k] = z.at(xq, yq, k);
                                lo = std::min(lo, p.z[c]);
                                hi = std::max(hi, p.z[c]);
                                pts.push_back(p);
                            }
                        const Fit f = fit(pts);
                        if (f.present)
                            out.at(x, y, c) = float(std::min(std::max(f.at(c, 0, 0), lo), hi));
                    }
                }
            }
            if (passthrough)
                ++st.passthrough_pixels;
        }
    return out;
}

}  // namespace

RefImage
regression_filter(const RefImage& z, const RefImage& La, const RefGuides& guides,
                  const FilterOptions& opt, RefStats* stats,
                  RefImage* diagnostics)
{
    if (z.nch < 3 || La.nch < 3 || La.w != z.w || La.h != z.h)
        throw std::invalid_argument("regression_filter: bad inputs");
    Filter f(z, La, guides, opt);
    const RefImage out = opt.core ? f.run_box(stats) : f.run(stats, diagnostics);
    return opt.energy_radius > 0 ? correct_energy(z, out, La, opt) : out;
}

RefImage
denoise(const RefImage& L, const RefImage& La, const RefGuides& guides,
        const FilterOptions& opt, RefStats* stats)
{
    RefImage z  = demodulate(L, La, opt.albedo_eps);
    RefImage zf = regression_filter(z, La, guides, opt, stats);
    return bound_highlights(remodulate(zf, La, opt.albedo_eps), L);
}


RefImage
prefilter_albedo(const RefImage& A, int samples, const RefImage* half_a,
                 const RefImage* half_b)
{
    // Section 12, in double, one pixel at a time.
    const int w = A.w, h = A.h;
    auto finite = [&](int x, int y, int c) { return std::isfinite(A.at(x, y, c)); };
    // the coverage variance of each value (NaN where not finite)
    RefImage V(w, h, 3, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                if (!finite(x, y, c)) {
                    V.at(x, y, c) = std::numeric_limits<float>::quiet_NaN();
                    continue;
                }
                double lo = A.at(x, y, c), hi = lo;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx)
                        if (A.inside(x + dx, y + dy) && finite(x + dx, y + dy, c)) {
                            lo = std::min(lo, double(A.at(x + dx, y + dy, c)));
                            hi = std::max(hi, double(A.at(x + dx, y + dy, c)));
                        }
                const double range = hi - lo;
                const double t     = range > 1e-6 ? (A.at(x, y, c) - lo) / range : 0.0;
                V.at(x, y, c) = float(range * range * t * (1.0 - t) / std::pow(samples, 1.5));
            }
    // the halves' variance, the 3x3 mean of (a - b)^2 / 4 over finite
    // values, where it is larger
    if (half_a)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    double sum = 0.0;
                    int n      = 0;
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            if (!A.inside(x + dx, y + dy))
                                continue;
                            const double diff = double(half_a->at(x + dx, y + dy, c))
                                                - half_b->at(x + dx, y + dy, c);
                            if (std::isfinite(diff)) {
                                sum += 0.25 * diff * diff;
                                ++n;
                            }
                        }
                    if (n && std::isfinite(V.at(x, y, c)))
                        V.at(x, y, c) = std::max(V.at(x, y, c), float(sum / n));
                }
    // d(p, q): mean over channels of ((A_p - A_q)^2 - (V_p + min(V_p, V_q)))
    // / (1e-10 + V_p + V_q); undefined (NaN) if a value is not finite
    auto d = [&](int px, int py, int qx, int qy) {
        double sum = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double diff = double(A.at(px, py, c)) - A.at(qx, qy, c);
            const double vp = V.at(px, py, c), vq = V.at(qx, qy, c);
            sum += (diff * diff - (vp + std::min(vp, vq))) / (1e-10 + vp + vq);
        }
        return sum / 3.0;
    };
    RefImage out = A;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            // only where the 3x3 is not flat
            bool flat = true;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                    for (int c = 0; c < 3; ++c)
                        if (A.inside(x + dx, y + dy)
                            && !(A.at(x + dx, y + dy, c) == A.at(x, y, c)))
                            flat = false;
            if (flat)
                continue;
            double acc[3] = { 0, 0, 0 }, wsum = 0.0;
            for (int oy = -3; oy <= 3; ++oy)
                for (int ox = -3; ox <= 3; ++ox) {
                    const int qx = x + ox, qy = y + oy;
                    if (!A.inside(qx, qy) || std::isnan(d(x, y, qx, qy)))
                        continue;
                    // the patch: the defined d(p + o, q + o) with p + o in
                    // the image and q + o too
                    double sum = 0.0;
                    int n      = 0;
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            if (!A.inside(x + dx, y + dy) || !A.inside(qx + dx, qy + dy))
                                continue;
                            const double dd = d(x + dx, y + dy, qx + dx, qy + dy);
                            if (!std::isnan(dd)) {
                                sum += dd;
                                ++n;
                            }
                        }
                    const double wq = std::exp(-std::max(sum / n, 0.0));
                    for (int c = 0; c < 3; ++c)
                        acc[c] += wq * A.at(qx, qy, c);
                    wsum += wq;
                }
            for (int c = 0; c < 3; ++c)
                if (finite(x, y, c) && wsum > 0.0)
                    out.at(x, y, c) = float(acc[c] / wsum);
        }
    return out;
}

}  // namespace zdenoise_ref
