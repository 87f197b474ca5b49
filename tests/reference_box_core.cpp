// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The box core, written plainly (docs/FILTER.md section 15): sums point by
// point, Gaussian elimination instead of Cholesky, splats window by
// window, cells' windows and splats cell by cell.

#include "reference_box_core.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace zdenoise_ref {

namespace {

constexpr int K = 7;  // 1, x, y, normal, log(1 / depth)
constexpr double kRidge[K] = { 0.0, 1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-6 };
constexpr double LW[3] = { 0.2126, 0.7152, 0.0722 };

struct Candidate {
    int radius = 0;
    std::vector<double> rgb, hat;  // NaN where no window reaches
};

void
features(const BoxInputs& in, int x, int y, double f[K])
{
    const size_t i = size_t(y) * in.w + x;
    f[0] = 1.0, f[1] = x, f[2] = y;
    for (int c = 0; c < 3; ++c)
        f[3 + c] = in.normal[3 * i + c];
    f[6] = in.invdepth[i] > 0.0 ? std::log(in.invdepth[i]) : 0.0;
}

/// One window's fit over the pixels [xa, xb) x [ya, yb) (clipped to the
/// image): beta (3 x K, global features), its weight and mean leverage;
/// false when it has fewer than 3 points.
bool
fit_window(const BoxInputs& in, int xa, int xb, int ya, int yb, double beta[3][K],
           double& weight, double& leverage)
{
    double n = 0, sf[K] = {}, sff[K][K] = {}, sfz[K][3] = {}, szz = 0;
    for (int y = std::max(ya, 0); y < std::min(yb, in.h); ++y)
        for (int x = std::max(xa, 0); x < std::min(xb, in.w); ++x) {
            const size_t i = size_t(y) * in.w + x;
            if (!in.fit[i])
                continue;
            double f[K];
            features(in, x, y, f);
            n += 1;
            for (int j = 0; j < K; ++j) {
                sf[j] += f[j];
                for (int k = 0; k < K; ++k)
                    sff[j][k] += f[j] * f[k];
                for (int c = 0; c < 3; ++c)
                    sfz[j][c] += f[j] * in.z[3 * i + c];
            }
            szz += in.zl[i] * in.zl[i];
        }
    if (n < 3)
        return false;
    constexpr int m = K - 1;
    double a[m][m + 3], mean[K], zmean[3];
    for (int j = 0; j < K; ++j)
        mean[j] = sf[j] / n;
    for (int c = 0; c < 3; ++c)
        zmean[c] = sfz[0][c] / n;
    double dof = 1.0;
    for (int j = 0; j < m; ++j) {
        for (int k = 0; k < m; ++k)
            a[j][k] = sff[j + 1][k + 1] - n * mean[j + 1] * mean[k + 1];
        const double ridge = n * kRidge[j + 1] + 1e-12;
        if (a[j][j] > 0)
            dof += a[j][j] / (a[j][j] + ridge);
        a[j][j] += ridge;
        for (int c = 0; c < 3; ++c)
            a[j][m + c] = sfz[j + 1][c] - n * mean[j + 1] * zmean[c];
    }
    double g[m][3];
    for (int j = 0; j < m; ++j)
        for (int c = 0; c < 3; ++c)
            g[j][c] = a[j][m + c];
    // Gaussian elimination (the matrix is symmetric positive definite).
    for (int p = 0; p < m; ++p)
        for (int j = p + 1; j < m; ++j) {
            const double factor = a[j][p] / a[p][p];
            for (int k = p; k < m + 3; ++k)
                a[j][k] -= factor * a[p][k];
        }
    double t[m][3];
    for (int j = m - 1; j >= 0; --j)
        for (int c = 0; c < 3; ++c) {
            double v = a[j][m + c];
            for (int k = j + 1; k < m; ++k)
                v -= a[j][k] * t[k][c];
            t[j][c] = v / a[j][j];
        }
    double zl = 0, explained = 0;
    for (int c = 0; c < 3; ++c) {
        beta[c][0] = zmean[c];
        for (int j = 0; j < m; ++j) {
            beta[c][j + 1] = t[j][c];
            beta[c][0] -= t[j][c] * mean[j + 1];
        }
        zl += LW[c] * zmean[c];
    }
    for (int j = 0; j < m; ++j) {
        double bl = 0, gl = 0;
        for (int c = 0; c < 3; ++c)
            bl += LW[c] * t[j][c], gl += LW[c] * g[j][c];
        explained += bl * gl;
    }
    const double rss = szz - n * zl * zl - explained;
    const double resid = std::max(rss, 0.0) / std::max(n - dof, 1.0) / (zl * zl + 1e-8);
    weight   = 1.0 / (resid + 1e-3);
    leverage = dof / n;
    return true;
}

constexpr int kSplat = 3 * K + 2;  // w beta, w K/n, w

/// Add a window's fit to the splat sums `p` (kSplat values).
void
add_fit(double* p, const double beta[3][K], double weight, double leverage)
{
    for (int c = 0; c < 3; ++c)
        for (int j = 0; j < K; ++j)
            p[c * K + j] += weight * beta[c][j];
    p[3 * K] += weight * leverage;
    p[3 * K + 1] += weight;
}

/// The light and hat diagonal at (x, y) from splat sums p.
void
read_light(const BoxInputs& in, int x, int y, const double* p, Candidate& cand)
{
    const size_t i = size_t(y) * in.w + x;
    if (!(p[3 * K + 1] > 0))
        return;
    double f[K];
    features(in, x, y, f);
    for (int c = 0; c < 3; ++c) {
        double v = 0;
        for (int j = 0; j < K; ++j)
            v += f[j] * p[c * K + j];
        cand.rgb[3 * i + c] = v / p[3 * K + 1];
    }
    cand.hat[i] = p[3 * K] / p[3 * K + 1];
}

/// Radii up to 4: a window of (2r+1)^2 pixels at every pixel, each pixel
/// the sum of the windows holding it.
void
pixel_candidate(const BoxInputs& in, int r, Candidate& cand)
{
    const size_t np = size_t(in.w) * in.h;
    std::vector<double> sum(np * kSplat, 0.0);
    for (int y0 = 0; y0 < in.h; ++y0)
        for (int x0 = 0; x0 < in.w; ++x0) {
            double beta[3][K], weight, leverage;
            if (!fit_window(in, x0 - r, x0 + r + 1, y0 - r, y0 + r + 1, beta, weight, leverage))
                continue;
            for (int y = std::max(y0 - r, 0); y <= std::min(y0 + r, in.h - 1); ++y)
                for (int x = std::max(x0 - r, 0); x <= std::min(x0 + r, in.w - 1); ++x)
                    add_fit(&sum[(size_t(y) * in.w + x) * kSplat], beta, weight, leverage);
        }
    for (int y = 0; y < in.h; ++y)
        for (int x = 0; x < in.w; ++x)
            read_light(in, x, y, &sum[(size_t(y) * in.w + x) * kSplat], cand);
}

/// Larger radii: cells of s = r / 4 pixels from the image's origin; a
/// window of 9 x 9 cells at every cell; each cell the sum of the windows
/// within 4 cells; each pixel those sums interpolated bilinearly between
/// the four nearest cell centres (indices clamped to the image's cells).
void
cell_candidate(const BoxInputs& in, int r, Candidate& cand)
{
    const int s = r / 4, R = 4;
    const int nx = (in.w + s - 1) / s, ny = (in.h + s - 1) / s;
    std::vector<double> fits(size_t(nx) * ny * kSplat, 0.0);
    for (int J = 0; J < ny; ++J)
        for (int I = 0; I < nx; ++I) {
            double beta[3][K], weight, leverage;
            if (fit_window(in, (I - R) * s, (I + R + 1) * s, (J - R) * s, (J + R + 1) * s,
                           beta, weight, leverage))
                add_fit(&fits[(size_t(J) * nx + I) * kSplat], beta, weight, leverage);
        }
    std::vector<double> cell(fits.size(), 0.0);
    for (int J = 0; J < ny; ++J)
        for (int I = 0; I < nx; ++I)
            for (int v = std::max(J - R, 0); v <= std::min(J + R, ny - 1); ++v)
                for (int u = std::max(I - R, 0); u <= std::min(I + R, nx - 1); ++u)
                    for (int k = 0; k < kSplat; ++k)
                        cell[(size_t(J) * nx + I) * kSplat + k]
                            += fits[(size_t(v) * nx + u) * kSplat + k];
    auto axis = [&](int p, int n, int& a, int& b, double& t) {
        const double u = (p + 0.5) / s - 0.5;
        const int lo   = int(std::floor(u));
        t = u - lo;
        a = std::clamp(lo, 0, n - 1);
        b = std::clamp(lo + 1, 0, n - 1);
    };
    for (int y = 0; y < in.h; ++y)
        for (int x = 0; x < in.w; ++x) {
            int i0, i1, j0, j1;
            double tx, ty;
            axis(x, nx, i0, i1, tx);
            axis(y, ny, j0, j1, ty);
            double p[kSplat];
            for (int k = 0; k < kSplat; ++k) {
                auto at = [&](int I, int J) { return cell[(size_t(J) * nx + I) * kSplat + k]; };
                p[k] = (1 - ty) * ((1 - tx) * at(i0, j0) + tx * at(i1, j0))
                       + ty * ((1 - tx) * at(i0, j1) + tx * at(i1, j1));
            }
            read_light(in, x, y, p, cand);
        }
}

Candidate
radius_candidate(const BoxInputs& in, int r)
{
    Candidate cand;
    cand.radius = r;
    cand.rgb.assign(3 * size_t(in.w) * in.h, NAN);
    cand.hat.assign(size_t(in.w) * in.h, NAN);
    if (r <= 4)
        pixel_candidate(in, r, cand);
    else
        cell_candidate(in, r, cand);
    return cand;
}

double
lum(const double* rgb)
{
    return LW[0] * rgb[0] + LW[1] * rgb[1] + LW[2] * rgb[2];
}

}  // namespace


void
box_core_light(const BoxInputs& in, const zdenoise::FilterOptions& opt,
               std::vector<double>& acc, std::vector<double>& wsum)
{
    const size_t np = size_t(in.w) * in.h;
    std::vector<Candidate> cands(1);
    cands[0].rgb = in.z;
    cands[0].hat.assign(np, 1.0);
    std::vector<int> radii;
    for (int r = 1; r < opt.box_radius; r *= 2)
        radii.push_back(r);
    radii.push_back(opt.box_radius);
    int guide = 1;
    for (size_t j = 0; j < radii.size(); ++j) {
        cands.push_back(radius_candidate(in, radii[j]));
        if (radii[j] <= 8)
            guide = int(j) + 1;
    }
    const int nc = int(cands.size());
    const Candidate& ref = cands[1];
    auto finite3 = [](const double* v) {
        return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
    };
    // The noise: radius 1's squared residuals over 1 - D, 5x5, at fit points.
    std::vector<double> v(np, 0.0);
    for (int y = 0; y < in.h; ++y)
        for (int x = 0; x < in.w; ++x) {
            double num = 0, den = 0;
            for (int b = std::max(y - 2, 0); b <= std::min(y + 2, in.h - 1); ++b)
                for (int a = std::max(x - 2, 0); a <= std::min(x + 2, in.w - 1); ++a) {
                    const size_t j = size_t(b) * in.w + a;
                    const double l = lum(&ref.rgb[3 * j]);
                    if (!in.fit[j] || !std::isfinite(l))
                        continue;
                    num += (in.zl[j] - l) * (in.zl[j] - l);
                    den += 1.0 - ref.hat[j];
                }
            v[size_t(y) * in.w + x] = num / std::max(den, 1e-9);
        }
    // Each candidate's risk against radius 1, the reference's own, the guide.
    std::vector<std::vector<double>> risk(size_t(nc) + 1, std::vector<double>(np, 0.0));
    std::vector<double> g(np), gv(np);
    for (size_t i = 0; i < np; ++i) {
        const double gl = lum(&cands[size_t(guide)].rgb[3 * i]);
        const double gvar = v[i] * cands[size_t(guide)].hat[i];
        g[i]  = std::isfinite(gl) ? gl : 0.0;
        gv[i] = (std::isfinite(gvar) ? gvar : 0.0) + 1e-12;
        if (!in.fit[i])
            continue;
        double a = 0;
        for (int c = 0; c < 3; ++c)
            a += LW[c] * (in.albedo[3 * i + c] > 0 ? in.albedo[3 * i + c] : 1.0);
        const double light = std::isfinite(gl) ? std::max(gl, 0.0) : in.zl[i];
        const double wl = a * a / (a * a * light * light + 1e-2);
        const double l1 = lum(&ref.rgb[3 * i]), d1 = ref.hat[i];
        for (int k = 0; k < nc; ++k) {
            const double lk = lum(&cands[size_t(k)].rgb[3 * i]), dk = cands[size_t(k)].hat[i];
            const double s = ((lk - l1) * (lk - l1) - v[i] * std::abs(dk - d1) + v[i] * dk) * wl;
            risk[size_t(k)][i] = std::isfinite(s) ? s : 1e30;
        }
        const double own = v[i] * d1 * wl;
        risk[size_t(nc)][i] = std::isfinite(own) ? own : 0.0;
    }
    // Pooled over the 11x11 of the same light; the candidates blended.
    acc.assign(3 * np, 0.0);
    wsum.assign(np, 0.0);
    for (int y = 0; y < in.h; ++y)
        for (int x = 0; x < in.w; ++x) {
            const size_t p = size_t(y) * in.w + x;
            std::vector<double> pooled(size_t(nc) + 1, 0.0);
            for (int b = std::max(y - 5, 0); b <= std::min(y + 5, in.h - 1); ++b)
                for (int a = std::max(x - 5, 0); a <= std::min(x + 5, in.w - 1); ++a) {
                    const size_t q = size_t(b) * in.w + a;
                    const double w = std::exp(-(g[q] - g[p]) * (g[q] - g[p]) / (4.0 * (gv[p] + gv[q])));
                    for (int k = 0; k <= nc; ++k)
                        pooled[size_t(k)] += w * risk[size_t(k)][q];
                }
            double least = std::numeric_limits<double>::infinity();
            for (int k = 0; k < nc; ++k)
                if (finite3(&cands[size_t(k)].rgb[3 * p]))
                    least = std::min(least, pooled[size_t(k)]);
            if (least == std::numeric_limits<double>::infinity())
                continue;
            double sum = 0;
            for (int k = 0; k < nc; ++k) {
                if (!finite3(&cands[size_t(k)].rgb[3 * p]))
                    continue;
                const double w = std::exp(-(pooled[size_t(k)] - least) / (0.3 * pooled[size_t(nc)] + 1e-30));
                sum += w;
                for (int c = 0; c < 3; ++c)
                    acc[3 * p + c] += w * cands[size_t(k)].rgb[3 * p + c];
            }
            for (int c = 0; c < 3; ++c)
                acc[3 * p + c] /= sum;
            wsum[p] = 1.0;
        }
}

}  // namespace zdenoise_ref
