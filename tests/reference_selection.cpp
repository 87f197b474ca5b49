// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Reference implementations of the selection stages (reference_selection.h).

#include "reference_selection.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace zdenoise_ref {

namespace {

const double kLuma[3] = { 0.2126f, 0.7152f, 0.0722f };

double
luma(const RefImage& img, int x, int y)
{
    return double(float(kLuma[0]) * img.at(x, y, 0) + float(kLuma[1]) * img.at(x, y, 1)
                  + float(kLuma[2]) * img.at(x, y, 2));
}

/// Section 13.2's point set and features.
struct Features {
    const RefImage& z;
    const RefImage& albedo;
    const RefImage& pilot;
    const RefGuides& g;
    const zdenoise::FeatureRegressionOptions& o;

    /// z to radiance.
    float scale(int x, int y, int c) const { return albedo.at(x, y, c) + o.albedo_eps; }
    bool valid(int x, int y) const
    {
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(z.at(x, y, c)) || std::fabs(z.at(x, y, c)) >= 1e18f
                || !(scale(x, y, c) > 0.0f) || !std::isfinite(scale(x, y, c)))
                return false;
        if (!std::isfinite(luma(pilot, x, y)))
            return false;
        if (g.depth) {
            const float d = g.depth->at(x, y, 0);
            if (!(d > 0.0f && d < 1e9f && std::isfinite(d)))
                return false;
        }
        return true;
    }
    std::vector<double> normal(int x, int y) const
    {
        float n[3] = { g.normal->at(x, y, 0), g.normal->at(x, y, 1),
                       g.normal->at(x, y, 2) };
        const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len >= 1e-6f && std::isfinite(len)))
            return { 0.0, 0.0, 0.0 };
        return { double(n[0] / len), double(n[1] / len), double(n[2] / len) };
    }
    std::vector<double> x(int x0, int y0, int px, int py) const
    {
        std::vector<double> f = { 1.0, double(float(px - x0) * (1.0f / float(o.radius))),
                                  double(float(py - y0) * (1.0f / float(o.radius))) };
        if (g.normal) {
            const std::vector<double> a = normal(px, py), b = normal(x0, y0);
            for (int c = 0; c < 3; ++c)
                f.push_back(a[size_t(c)] - b[size_t(c)]);
        }
        if (g.depth) {
            const double ij = double(1.0f / g.depth->at(px, py, 0));
            const double i0 = double(1.0f / g.depth->at(x0, y0, 0));
            f.push_back((ij - i0) / i0);
        }
        return f;
    }
    double variance(int x, int y) const
    {
        const float v = pilot.at(x, y, 3);
        return std::isfinite(v) && v > 0.0f ? double(v) : 0.0;
    }
    /// Spatial Gaussian x same id x the patch weight (NFOR's distance).
    double weight(int x0, int y0, int px, int py) const
    {
        if (!valid(px, py))
            return 0.0;
        if (g.object_id) {
            const float a = g.object_id->at(px, py, 0), b = g.object_id->at(x0, y0, 0);
            if (std::memcmp(&a, &b, sizeof a) != 0)
                return 0.0;
        }
        const double k2 = double(o.patch_k) * o.patch_k;
        double d2 = 0.0;
        int n     = 0;
        for (int ty = -o.patch_radius; ty <= o.patch_radius; ++ty)
            for (int tx = -o.patch_radius; tx <= o.patch_radius; ++tx) {
                if (!z.inside(x0 + tx, y0 + ty) || !z.inside(px + tx, py + ty))
                    continue;
                const double la = luma(pilot, x0 + tx, y0 + ty);
                const double lb = luma(pilot, px + tx, py + ty);
                const double va = variance(x0 + tx, y0 + ty);
                const double vb = variance(px + tx, py + ty);
                d2 += ((la - lb) * (la - lb) - (va + std::min(va, vb)))
                      / (1e-4 * (la * la + lb * lb) + 1e-30 + k2 * (va + vb));
                ++n;
            }
        if (n)
            d2 /= n;
        const double sp = double(px - x0) * (px - x0) + double(py - y0) * (py - y0);
        // Weights are floats: one too small for a float takes no part.
        return double(float(std::exp(-sp / (double(o.radius) * o.radius) - std::max(0.0, d2))));
    }
};

/// Solve M a = b for several right-hand sides by Gaussian elimination with
/// partial pivoting; false if M is singular.
bool
solve(std::vector<std::vector<double>> M, std::vector<std::vector<double>>& B)
{
    const size_t n = M.size(), m = B[0].size();
    for (size_t c = 0; c < n; ++c) {
        size_t p = c;
        for (size_t r = c + 1; r < n; ++r)
            if (std::fabs(M[r][c]) > std::fabs(M[p][c]))
                p = r;
        if (!(std::fabs(M[p][c]) > 0.0))
            return false;
        std::swap(M[c], M[p]);
        std::swap(B[c], B[p]);
        for (size_t r = 0; r < n; ++r) {
            if (r == c)
                continue;
            const double f = M[r][c] / M[c][c];
            for (size_t k = c; k < n; ++k)
                M[r][k] -= f * M[c][k];
            for (size_t k = 0; k < m; ++k)
                B[r][k] -= f * B[c][k];
        }
    }
    for (size_t r = 0; r < n; ++r)
        for (size_t k = 0; k < m; ++k)
            B[r][k] /= M[r][r];
    return true;
}

/// A box mean over (2r+1)^2 clipped to the image of the pixels where
/// `use` holds: sum and count.
template<class Value>
void
box(int w, int h, int x, int y, int r, Value&& value, double& sum, double& count)
{
    sum = count = 0.0;
    for (int v = std::max(0, y - r); v <= std::min(h - 1, y + r); ++v)
        for (int u = std::max(0, x - r); u <= std::min(w - 1, x + r); ++u) {
            double a = 0.0;
            if (value(u, v, a)) {
                sum += a;
                count += 1.0;
            }
        }
}

}  // namespace


RefImage
feature_regression(const RefImage& z, const RefImage& albedo, const RefImage& pilot,
                   const RefGuides& guides,
                   const zdenoise::FeatureRegressionOptions& o)
{
    const Features F { z, albedo, pilot, guides, o };
    const int w = z.w, h = z.h, r = o.radius, s = o.centre_stride;
    RefImage out(w, h, 4);
    for (int qy = 0; qy < h; ++qy)
        for (int qx = 0; qx < w; ++qx) {
            double acc[3] = { 0, 0, 0 }, wsum = 0.0, hsum = 0.0;
            for (int y0 = 0; y0 < h; y0 += s)
                for (int x0 = 0; x0 < w; x0 += s) {
                    if (std::abs(qx - x0) > r || std::abs(qy - y0) > r
                        || !F.valid(x0, y0))
                        continue;
                    const double wq = F.weight(x0, y0, qx, qy);
                    if (!(wq > 0.0))
                        continue;
                    // The window's normal equations, with the ridge.
                    const size_t nf = F.x(x0, y0, x0, y0).size();
                    std::vector<std::vector<double>> M(nf, std::vector<double>(nf, 0.0));
                    std::vector<std::vector<double>> B(nf, std::vector<double>(3 + nf, 0.0));
                    double lo[3], hi[3];
                    // The range of the radiance of the window's points.
                    for (int c = 0; c < 3; ++c)
                        lo[c] = hi[c] = z.at(x0, y0, c) * F.scale(x0, y0, c);
                    for (int py = std::max(0, y0 - r); py <= std::min(h - 1, y0 + r); ++py)
                        for (int px = std::max(0, x0 - r); px <= std::min(w - 1, x0 + r); ++px) {
                            const double wj = F.weight(x0, y0, px, py);
                            if (!(wj > 0.0))
                                continue;
                            const std::vector<double> f = F.x(x0, y0, px, py);
                            for (size_t a = 0; a < nf; ++a) {
                                for (size_t b = 0; b < nf; ++b)
                                    M[a][b] += wj * f[a] * f[b];
                                for (int c = 0; c < 3; ++c)
                                    B[a][size_t(c)] += wj * f[a] * z.at(px, py, c);
                            }
                            for (int c = 0; c < 3; ++c) {
                                const float l = z.at(px, py, c) * F.scale(px, py, c);
                                lo[c] = std::min(lo[c], double(l));
                                hi[c] = std::max(hi[c], double(l));
                            }
                        }
                    const double m00 = M[0][0];
                    for (size_t a = 1; a < nf; ++a)
                        M[a][a] += double(o.ridge) * m00;
                    // Right-hand sides: the three channels and the identity
                    // (M^-1 for the hat diagonal).
                    for (size_t a = 0; a < nf; ++a)
                        B[a][3 + a] = 1.0;
                    if (!solve(M, B))
                        continue;
                    const std::vector<double> f = F.x(x0, y0, qx, qy);
                    double quad = 0.0;
                    for (size_t a = 0; a < nf; ++a)
                        for (size_t b = 0; b < nf; ++b)
                            quad += f[a] * B[a][3 + b] * f[b];
                    double hl = 0.0;
                    for (int c = 0; c < 3; ++c) {
                        double v = 0.0;
                        for (size_t a = 0; a < nf; ++a)
                            v += f[a] * B[a][size_t(c)];
                        const double a  = F.scale(qx, qy, c);
                        const double cl = std::min(std::max(v, lo[c] / a), hi[c] / a);
                        if (cl == v)
                            hl += kLuma[c] * wq * quad;
                        acc[c] += wq * cl;
                    }
                    wsum += wq;
                    hsum += wq * hl;
                }
            if (F.valid(qx, qy) && wsum > 0.0) {
                for (int c = 0; c < 3; ++c)
                    out.at(qx, qy, c) = float(acc[c] / wsum);
                out.at(qx, qy, 3) = float(hsum / wsum);
            } else {
                for (int c = 0; c < 3; ++c)
                    out.at(qx, qy, c) = std::isfinite(z.at(qx, qy, c)) ? z.at(qx, qy, c) : 0.0f;
                out.at(qx, qy, 3) = 1.0f;
            }
        }
    return out;
}


RefImage
sure_risk(const RefImage& candidate, const RefImage& z, const RefImage& variance,
          const RefImage& weight, double clip_sigmas)
{
    RefImage out(z.w, z.h, 1);
    for (int y = 0; y < z.h; ++y)
        for (int x = 0; x < z.w; ++x) {
            const double e = luma(candidate, x, y) - luma(z, x, y);
            const double v = variance.at(x, y, 0);
            double e2      = e * e;
            if (clip_sigmas > 0.0 && v > 0.0 && e2 > clip_sigmas * clip_sigmas * v)
                e2 = clip_sigmas * clip_sigmas * v;
            const double r  = weight.at(x, y, 0) * (e2 - v + 2.0 * v * candidate.at(x, y, 3));
            out.at(x, y, 0) = v >= 0.0 && std::isfinite(r) ? float(r) : NAN;
        }
    return out;
}


RefImage
select_by_risk(const std::vector<const RefImage*>& candidates,
               const std::vector<const RefImage*>& risks,
               const zdenoise::SelectionOptions& o, RefImage* weights)
{
    const int K = int(candidates.size()), w = candidates[0]->w, h = candidates[0]->h;
    // The choice at each pixel.
    std::vector<int> choice(size_t(w) * h, 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double best = 0.0;
            for (int k = 1; k < K; ++k) {
                auto diff = [&](int u, int v, double& d) {
                    const float a = risks[size_t(k)]->at(u, v, 0), b = risks[0]->at(u, v, 0);
                    d = double(a) - double(b);
                    return std::isfinite(a) && std::isfinite(b);
                };
                double s1, n, s2, n2;
                box(w, h, x, y, o.risk_radius, diff, s1, n);
                box(w, h, x, y, o.risk_radius,
                    [&](int u, int v, double& d) {
                        const bool ok = diff(u, v, d);
                        d *= d;
                        return ok;
                    }, s2, n2);
                if (n < 2.0)
                    continue;
                const double mean = s1 / n;
                const double se   = std::sqrt(std::max(0.0, s2 / n - mean * mean) / (n - 1.0));
                if (mean < -double(o.confidence) * se && mean < best) {
                    best = mean;
                    choice[size_t(y) * w + x] = k;
                }
            }
        }
    RefImage out(w, h, 3);
    if (weights)
        *weights = RefImage(w, h, K);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::vector<double> alpha(size_t(K), 0.0);
            double total = 0.0;
            for (int k = 0; k < K; ++k) {
                double s, n;
                box(w, h, x, y, o.map_radius, [&](int u, int v, double& a) {
                    a = choice[size_t(v) * w + u] == k ? 1.0 : 0.0;
                    return true;
                }, s, n);
                alpha[size_t(k)] = s;
                total += s;
            }
            for (int c = 0; c < 3; ++c) {
                double v = 0.0;
                for (int k = 0; k < K; ++k)
                    v += alpha[size_t(k)] * candidates[size_t(k)]->at(x, y, c);
                out.at(x, y, c) = float(v / total);
            }
            if (weights)
                for (int k = 0; k < K; ++k)
                    weights->at(x, y, k) = float(alpha[size_t(k)] / total);
        }
    return out;
}

}  // namespace zdenoise_ref
