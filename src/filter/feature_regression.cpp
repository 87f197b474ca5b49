// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// feature_regression(): the second candidate filter of the selection
// (docs/FILTER.md section 13.2), after Bitterli et al. 2016 (NFOR): in each
// window a first-order weighted least-squares fit of the quotient on the
// features, with patch weights on a pilot estimate, splatted with the same
// weights. Stages, in order:
//   decode_points()   z, pilot, features and validity over the region
//   window_weights()  one centre's patch weights, row by row
//   fit_window()      its normal equations, Cholesky and M^-1
//   splat_window()    its predictions, clamped, and its hat diagonal
//   normalise()       acc / wsum and hsum / wsum per output pixel

#include <zdenoise/selection.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include <OpenImageIO/imagebufalgo_util.h>

#include "filter_inputs.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;

namespace {

constexpr int kMaxFeatures = 7;  ///< 1, dx, dy, normal (3), inverse depth

/// The inputs over the region, row-major.
struct Points {
    ROI region;
    int width = 0;
    int nfeatures = 3;
    std::vector<float> z;        ///< 3 a pixel
    std::vector<float> scale;    ///< La + albedo_eps, 3 a pixel: z to radiance
    std::vector<uint8_t> valid;  ///< takes part in fits
    std::vector<float> pilot_l;  ///< pilot luminance
    std::vector<float> pilot_v;  ///< variance of pilot_l
    std::vector<float> normal;   ///< unit, 3 a pixel (empty: none)
    std::vector<float> invdepth; ///< 1/depth (empty: none)
    std::vector<uint32_t> id;    ///< bits of channel 0 (empty: none)
    size_t index(int x, int y) const
    {
        return size_t(y - region.ybegin) * size_t(width)
               + size_t(x - region.xbegin);
    }
};

Points
decode_points(const ImageBuf& quotient, const ImageBuf& albedo,
              const ImageBuf& pilot, const Guides& guides, const ROI& region,
              float albedo_eps)
{
    Points p;
    p.region = region;
    p.width  = region.width();
    const size_t npix = region.npixels();
    p.z = detail::read_channels(quotient, region, 0, 3);
    p.scale = detail::read_channels(albedo, region, 0, 3);
    for (float& a : p.scale)
        a += albedo_eps;
    const std::vector<float> pl = detail::read_channels(pilot, region, 0, 4);
    p.pilot_l.resize(npix);
    p.pilot_v.resize(npix);
    p.valid.assign(npix, 0);
    std::vector<float> depth;
    if (guides.depth)
        depth = detail::read_channels(*guides.depth, region, 0, 1);
    if (guides.normal) {
        p.normal = detail::read_channels(*guides.normal, region, 0, 3);
        p.nfeatures += 3;
    }
    if (guides.depth) {
        p.invdepth.assign(npix, 0.0f);
        p.nfeatures += 1;
    }
    if (guides.object_id) {
        const std::vector<float> ids = detail::read_channels(*guides.object_id, region, 0, 1);
        p.id.resize(npix);
        std::memcpy(p.id.data(), ids.data(), npix * 4);
    }
    for (size_t i = 0; i < npix; ++i) {
        const float* pi = &pl[4 * i];
        p.pilot_l[i] = detail::luminance(pi);
        p.pilot_v[i] = std::isfinite(pi[3]) && pi[3] > 0.0f ? pi[3] : 0.0f;
        bool ok = std::isfinite(p.pilot_l[i]);
        for (int c = 0; c < 3; ++c)
            ok = ok && std::isfinite(p.z[3 * i + c])
                 && std::fabs(p.z[3 * i + c]) < detail::kLargestFitQuotient
                 && p.scale[3 * i + c] > 0.0f && std::isfinite(p.scale[3 * i + c]);
        if (!p.normal.empty()) {
            float* n = &p.normal[3 * i];
            const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (len >= 1e-6f && std::isfinite(len))
                n[0] /= len, n[1] /= len, n[2] /= len;
            else
                n[0] = n[1] = n[2] = 0.0f;
        }
        if (!depth.empty()) {
            const float d = depth[i];
            if (d > 0.0f && d < 1e9f && std::isfinite(d))
                p.invdepth[i] = 1.0f / d;
            else
                ok = false;
        }
        p.valid[i] = ok;
    }
    return p;
}

/// One window's fit: its centre, the solved coefficients and the Cholesky
/// factor of its normal matrix (for the hat diagonal).
struct WindowFit {
    int x0 = 0, y0 = 0;
    int nf = 0;
    /// The weight of each point of the window, (2 r + 1)^2 in rows: the
    /// fit computes them and the splat reuses them (the patch distances
    /// are most of the work).
    std::vector<float> weight;
    /// Scratch of window_weights(): each point's patch distance sum and
    /// its number of terms.
    std::vector<float> distance, terms;
    double beta[kMaxFeatures][3] = {};
    double chol[kMaxFeatures][kMaxFeatures] = {};
    /// M^-1 as the quadratic form x^T M^-1 x: diagonal, then twice each
    /// off-diagonal entry (a > b); independent products, not the
    /// dependent chain of a triangular solve per splatted point.
    double inverse[kMaxFeatures][kMaxFeatures] = {};
    float lo[3] = {}, hi[3] = {};  ///< range of the radiance of the weighted points
};

/// The features of point j for the window centred on i0, relative to the
/// centre (so that the constant term is the fit's value at the centre).
int
features(const Points& p, size_t i0, size_t j, int dx, int dy, float inv_r,
         double* x)
{
    int n = 0;
    x[n++] = 1.0;
    x[n++] = dx * inv_r;
    x[n++] = dy * inv_r;
    if (!p.normal.empty())
        for (int c = 0; c < 3; ++c)
            x[n++] = double(p.normal[3 * j + c]) - p.normal[3 * i0 + c];
    if (!p.invdepth.empty())
        x[n++] = (double(p.invdepth[j]) - p.invdepth[i0]) / p.invdepth[i0];
    return n;
}

/// The weight of every point of the window centred on (x0, y0) into
/// fit.weight: spatial Gaussian x same id x the patch weight
/// exp(-max(0, d2)), d2 the variance-cancelled distance of the pilot's
/// patches (FILTER.md 13.2). The distance is summed patch offset by patch
/// offset over whole window rows, contiguous points in float lanes (each
/// point's terms in the same order as a point-by-point sum).
void
window_weights(const Points& p, const FeatureRegressionOptions& o,
               const ROI& clip, int x0, int y0, WindowFit& fit)
{
    const int r = o.radius, side = 2 * r + 1, pr = o.patch_radius;
    const ROI& region = p.region;
    const int ylo = std::max(y0 - r, clip.ybegin), yhi = std::min(y0 + r, clip.yend - 1);
    const int xlo = std::max(x0 - r, clip.xbegin), xhi = std::min(x0 + r, clip.xend - 1);
    const size_t n = size_t(side) * size_t(side);
    fit.weight.assign(n, 0.0f);
    fit.distance.assign(n, 0.0f);
    fit.terms.assign(n, 0.0f);
    const float k2 = o.patch_k * o.patch_k;
    auto at = [&](int x, int y) { return size_t(y - y0 + r) * size_t(side) + size_t(x - x0 + r); };
    for (int ty = -pr; ty <= pr; ++ty)
        for (int tx = -pr; tx <= pr; ++tx) {
            const int ax = x0 + tx, ay = y0 + ty;
            if (!region.contains(ax, ay))
                continue;
            const float la = p.pilot_l[p.index(ax, ay)], va = p.pilot_v[p.index(ax, ay)];
            // The points whose patch pixel j + (tx, ty) lies in the region.
            const int ya = std::max(ylo, region.ybegin - ty);
            const int yb = std::min(yhi, region.yend - 1 - ty);
            const int xa = std::max(xlo, region.xbegin - tx);
            const int xb = std::min(xhi, region.xend - 1 - tx);
            for (int y = ya; y <= yb; ++y) {
                const size_t b = p.index(xa + tx, y + ty);
                const float* __restrict pl = &p.pilot_l[b];
                const float* __restrict pv = &p.pilot_v[b];
                float* __restrict d = &fit.distance[at(xa, y)];
                float* __restrict c = &fit.terms[at(xa, y)];
                for (int q = 0; q <= xb - xa; ++q) {
                    const float lb = pl[q], vb = pv[q];
                    const float diff = la - lb;
                    // A 1 % difference is always tolerated: the pilot's own bias.
                    const float floor = 1e-4f * (la * la + lb * lb) + 1e-30f;
                    d[q] += (diff * diff - (va + std::min(va, vb)))
                            / (floor + k2 * (va + vb));
                    c[q] += 1.0f;
                }
            }
        }
    const size_t i0 = p.index(x0, y0);
    const float inv_r2 = 1.0f / float(r * r);
    for (int y = ylo; y <= yhi; ++y)
        for (int x = xlo; x <= xhi; ++x) {
            const size_t j = p.index(x, y), k = at(x, y);
            if (!p.valid[j] || (!p.id.empty() && p.id[j] != p.id[i0]))
                continue;
            const float d2 = fit.terms[k] > 0.0f ? fit.distance[k] / fit.terms[k] : 0.0f;
            const float sp = float((x - x0) * (x - x0) + (y - y0) * (y - y0)) * inv_r2;
            fit.weight[k] = std::exp(-sp - std::max(0.0f, d2));
        }
}

/// Fit the window centred on (x0, y0); false when it has no usable centre.
bool
fit_window(const Points& p, const FeatureRegressionOptions& o,
           const ROI& clip, int x0, int y0, WindowFit& fit)
{
    const size_t i0 = p.index(x0, y0);
    if (!p.valid[i0])
        return false;
    const int r = o.radius, nf = p.nfeatures;
    const float inv_r = 1.0f / float(r);
    double M[kMaxFeatures][kMaxFeatures] = {}, B[kMaxFeatures][3] = {};
    fit.x0 = x0, fit.y0 = y0, fit.nf = nf;
    const int side = 2 * r + 1;
    window_weights(p, o, clip, x0, y0, fit);
    for (int c = 0; c < 3; ++c)
        fit.lo[c] = fit.hi[c] = p.z[3 * i0 + c] * p.scale[3 * i0 + c];
    for (int y = std::max(y0 - r, clip.ybegin); y <= std::min(y0 + r, clip.yend - 1); ++y)
        for (int x = std::max(x0 - r, clip.xbegin); x <= std::min(x0 + r, clip.xend - 1); ++x) {
            const float w = fit.weight[size_t(y - y0 + r) * size_t(side) + size_t(x - x0 + r)];
            if (!(w > 0.0f))
                continue;
            const size_t j = p.index(x, y);
            double f[kMaxFeatures];
            features(p, i0, j, x - x0, y - y0, inv_r, f);
            for (int a = 0; a < nf; ++a) {
                for (int b = 0; b <= a; ++b)
                    M[a][b] += w * f[a] * f[b];
                for (int c = 0; c < 3; ++c)
                    B[a][c] += w * f[a] * p.z[3 * j + c];
            }
            for (int c = 0; c < 3; ++c) {
                const float l = p.z[3 * j + c] * p.scale[3 * j + c];
                fit.lo[c] = std::min(fit.lo[c], l);
                fit.hi[c] = std::max(fit.hi[c], l);
            }
        }
    // Ridge on the non-constant features relative to the window's weight:
    // the features are O(1) where they vary (dx/r, normal differences,
    // relative inverse depth), so a feature that varies by less than
    // sqrt(ridge) over the window (a flat depth, a constant normal) is
    // not fitted to the noise, and a constant one (zero column) stays
    // solvable.
    for (int a = 1; a < nf; ++a)
        M[a][a] += o.ridge * M[0][0];
    // Cholesky M = L L^T, in place in fit.chol (lower triangle).
    auto& L = fit.chol;
    for (int a = 0; a < nf; ++a) {
        for (int b = 0; b <= a; ++b) {
            double s = M[a][b];
            for (int k = 0; k < b; ++k)
                s -= L[a][k] * L[b][k];
            if (a == b) {
                if (!(s > 0.0))
                    return false;
                L[a][a] = std::sqrt(s);
            } else {
                L[a][b] = s / L[b][b];
            }
        }
    }
    // M^-1 = L^-T L^-1, from the lower triangle L^-1.
    double Li[kMaxFeatures][kMaxFeatures] = {};
    for (int a = 0; a < nf; ++a) {
        Li[a][a] = 1.0 / L[a][a];
        for (int b = 0; b < a; ++b) {
            double t = 0.0;
            for (int k = b; k < a; ++k)
                t -= L[a][k] * Li[k][b];
            Li[a][b] = t / L[a][a];
        }
    }
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b <= a; ++b) {
            double m = 0.0;
            for (int k = a; k < nf; ++k)
                m += Li[k][a] * Li[k][b];
            fit.inverse[a][b] = a == b ? m : 2.0 * m;
        }
    // beta = M^-1 B: forward then backward substitution.
    for (int c = 0; c < 3; ++c) {
        double t[kMaxFeatures];
        for (int a = 0; a < nf; ++a) {
            double s = B[a][c];
            for (int k = 0; k < a; ++k)
                s -= L[a][k] * t[k];
            t[a] = s / L[a][a];
        }
        for (int a = nf - 1; a >= 0; --a) {
            double s = t[a];
            for (int k = a + 1; k < nf; ++k)
                s -= L[k][a] * fit.beta[k][c];
            fit.beta[a][c] = s / L[a][a];
        }
    }
    return true;
}

/// The output pixels' sums: s P per channel, s, s h.
struct Sums {
    std::vector<double> acc, wsum, hsum;
    explicit Sums(size_t n) : acc(3 * n, 0.0), wsum(n, 0.0), hsum(n, 0.0) {}
};

/// Splat one fitted window onto the output pixels of roi it covers: the
/// prediction at each point, clamped so that its radiance stays within the
/// range of radiance the window saw (no light beyond what the render has,
/// as section 6 does), with the fit's weight; and the
/// hat diagonal h = w x^T M^-1 x (0 where clamped: the value no longer
/// moves with z there, up to the point attaining the bound).
void
splat_window(const Points& p, const FeatureRegressionOptions& o,
             const ROI& clip, const ROI& roi, const WindowFit& fit, Sums& s)
{
    const int r = o.radius, nf = fit.nf;
    const float inv_r = 1.0f / float(r);
    const size_t i0 = p.index(fit.x0, fit.y0);
    const int ylo = std::max({ fit.y0 - r, clip.ybegin, roi.ybegin });
    const int yhi = std::min({ fit.y0 + r, clip.yend - 1, roi.yend - 1 });
    const int xlo = std::max({ fit.x0 - r, clip.xbegin, roi.xbegin });
    const int xhi = std::min({ fit.x0 + r, clip.xend - 1, roi.xend - 1 });
    for (int y = ylo; y <= yhi; ++y)
        for (int x = xlo; x <= xhi; ++x) {
            const float w = fit.weight[size_t(y - fit.y0 + r) * size_t(2 * r + 1)
                                       + size_t(x - fit.x0 + r)];
            if (!(w > 0.0f))
                continue;
            const size_t j = p.index(x, y);
            double f[kMaxFeatures];
            features(p, i0, j, x - fit.x0, y - fit.y0, inv_r, f);
            double q = 0.0;  // x^T M^-1 x
            for (int a = 0; a < nf; ++a)
                for (int b = 0; b <= a; ++b)
                    q += fit.inverse[a][b] * f[a] * f[b];
            const size_t o_ = size_t(y - roi.ybegin) * size_t(roi.width())
                              + size_t(x - roi.xbegin);
            double hl = 0.0;
            for (int c = 0; c < 3; ++c) {
                double v = 0.0;
                for (int a = 0; a < nf; ++a)
                    v += f[a] * fit.beta[a][c];
                const double a = p.scale[3 * j + c];
                const double clamped = std::min(std::max(v, fit.lo[c] / a),
                                                fit.hi[c] / a);
                if (clamped == v)
                    hl += detail::kLumaWeights[c] * w * q;
                s.acc[3 * o_ + c] += w * clamped;
            }
            s.wsum[o_] += w;
            s.hsum[o_] += w * hl;
        }
}

}  // namespace


int
feature_regression_halo(const FeatureRegressionOptions& o)
{
    // A pixel is splatted by centres up to radius away, whose windows and
    // patch weights reach radius + patch_radius further.
    return 2 * std::max(o.radius, 0) + std::max(o.patch_radius, 0);
}


bool
feature_regression(ImageBuf& dst, const ImageBuf& quotient,
                   const ImageBuf& albedo, const ImageBuf& pilot,
                   const Guides& guides,
                   const FeatureRegressionOptions& options, ROI roi,
                   int nthreads)
{
    const char* opname = "feature_regression";
    FeatureRegressionOptions o = options;
    if (!o.frame.defined())
        o.frame = quotient.roi();
    if (!roi.defined())
        roi = o.frame;
    roi.chbegin = 0;
    roi.chend   = 4;
    if (o.radius < 1 || o.radius > 64)
        return dst.errorfmt("{}: option radius = {} is invalid: needs 1..64",
                            opname, o.radius), false;
    if (o.centre_stride < 1 || o.centre_stride > o.radius)
        return dst.errorfmt("{}: option centre_stride = {} is invalid: needs "
                            "1..radius", opname, o.centre_stride), false;
    if (o.patch_radius < 0 || o.patch_radius > 8)
        return dst.errorfmt("{}: option patch_radius = {} is invalid: needs "
                            "0..8", opname, o.patch_radius), false;
    if (!(o.patch_k > 0.0f) || !std::isfinite(o.patch_k))
        return dst.errorfmt("{}: option patch_k = {} is invalid: needs a "
                            "finite number > 0", opname, o.patch_k), false;
    if (!(o.albedo_eps > 0.0f) || !std::isfinite(o.albedo_eps))
        return dst.errorfmt("{}: option albedo_eps = {} is invalid: needs a "
                            "finite number > 0", opname, o.albedo_eps), false;
    if (!(o.ridge >= 0.0f) || !std::isfinite(o.ridge))
        return dst.errorfmt("{}: option ridge = {} is invalid: needs a finite "
                            "number >= 0", opname, o.ridge), false;
    if (!detail::check_frame(dst, opname, roi, o.frame))
        return false;
    const ROI region = detail::halo_region(roi, o.frame, feature_regression_halo(o));
    if (!detail::check_input(dst, quotient, opname, "quotient", region, 3)
        || !detail::check_input(dst, albedo, opname, "albedo", region, 3)
        || !detail::check_input(dst, pilot, opname, "pilot", region, 4))
        return false;
    // Only the geometric guides are read (variance and halves are not).
    Guides read;
    read.normal    = guides.normal;
    read.depth     = guides.depth;
    read.object_id = guides.object_id;
    if (!detail::check_guides(dst, read, opname, region))
        return false;
    static const std::vector<std::string> channels = { "R", "G", "B", "D" };
    if (!detail::prepare_result(dst, dst, roi, o.frame, 4, opname, "the destination",
                                &channels))
        return false;

    const Points p = decode_points(quotient, albedo, pilot, guides, region,
                                   o.albedo_eps);
    // Windows clip at the frame, whose part held here is the region.
    const ROI clip = region;
    // Centres: lattice points (anchored at the frame's origin) whose window
    // reaches roi. Lattice rows a multiple of `phases` apart have disjoint
    // windows, so the rows of one phase run in parallel and every pixel
    // receives its windows in phase order, then left to right: a fixed
    // order for any thread count or part of the frame (section 8).
    const int s = o.centre_stride, r = o.radius;
    auto first_at_or_after = [s](int v, int origin) {
        const int d = v - origin;
        return origin + (d >= 0 ? (d + s - 1) / s : -((-d) / s)) * s;
    };
    const int cy0 = first_at_or_after(std::max(roi.ybegin - r, region.ybegin), o.frame.ybegin);
    const int cx0 = first_at_or_after(std::max(roi.xbegin - r, region.xbegin), o.frame.xbegin);
    const int cy1 = std::min(roi.yend - 1 + r, region.yend - 1);
    const int cx1 = std::min(roi.xend - 1 + r, region.xend - 1);
    const int phases = 2 * r / s + 1;
    Sums sums(roi.npixels());
    std::vector<int> rows;
    for (int phase = 0; phase < phases; ++phase) {
        rows.clear();
        for (int y = cy0; y <= cy1; y += s)
            if (((y - o.frame.ybegin) / s) % phases == phase)
                rows.push_back(y);
        parallel_for(int64_t(0), int64_t(rows.size()), [&](int64_t k) {
            const int y0 = rows[size_t(k)];
            WindowFit fit;
            for (int x0 = cx0; x0 <= cx1; x0 += s)
                if (fit_window(p, o, clip, x0, y0, fit))
                    splat_window(p, o, clip, roi, fit, sums);
        }, detail::paropt_any_length(nthreads));
    }
    const size_t nout = roi.npixels();
    std::vector<float> out(4 * nout);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t o_ = size_t(y - roi.ybegin) * size_t(roi.width())
                              + size_t(x - roi.xbegin);
            const size_t i = p.index(x, y);
            float* d       = &out[4 * o_];
            if (p.valid[i] && sums.wsum[o_] > 0.0) {
                for (int c = 0; c < 3; ++c)
                    d[c] = float(sums.acc[3 * o_ + c] / sums.wsum[o_]);
                d[3] = float(sums.hsum[o_] / sums.wsum[o_]);
            } else {
                for (int c = 0; c < 3; ++c)
                    d[c] = std::isfinite(p.z[3 * i + c]) ? p.z[3 * i + c] : 0.0f;
                d[3] = 1.0f;
            }
        }
    if (!dst.set_pixels(roi, TypeFloat, out.data()))
        return dst.errorfmt("{}: could not store the result", opname), false;
    return true;
}

}  // namespace zdenoise
