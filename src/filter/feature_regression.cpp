// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// feature_regression(): the second candidate filter of the selection
// (docs/FILTER.md section 13.2), after Bitterli et al. 2016 (NFOR): in each
// window a first-order weighted least-squares fit of the quotient on the
// features, with patch weights on a pilot estimate, splatted with the same
// weights. Stages, in order:
//   decode_points()   planes of z, pilot, guides and validity over the region
//   window_weights()  one centre's patch weights (feature_regression_kernels)
//   window_sums()     its normal equations (likewise)
//   solve_window()    ridge, Cholesky, M^-1 and beta, in double
//   window_splat()    its predictions, clamped, and its hat diagonal
//                     (feature_regression_kernels), added to the sums
//   the last loop     acc / wsum and hsum / wsum per output pixel

#include <zdenoise/selection.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include <OpenImageIO/imagebufalgo_util.h>

#include "feature_regression_kernels.h"
#include "filter_inputs.h"
#include "checks.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;
using namespace detail;

namespace {

/// The region's planes (FeaturePlanes points into them), row-major, each
/// with kFeaturePlanePadding zeros after its last pixel.
struct Points {
    ROI region;
    int width = 0;
    int patch_radius = 0;
    bool has_normal = false, has_depth = false;
    std::vector<float> quotient;  ///< as read, 3 a pixel: what passes through
    std::vector<float> valid, z[3], radiance[3], inv_scale[3], normal[3], invdepth;
    std::vector<uint32_t> id;
    std::vector<float> pilot_l, pilot_v, pilot_in;  ///< grown by patch_radius
    size_t index(int x, int y) const
    {
        return size_t(y - region.ybegin) * size_t(width)
               + size_t(x - region.xbegin);
    }
    FeaturePlanes planes() const
    {
        FeaturePlanes p;
        p.width = width;
        p.valid = valid.data();
        p.id    = id.empty() ? nullptr : id.data();
        for (int c = 0; c < 3; ++c) {
            p.z[c]         = z[c].data();
            p.radiance[c]  = radiance[c].data();
            p.inv_scale[c] = inv_scale[c].data();
            p.normal[c]    = has_normal ? normal[c].data() : nullptr;
        }
        p.invdepth    = has_depth ? invdepth.data() : nullptr;
        p.pilot_l     = pilot_l.data();
        p.pilot_v     = pilot_v.data();
        p.pilot_in    = pilot_in.data();
        p.pilot_width = width + 2 * patch_radius;
        return p;
    }
};

Points
decode_points(const ImageBuf& quotient, const ImageBuf& albedo,
              const ImageBuf& pilot, const Guides& guides, const ROI& region,
              float albedo_eps, int patch_radius)
{
    Points p;
    p.region = region;
    p.width  = region.width();
    p.patch_radius = patch_radius;
    p.has_normal = guides.normal != nullptr;
    p.has_depth = guides.depth != nullptr;
    const size_t npix = region.npixels(), padded = npix + kFeaturePlanePadding;
    p.quotient = detail::read_channels(quotient, region, 0, 3);
    const std::vector<float>& zq = p.quotient;
    const std::vector<float> al = detail::read_channels(albedo, region, 0, 3);
    const std::vector<float> pl = detail::read_channels(pilot, region, 0, 4);
    std::vector<float> depth, normal;
    if (guides.depth)
        depth = detail::read_channels(*guides.depth, region, 0, 1);
    if (guides.normal)
        normal = detail::read_channels(*guides.normal, region, 0, 3);
    p.valid.assign(padded, 0.0f);
    for (int c = 0; c < 3; ++c) {
        p.z[c].assign(padded, 0.0f);
        p.radiance[c].assign(padded, 0.0f);
        p.inv_scale[c].assign(padded, 0.0f);
        if (p.has_normal)
            p.normal[c].assign(padded, 0.0f);
    }
    if (p.has_depth)
        p.invdepth.assign(padded, 0.0f);
    if (guides.object_id) {
        const std::vector<float> ids = detail::read_channels(*guides.object_id, region, 0, 1);
        p.id.assign(padded, 0u);
        std::memcpy(p.id.data(), ids.data(), npix * 4);
    }
    const int pr = patch_radius, pw = p.width + 2 * pr;
    const size_t npilot = size_t(pw) * size_t(region.height() + 2 * pr);
    p.pilot_l.assign(npilot + kFeaturePlanePadding, 0.0f);
    p.pilot_v.assign(npilot + kFeaturePlanePadding, 0.0f);
    p.pilot_in.assign(npilot + kFeaturePlanePadding, 0.0f);
    for (size_t i = 0; i < npix; ++i) {
        const float* pi = &pl[4 * i];
        const size_t pj = (i / size_t(p.width) + size_t(pr)) * size_t(pw)
                          + i % size_t(p.width) + size_t(pr);
        const float l = detail::luminance(pi);
        p.pilot_l[pj]  = l;
        p.pilot_v[pj]  = std::isfinite(pi[3]) && pi[3] > 0.0f ? pi[3] : 0.0f;
        p.pilot_in[pj] = 1.0f;
        bool ok = std::isfinite(l);
        float scale[3];
        for (int c = 0; c < 3; ++c) {
            scale[c] = al[3 * i + c] + albedo_eps;
            ok = ok && std::isfinite(zq[3 * i + c])
                 && std::fabs(zq[3 * i + c]) < detail::kLargestFitQuotient
                 && scale[c] > 0.0f && std::isfinite(scale[c]);
        }
        float invd = 0.0f;
        if (!depth.empty()) {
            const float d = depth[i];
            if (d > 0.0f && d < 1e9f && std::isfinite(d))
                invd = 1.0f / d;
            else
                ok = false;
        }
        if (!ok)
            continue;  // every plane stays 0: the point takes no part
        p.valid[i] = 1.0f;
        for (int c = 0; c < 3; ++c) {
            p.z[c][i]         = zq[3 * i + c];
            p.radiance[c][i]  = zq[3 * i + c] * scale[c];
            p.inv_scale[c][i] = 1.0f / scale[c];
        }
        if (p.has_depth)
            p.invdepth[i] = invd;
        if (p.has_normal) {
            const float* n = &normal[3 * i];
            const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (len >= 1e-6f && std::isfinite(len))
                for (int c = 0; c < 3; ++c)
                    p.normal[c][i] = n[c] / len;
        }
    }
    return p;
}

/// One lattice row's scratch: a window's weights and splat, rows of
/// row_stride.
struct WindowScratch {
    int row_stride = 0;
    std::vector<float> weight, splat[kSplatPlanes];
    explicit WindowScratch(int radius)
    {
        const int side = 2 * radius + 1;
        row_stride = (side + kFeaturePlanePadding - 1) / kFeaturePlanePadding
                         * kFeaturePlanePadding + kFeaturePlanePadding;
        const size_t n = size_t(side) * size_t(row_stride);
        weight.assign(n, 0.0f);
        for (auto& plane : splat)
            plane.assign(n, 0.0f);
    }
};

/// The window centred on (x0, y0), clipped to the region.
WindowExtent
window_extent(const Points& p, int x0, int y0, int r, int row_stride)
{
    const ROI& g = p.region;
    WindowExtent e;
    e.x0 = x0 - g.xbegin, e.y0 = y0 - g.ybegin, e.radius = r;
    e.xlo = std::max(x0 - r, g.xbegin) - g.xbegin;
    e.xhi = std::min(x0 + r, g.xend - 1) - g.xbegin;
    e.ylo = std::max(y0 - r, g.ybegin) - g.ybegin;
    e.yhi = std::min(y0 + r, g.yend - 1) - g.ybegin;
    e.centre = p.index(x0, y0);
    e.row_stride = row_stride;
    return e;
}

/// The centre's patch offsets that lie in the region, as shifts in the
/// pilot planes.
void
centre_patch(const Points& p, int x0, int y0, CentrePatch& patch)
{
    const int pr = p.patch_radius, pw = p.width + 2 * pr;
    patch.count = 0;
    for (int ty = -pr; ty <= pr; ++ty)
        for (int tx = -pr; tx <= pr; ++tx) {
            if (!p.region.contains(x0 + tx, y0 + ty))
                continue;
            const size_t i = p.index(x0 + tx, y0 + ty);
            const size_t pj = (i / size_t(p.width) + size_t(pr)) * size_t(pw)
                              + i % size_t(p.width) + size_t(pr);
            patch.shift[patch.count] = ptrdiff_t(ty) * pw + tx;
            patch.l[patch.count]     = p.pilot_l[pj];
            patch.v[patch.count]     = p.pilot_v[pj];
            ++patch.count;
        }
}

/// Solve one window's normal equations over the features it has
/// (present[0..nf)) in double: ridge, Cholesky, M^-1 as a quadratic form
/// and beta; false when M is not positive definite.
bool
solve_window(const WindowSums& s, const int* present, int nf, float ridge,
             WindowSolution& out)
{
    double M[kWindowFeatures][kWindowFeatures] = {};
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b <= a; ++b)
            M[a][b] = s.m[present[a]][present[b]];
    // Ridge on the non-constant features relative to the window's weight:
    // the features are O(1) where they vary (dx/r, normal differences,
    // relative inverse depth), so a feature that varies by less than
    // sqrt(ridge) over the window (a flat depth, a constant normal) is
    // not fitted to the noise, and a constant one (zero column) stays
    // solvable.
    for (int a = 1; a < nf; ++a)
        M[a][a] += ridge * M[0][0];
    // Cholesky M = L L^T (lower triangle).
    double L[kWindowFeatures][kWindowFeatures] = {};
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b <= a; ++b) {
            double t = M[a][b];
            for (int k = 0; k < b; ++k)
                t -= L[a][k] * L[b][k];
            if (a == b) {
                if (!(t > 0.0))
                    return false;
                L[a][a] = std::sqrt(t);
            } else {
                L[a][b] = t / L[b][b];
            }
        }
    // M^-1 = L^-T L^-1, from the lower triangle L^-1.
    double Li[kWindowFeatures][kWindowFeatures] = {};
    for (int a = 0; a < nf; ++a) {
        Li[a][a] = 1.0 / L[a][a];
        for (int b = 0; b < a; ++b) {
            double t = 0.0;
            for (int k = b; k < a; ++k)
                t -= L[a][k] * Li[k][b];
            Li[a][b] = t / L[a][a];
        }
    }
    std::memset(&out.inverse, 0, sizeof(out.inverse));
    std::memset(&out.beta, 0, sizeof(out.beta));
    for (int a = 0; a < nf; ++a)
        for (int b = 0; b <= a; ++b) {
            double m = 0.0;
            for (int k = a; k < nf; ++k)
                m += Li[k][a] * Li[k][b];
            out.inverse[present[a]][present[b]] = float(a == b ? m : 2.0 * m);
        }
    // beta = M^-1 B: forward then backward substitution.
    for (int c = 0; c < 3; ++c) {
        double t[kWindowFeatures], beta[kWindowFeatures];
        for (int a = 0; a < nf; ++a) {
            double v = s.b[present[a]][c];
            for (int k = 0; k < a; ++k)
                v -= L[a][k] * t[k];
            t[a] = v / L[a][a];
        }
        for (int a = nf - 1; a >= 0; --a) {
            double v = t[a];
            for (int k = a + 1; k < nf; ++k)
                v -= L[k][a] * beta[k];
            beta[a] = v / L[a][a];
        }
        for (int a = 0; a < nf; ++a)
            out.beta[present[a]][c] = float(beta[a]);
    }
    for (int c = 0; c < 3; ++c)
        out.lo[c] = s.lo[c], out.hi[c] = s.hi[c];
    return true;
}

/// The output pixels' sums: s P per channel, s, s h.
struct Sums {
    std::vector<double> acc[3], wsum, hsum;
    explicit Sums(size_t n) : wsum(n, 0.0), hsum(n, 0.0)
    {
        for (auto& a : acc)
            a.assign(n, 0.0);
    }
};

/// Fit the window centred on (x0, y0) and splat it onto the pixels of roi
/// it covers; nothing when its centre takes no part or its normal matrix
/// is singular.
void
fit_and_splat(const Points& p, const FeaturePlanes& planes,
              const FeatureRegressionOptions& o, const ROI& roi, int x0,
              int y0, WindowScratch& scratch, CentrePatch& patch, Sums& s)
{
    const size_t i0 = p.index(x0, y0);
    if (!(p.valid[i0] > 0.0f))
        return;
    const WindowExtent e = window_extent(p, x0, y0, o.radius, scratch.row_stride);
    centre_patch(p, x0, y0, patch);
    window_weights(planes, e, patch, o.patch_k, scratch.weight.data());
    WindowSums sums;
    for (int c = 0; c < 3; ++c)
        sums.lo[c] = sums.hi[c] = p.radiance[c][i0];
    window_sums(planes, e, scratch.weight.data(), sums);
    int present[kWindowFeatures] = { 0, 1, 2 }, nf = 3;
    if (p.has_normal)
        present[nf++] = 3, present[nf++] = 4, present[nf++] = 5;
    if (p.has_depth)
        present[nf++] = 6;
    WindowSolution fit;
    if (!solve_window(sums, present, nf, o.ridge, fit))
        return;
    float* const splat[kSplatPlanes] = { scratch.splat[0].data(), scratch.splat[1].data(),
                                         scratch.splat[2].data(), scratch.splat[3].data(),
                                         scratch.splat[4].data() };
    window_splat(planes, e, scratch.weight.data(), fit, splat);
    // Add the points inside roi to its pixels' sums, in window order.
    const ROI& g = p.region;
    const int xlo = std::max(e.xlo + g.xbegin, roi.xbegin), xhi = std::min(e.xhi + g.xbegin, roi.xend - 1);
    const int ylo = std::max(e.ylo + g.ybegin, roi.ybegin), yhi = std::min(e.yhi + g.ybegin, roi.yend - 1);
    for (int y = ylo; y <= yhi; ++y) {
        const size_t k = size_t(y - g.ybegin - e.ylo) * size_t(e.row_stride)
                         + size_t(xlo - g.xbegin - e.xlo);
        const size_t out = size_t(y - roi.ybegin) * size_t(roi.width())
                           + size_t(xlo - roi.xbegin);
        const int n = xhi - xlo + 1;
        for (int c = 0; c < 3; ++c) {
            const float* __restrict from = splat[kSplatR + c] + k;
            double* __restrict to = s.acc[c].data() + out;
            for (int q = 0; q < n; ++q)
                to[q] += double(from[q]);
        }
        const float* __restrict w = splat[kSplatWeight] + k;
        const float* __restrict h = splat[kSplatHat] + k;
        double* __restrict ws = s.wsum.data() + out;
        double* __restrict hs = s.hsum.data() + out;
        for (int q = 0; q < n; ++q) {
            ws[q] += double(w[q]);
            hs[q] += double(h[q]);
        }
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
    const bool dst_was_given = dst.initialized();
    if (detail::cancel_requested(options.cancel))
        return detail::cancelled(dst, dst_was_given, roi, nthreads);
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
                                   o.albedo_eps, o.patch_radius);
    if (detail::cancel_requested(o.cancel))
        return detail::cancelled(dst, dst_was_given, roi, nthreads);
    const FeaturePlanes planes = p.planes();
    // Windows clip at the frame, whose part held here is the region
    // (window_extent()).
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
            // Cancelled: every remaining row returns at once.
            if (detail::cancel_requested(o.cancel))
                return;
            const int y0 = rows[size_t(k)];
            WindowScratch scratch(r);
            CentrePatch patch;
            for (int x0 = cx0; x0 <= cx1; x0 += s)
                fit_and_splat(p, planes, o, roi, x0, y0, scratch, patch, sums);
        }, detail::paropt_any_length(nthreads));
    }
    if (detail::cancel_requested(o.cancel))
        return detail::cancelled(dst, dst_was_given, roi, nthreads);
    const size_t nout = roi.npixels();
    std::vector<float> out(4 * nout);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t o_ = size_t(y - roi.ybegin) * size_t(roi.width())
                              + size_t(x - roi.xbegin);
            const size_t i = p.index(x, y);
            float* d       = &out[4 * o_];
            if (p.valid[i] > 0.0f && sums.wsum[o_] > 0.0) {
                for (int c = 0; c < 3; ++c)
                    d[c] = float(sums.acc[c][o_] / sums.wsum[o_]);
                d[3] = float(sums.hsum[o_] / sums.wsum[o_]);
            } else {
                for (int c = 0; c < 3; ++c)
                    d[c] = std::isfinite(p.quotient[3 * i + c]) ? p.quotient[3 * i + c] : 0.0f;
                d[3] = 1.0f;
            }
        }
    if (!dst.set_pixels(roi, TypeFloat, out.data()))
        return dst.errorfmt("{}: could not store the result", opname), false;
    return true;
}

}  // namespace zdenoise
