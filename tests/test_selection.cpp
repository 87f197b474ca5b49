// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The selection stages (include/zdenoise/selection.h, docs/FILTER.md
// section 13): each against its reference implementation, the hat diagonal
// against finite differences, SURE against the true error, a two-region
// scene that needs two filters and gets them without a seam, and
// regression_filter() with select = 1 (determinism, quality, options).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <zdenoise/selection.h>
#include <zdenoise/simd.h>
#include <zdenoise/zdenoise.h>

#include "reference_filter.h"
#include "reference_selection.h"
#include "synthetic_scenes.h"

using OIIO::ImageBuf;
using OIIO::ROI;
using zdenoise_ref::RefImage;

namespace {

const float kLuma[3] = { 0.2126f, 0.7152f, 0.0722f };

float
luma(const RefImage& img, int x, int y)
{
    return kLuma[0] * img.at(x, y, 0) + kLuma[1] * img.at(x, y, 1)
           + kLuma[2] * img.at(x, y, 2);
}

/// Largest |a - b| over channels [0, nch) relative to `scale`.
double
max_difference(const RefImage& a, const RefImage& b, int nch, double scale)
{
    double worst = 0.0;
    for (int y = 0; y < a.h; ++y)
        for (int x = 0; x < a.w; ++x)
            for (int c = 0; c < nch; ++c)
                worst = std::max(worst, std::fabs(double(a.at(x, y, c)) - b.at(x, y, c))
                                            / scale);
    return worst;
}

/// A pilot for the feature regression: the 3x3 mean of z, and in channel
/// 3 the variance of its luminance (the pixel's variance over 9).
RefImage
box_pilot(const RefImage& z, const RefImage& variance)
{
    RefImage p(z.w, z.h, 4);
    for (int y = 0; y < z.h; ++y)
        for (int x = 0; x < z.w; ++x) {
            double s[3] = { 0, 0, 0 }, v = 0.0;
            int n       = 0;
            for (int v_ = std::max(0, y - 1); v_ <= std::min(z.h - 1, y + 1); ++v_)
                for (int u = std::max(0, x - 1); u <= std::min(z.w - 1, x + 1); ++u) {
                    for (int c = 0; c < 3; ++c)
                        s[c] += z.at(u, v_, c);
                    v += luma(variance, u, v_);
                    ++n;
                }
            for (int c = 0; c < 3; ++c)
                p.at(x, y, c) = float(s[c] / n);
            p.at(x, y, 3) = float(v / (double(n) * n));
        }
    return p;
}

/// The demodulated noisy image of a scene and its variance, as RefImages.
struct Quotient {
    RefImage z, var, pilot, albedo;
    explicit Quotient(const synth::Scene& s)
    {
        z   = zdenoise_ref::from_imagebuf(zdenoise::demodulate(s.noisy, s.albedo));
        var = zdenoise_ref::from_imagebuf(zdenoise::demodulate(s.variance, s.albedo));
        // The variance of a quotient divides by the albedo squared.
        albedo           = zdenoise_ref::from_imagebuf(s.albedo);
        const RefImage& a = albedo;
        for (int y = 0; y < z.h; ++y)
            for (int x = 0; x < z.w; ++x)
                for (int c = 0; c < 3; ++c)
                    var.at(x, y, c) /= a.at(x, y, c) + 1e-3f;
        pilot = box_pilot(z, var);
    }
};

zdenoise::FeatureRegressionOptions
small_windows()
{
    zdenoise::FeatureRegressionOptions o;
    o.radius        = 5;
    o.centre_stride = 2;
    return o;
}

/// A w x h RGB image of `f(x, y)` plus Gaussian noise of standard deviation
/// `sigma` (the same in R, G, B: correlated, as path-traced noise is).
RefImage
noisy_plane(int w, int h, double sigma, uint32_t seed, double (*f)(int, int),
            RefImage* clean)
{
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    RefImage z(w, h, 3);
    *clean = RefImage(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double e = sigma * n(rng);
            for (int c = 0; c < 3; ++c) {
                clean->at(x, y, c) = float(f(x, y));
                z.at(x, y, c)      = float(f(x, y) + e);
            }
        }
    return z;
}

/// A box mean of (2r+1)^2, clipped, with its hat diagonal in channel 3: a
/// linear candidate whose D is known exactly.
RefImage
box_candidate(const RefImage& z, int r)
{
    RefImage out(z.w, z.h, 4);
    for (int y = 0; y < z.h; ++y)
        for (int x = 0; x < z.w; ++x) {
            double s[3] = { 0, 0, 0 };
            int n       = 0;
            for (int v = std::max(0, y - r); v <= std::min(z.h - 1, y + r); ++v)
                for (int u = std::max(0, x - r); u <= std::min(z.w - 1, x + r); ++u) {
                    for (int c = 0; c < 3; ++c)
                        s[c] += z.at(u, v, c);
                    ++n;
                }
            for (int c = 0; c < 3; ++c)
                out.at(x, y, c) = float(s[c] / n);
            out.at(x, y, 3) = 1.0f / float(n);
        }
    return out;
}

RefImage
constant(int w, int h, float v)
{
    return RefImage(w, h, 1, v);
}

double
mse(const RefImage& a, const RefImage& clean, int x0, int x1)
{
    double s = 0.0;
    int n    = 0;
    for (int y = 0; y < a.h; ++y)
        for (int x = x0; x < x1; ++x, ++n)
            for (int c = 0; c < 3; ++c)
                s += std::pow(double(a.at(x, y, c)) - clean.at(x, y, c), 2) / 3.0;
    return s / n;
}

}  // namespace


namespace {

/// A staircase of w x 26 and its quotient, as images for the library and
/// for the reference, with the scene's normal, depth and id guides.
struct GuidedStaircase {
    synth::Scene s;
    Quotient q;
    RefImage n, d, id;
    ImageBuf zb, pb, ab;
    explicit GuidedStaircase(int w)
        : s(synth::staircase(w, 26, 6, { 8, 31 })), q(s),
          n(zdenoise_ref::from_imagebuf(s.normal)), d(zdenoise_ref::from_imagebuf(s.depth)),
          id(zdenoise_ref::from_imagebuf(s.object_id)), zb(zdenoise_ref::to_imagebuf(q.z)),
          pb(zdenoise_ref::to_imagebuf(q.pilot)), ab(zdenoise_ref::to_imagebuf(q.albedo))
    {
    }
    zdenoise_ref::RefGuides ref_guides() const
    {
        zdenoise_ref::RefGuides rg;
        rg.normal = &n, rg.depth = &d, rg.object_id = &id;
        return rg;
    }
    zdenoise::Guides guides() const
    {
        zdenoise::Guides g;
        g.normal = &s.normal, g.depth = &s.depth, g.object_id = &s.object_id;
        return g;
    }
};

}  // namespace

// The library's feature regression is the reference's, with and without
// guides, with the scene's ids; channel 3 (D) too.
TEST(FeatureRegression, MatchesTheReference)
{
    const GuidedStaircase st(30);
    for (int guided = 0; guided < 2; ++guided)
        for (float k : { 0.5f, 1.0f }) {
            SCOPED_TRACE(std::string(guided ? "guides" : "no guides") + ", patch_k "
                         + std::to_string(k));
            zdenoise::FeatureRegressionOptions o = small_windows();
            o.patch_k = k;
            const zdenoise_ref::RefGuides rg = guided ? st.ref_guides() : zdenoise_ref::RefGuides();
            const zdenoise::Guides g = guided ? st.guides() : zdenoise::Guides();
            ImageBuf lib;
            ASSERT_TRUE(zdenoise::feature_regression(lib, st.zb, st.ab, st.pb, g, o))
                << lib.geterror();
            const RefImage got = zdenoise_ref::from_imagebuf(lib);
            const RefImage ref
                = zdenoise_ref::feature_regression(st.q.z, st.q.albedo, st.q.pilot, rg, o);
            EXPECT_LT(max_difference(got, ref, 3, 1.0), 1e-4);
            EXPECT_LT(max_difference(got, ref, 4, 1.0), 1e-4) << "hat diagonal";
        }
}

// Every instruction set the kernels are compiled for that this CPU runs
// (AVX-512, AVX2, SSE4, the portable scalar code) gives the reference's
// result, and the sets agree with each other within float rounding.
TEST(FeatureRegression, EveryInstructionSetMatchesTheReference)
{
    const GuidedStaircase st(40);
    const zdenoise::FeatureRegressionOptions o = small_windows();
    const RefImage ref
        = zdenoise_ref::feature_regression(st.q.z, st.q.albedo, st.q.pilot, st.ref_guides(), o);
    const std::vector<std::string> targets = zdenoise::simd_targets();
    ASSERT_FALSE(targets.empty());
    EXPECT_TRUE(targets.back() == "SCALAR" || targets.back() == "EMU128")
        << "the portable code is always there, last: " << targets.back();
    std::vector<RefImage> got;
    for (const std::string& t : targets) {
        SCOPED_TRACE(t);
        ASSERT_TRUE(zdenoise::set_simd_target(t));
        EXPECT_EQ(zdenoise::simd_target(), t);
        ImageBuf lib;
        ASSERT_TRUE(zdenoise::feature_regression(lib, st.zb, st.ab, st.pb, st.guides(), o))
            << lib.geterror();
        got.push_back(zdenoise_ref::from_imagebuf(lib));
        EXPECT_LT(max_difference(got.back(), ref, 3, 1.0), 1e-4);
        EXPECT_LT(max_difference(got.back(), ref, 4, 1.0), 1e-4) << "hat diagonal";
        EXPECT_LT(max_difference(got.back(), got.front(), 4, 1.0), 1e-5)
            << "against " << targets.front();
    }
    EXPECT_FALSE(zdenoise::set_simd_target("no such set"));
    ASSERT_TRUE(zdenoise::set_simd_target(""));
    EXPECT_EQ(zdenoise::simd_target(), targets.front());
}

// The filter is linear in z (its weights read the pilot, never z), so D is
// the derivative of a pixel's output luminance by its own input: a small
// nudge of one pixel moves its output by D times the nudge.
TEST(FeatureRegression, HatDiagonalIsTheOutputsDerivative)
{
    const synth::Scene s = synth::fine_texture(24, 20, { 16, 7 });
    const Quotient q(s);
    const zdenoise::FeatureRegressionOptions o = small_windows();
    const RefImage base = zdenoise_ref::feature_regression(q.z, q.albedo, q.pilot, {}, o);
    int checked = 0, close = 0;
    for (int y = 2; y < q.z.h - 2; y += 5)
        for (int x = 3; x < q.z.w - 3; x += 5) {
            RefImage z = q.z;
            const float eps = 1e-3f * std::fabs(luma(z, x, y)) + 1e-6f;
            for (int c = 0; c < 3; ++c)
                z.at(x, y, c) += eps;
            const RefImage moved = zdenoise_ref::feature_regression(z, q.albedo, q.pilot, {}, o);
            const double fd = (double(luma(moved, x, y)) - luma(base, x, y)) / eps;
            ++checked;
            close += std::fabs(fd - base.at(x, y, 3)) < 2e-3;
        }
    // A pixel whose prediction is clamped in some window moves by less
    // than D says: the clamp is rare on a smooth light.
    EXPECT_GE(close, checked * 9 / 10) << close << " of " << checked;
}

// Today's filter's hat diagonal (FilterOptions::hat_diagonal, SURE's D for
// candidate 0) is the derivative of a pixel's output luminance by its own
// quotient: a small nudge of one pixel (of its three channels alike) moves
// its output by D times the nudge, except where the nudge moves a window's
// stop or a clamp. Without the value term the weights do not read z, so
// nearly every pixel agrees closely; with it (the default) D carries its
// first-order term, and the agreement is looser.
TEST(RegressionFilter, HatDiagonalIsTheOutputsDerivative)
{
    const synth::Scene s = synth::staircase(40, 36, 6, { 16, 21 });
    zdenoise::Guides g;
    g.normal = &s.normal, g.depth = &s.depth, g.object_id = &s.object_id;
    const ImageBuf z = zdenoise::demodulate(s.noisy, s.albedo);
    for (float value_k : { 0.0f, 1.0f }) {
        SCOPED_TRACE(value_k ? "value term" : "no value term");
        zdenoise::FilterOptions opt;
        opt.select  = 0;
        opt.r_max   = 6;
        opt.value_k = value_k;
        ImageBuf hat;
        opt.hat_diagonal = &hat;
        const ImageBuf base = zdenoise::regression_filter(z, s.albedo, g, opt);
        ASSERT_FALSE(base.has_error()) << base.geterror();
        ASSERT_EQ(hat.nchannels(), 1);
        opt.hat_diagonal = nullptr;
        const RefImage b = zdenoise_ref::from_imagebuf(base);
        int checked = 0, close = 0;
        std::vector<double> gap;  // d - fd
        for (int y = 3; y < s.h - 3; y += 4)
            for (int x = 3; x < s.w - 3; x += 4) {
                ImageBuf moved_z;
                moved_z.copy(z);
                float px[3];
                moved_z.getpixel(x, y, px, 3);
                const float eps = 1e-3f * std::fabs(kLuma[0] * px[0] + kLuma[1] * px[1]
                                                    + kLuma[2] * px[2]);
                for (float& v : px)
                    v += eps;
                moved_z.setpixel(x, y, px, 3);
                const RefImage m = zdenoise_ref::from_imagebuf(
                    zdenoise::regression_filter(moved_z, s.albedo, g, opt));
                const double fd = (double(luma(m, x, y)) - luma(b, x, y)) / eps;
                const double d  = hat.getchannel(x, y, 0, 0);
                ++checked;
                close += std::fabs(fd - d) < (value_k ? 0.05 : 0.01);
                gap.push_back(d - fd);
            }
        EXPECT_GE(close, checked * 9 / 10) << close << " of " << checked;
        // No bias either way (a stop moved by the nudge is an outlier of fd).
        std::nth_element(gap.begin(), gap.begin() + gap.size() / 2, gap.end());
        EXPECT_LT(std::fabs(gap[gap.size() / 2]), value_k ? 0.01 : 0.002);
    }
}

// The hat diagonal is the selection's own business when select is on.
TEST(RegressionFilter, HatDiagonalIsRefusedWithSelect)
{
    const synth::Scene s = synth::shadow_edge(16, 16);
    zdenoise::FilterOptions opt;
    opt.select = 1;
    ImageBuf hat, out;
    opt.hat_diagonal = &hat;
    const ImageBuf z = zdenoise::demodulate(s.noisy, s.albedo);
    EXPECT_FALSE(zdenoise::regression_filter(out, z, s.albedo, {}, opt));
    EXPECT_NE(out.geterror().find("hat_diagonal"), std::string::npos) << out.geterror();
}

// The library splits the frame into parts and threads exactly.
TEST(FeatureRegression, PartsAndThreadsGiveTheWholeImage)
{
    const synth::Scene s = synth::staircase(44, 40, 6, { 8, 5 });
    const Quotient q(s);
    const ImageBuf zb = zdenoise_ref::to_imagebuf(q.z), pb = zdenoise_ref::to_imagebuf(q.pilot);
    const ImageBuf ab = zdenoise_ref::to_imagebuf(q.albedo);
    zdenoise::Guides g;
    g.normal = &s.normal, g.depth = &s.depth, g.object_id = &s.object_id;
    const zdenoise::FeatureRegressionOptions o = small_windows();
    ImageBuf whole;
    ASSERT_TRUE(zdenoise::feature_regression(whole, zb, ab, pb, g, o, {}, 1));
    for (int nt : { 2, 3 })
        for (ROI roi : { ROI(0, 44, 0, 40), ROI(5, 31, 13, 22), ROI(0, 44, 39, 40) }) {
            ImageBuf part;
            ASSERT_TRUE(zdenoise::feature_regression(part, zb, ab, pb, g, o, roi, nt));
            roi.chbegin = 0, roi.chend = 4;
            std::vector<float> a(roi.npixels() * 4), b(a.size());
            whole.get_pixels(roi, OIIO::TypeFloat, a.data());
            part.get_pixels(roi, OIIO::TypeFloat, b.data());
            EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * 4), 0)
                << "threads " << nt << ", roi y " << roi.ybegin;
        }
}

// SURE of a linear smoother is unbiased: over an image of Gaussian noise
// its mean is the true mean squared error, for a filter that keeps the
// light (small D) and one that smooths a gradient away (bias).
TEST(SureRisk, MeanIsTheTrueErrorOfALinearFilter)
{
    const int w = 64, h = 64;
    const double sigma = 0.2;
    for (int r : { 1, 6 }) {
        double sure = 0.0, truth = 0.0;
        for (uint32_t seed = 1; seed <= 32; ++seed) {
            RefImage clean;
            const RefImage z = noisy_plane(w, h, sigma, seed,
                                           [](int x, int y) { return 1.0 + 0.02 * x * x / 64.0 + 0.3 * (y > 31); },
                                           &clean);
            const RefImage out = box_candidate(z, r);
            const RefImage risk = zdenoise_ref::sure_risk(out, z, constant(w, h, float(sigma * sigma)),
                                                          constant(w, h, 1.0f));
            ImageBuf lib;
            ASSERT_TRUE(zdenoise::sure_risk(lib, zdenoise_ref::to_imagebuf(out),
                                            zdenoise_ref::to_imagebuf(z),
                                            zdenoise_ref::to_imagebuf(constant(w, h, float(sigma * sigma))),
                                            zdenoise_ref::to_imagebuf(constant(w, h, 1.0f))));
            EXPECT_LT(max_difference(zdenoise_ref::from_imagebuf(lib), risk, 1, 1e-3), 1e-4);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    sure += risk.at(x, y, 0);
                    truth += std::pow(double(luma(out, x, y)) - luma(clean, x, y), 2);
                }
        }
        // 131072 one-sample estimates: their mean is within 3 % (one
        // standard error) of the truth here.
        EXPECT_NEAR(sure / truth, 1.0, 0.12) << "box radius " << r << ": SURE "
                                            << sure << ", true " << truth;
    }
}

// The winsorized risk (clip_sigmas, as the selection runs it): a 1-px dark
// line every 8 rows, 8 noise deviations deep, which a wide box fills in.
// Each line pixel's squared difference is clipped at 4 deviations for both
// candidates, yet the wide one still pays for filling it in: the selection
// keeps the narrow filter on the lines (before, such pixels had no
// observation). A noise-free pixel (variance 0) is an observation, its
// exact squared error. The library matches the reference.
TEST(SureRisk, WinsorizedRiskStillChargesTheFilterThatFillsInALine)
{
    const int w = 64, h = 64;
    const double sigma = 0.05;
    RefImage clean;
    const RefImage z = noisy_plane(w, h, sigma, 5, [](int, int y) {
        return y % 8 == 4 ? 1.0 - 8 * 0.05 : 1.0;
    }, &clean);
    const RefImage narrow = box_candidate(z, 0), wide = box_candidate(z, 3);
    RefImage var = constant(w, h, float(sigma * sigma));
    const RefImage one = constant(w, h, 1.0f);
    const RefImage r0 = zdenoise_ref::sure_risk(narrow, z, var, one, 4.0);
    const RefImage r1 = zdenoise_ref::sure_risk(wide, z, var, one, 4.0);
    for (const RefImage* r : { &r0, &r1 }) {
        ImageBuf lib;
        ASSERT_TRUE(zdenoise::sure_risk(lib, zdenoise_ref::to_imagebuf(r == &r0 ? narrow : wide),
                                        zdenoise_ref::to_imagebuf(z),
                                        zdenoise_ref::to_imagebuf(var),
                                        zdenoise_ref::to_imagebuf(one), 4.0f));
        EXPECT_LT(max_difference(zdenoise_ref::from_imagebuf(lib), *r, 1, 1e-3), 1e-4);
    }
    zdenoise::SelectionOptions o;
    RefImage weights;
    zdenoise_ref::select_by_risk({ &narrow, &wide }, { &r0, &r1 }, o, &weights);
    double narrow_on_lines = 0.0;
    int n = 0;
    for (int y = 12; y < h - 12; y += 8)
        for (int x = 12; x < w - 12; ++x, ++n)
            narrow_on_lines += weights.at(x, y, 0);
    EXPECT_GT(narrow_on_lines / n, 0.9) << "the lines keep the filter that keeps them";
    // Noise-free: the risk is the squared error, not "no observation".
    var.at(7, 9, 0) = 0.0f;
    const RefImage exact = zdenoise_ref::sure_risk(wide, z, var, one, 4.0);
    const double e = luma(wide, 7, 9) - luma(z, 7, 9);
    EXPECT_NEAR(exact.at(7, 9, 0), e * e, 1e-6);
}


// With two independent halves, the cross risk's mean is the true error of
// a half's filter plus the half's noise variance, common to every filter:
// no noise estimate needed to rank them.
TEST(HalvesRisk, MeanIsTheTrueErrorPlusTheHalfsVariance)
{
    const int w = 64, h = 64;
    const double sigma_half = 0.25;
    auto light = [](int x, int y) { return 1.0 + 0.02 * x * x / 64.0 + 0.3 * (y > 31); };
    for (int r : { 1, 6 }) {
        double risk = 0.0, truth = 0.0;
        for (uint32_t seed = 1; seed <= 32; ++seed) {
            RefImage clean;
            const RefImage za = noisy_plane(w, h, sigma_half, 2 * seed, light, &clean);
            const RefImage zb = noisy_plane(w, h, sigma_half, 2 * seed + 1, light, &clean);
            const RefImage fa = box_candidate(za, r), fb = box_candidate(zb, r);
            ImageBuf out;
            ASSERT_TRUE(zdenoise::halves_risk(out, zdenoise_ref::to_imagebuf(fa),
                                              zdenoise_ref::to_imagebuf(fb),
                                              zdenoise_ref::to_imagebuf(za),
                                              zdenoise_ref::to_imagebuf(zb),
                                              zdenoise_ref::to_imagebuf(constant(w, h, 1.0f))))
                << out.geterror();
            const RefImage got = zdenoise_ref::from_imagebuf(out);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    risk += double(got.at(x, y, 0)) - sigma_half * sigma_half;
                    truth += 0.5 * (std::pow(double(luma(fa, x, y)) - luma(clean, x, y), 2)
                                    + std::pow(double(luma(fb, x, y)) - luma(clean, x, y), 2));
                }
        }
        EXPECT_NEAR(risk / truth, 1.0, 0.12) << "box radius " << r << ": risk " << risk
                                             << ", true " << truth;
    }
}

// The library's selection is the reference's: three candidates, noisy
// risks with NaN holes, weights too.
TEST(SelectByRisk, MatchesTheReference)
{
    const int w = 37, h = 29;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<RefImage> cand(3, RefImage(w, h, 3)), risk(3, RefImage(w, h, 1));
    for (int k = 0; k < 3; ++k)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                for (int c = 0; c < 3; ++c)
                    cand[size_t(k)].at(x, y, c) = float(k) + u(rng);
                // Candidate 1 better on the left, 2 at the bottom, noisily.
                const float trend = k == 1 ? (x < 15 ? -0.3f : 0.2f)
                                  : k == 2 ? (y > 18 ? -0.5f : 0.3f) : 0.0f;
                risk[size_t(k)].at(x, y, 0) = (x * 7 + y) % 23 == 0 ? NAN : trend + u(rng);
            }
    zdenoise::SelectionOptions o;
    o.risk_radius = 4;
    o.map_radius  = 2;
    RefImage ref_weights;
    const RefImage ref = zdenoise_ref::select_by_risk({ &cand[0], &cand[1], &cand[2] },
                                                      { &risk[0], &risk[1], &risk[2] }, o,
                                                      &ref_weights);
    std::vector<ImageBuf> cb, rb;
    for (int k = 0; k < 3; ++k) {
        cb.push_back(zdenoise_ref::to_imagebuf(cand[size_t(k)]));
        rb.push_back(zdenoise_ref::to_imagebuf(risk[size_t(k)]));
    }
    ImageBuf lib, weights;
    ASSERT_TRUE(zdenoise::select_by_risk(lib, { &cb[0], &cb[1], &cb[2] },
                                         { &rb[0], &rb[1], &rb[2] }, o, &weights))
        << lib.geterror();
    EXPECT_LT(max_difference(zdenoise_ref::from_imagebuf(lib), ref, 3, 1.0), 1e-5);
    EXPECT_LT(max_difference(zdenoise_ref::from_imagebuf(weights), ref_weights, 3, 1.0), 1e-6);
    // Each candidate wins where it was made better.
    EXPECT_GT(ref_weights.at(5, 5, 1), 0.9f);
    EXPECT_GT(ref_weights.at(30, 26, 2), 0.9f);
}

// Two regions that need different filters: a smooth gradient (a wide box
// wins) beside stripes of period 6 (a wide box erases them, a narrow one
// wins). Selected by SURE, each region is as good as its better filter, and
// the change of filter is spread over the map's width: no seam.
TEST(SelectByRisk, TwoRegionsGetTheirFiltersWithoutASeam)
{
    const int w = 96, h = 64, edge = 48;
    const double sigma = 0.15;
    RefImage clean;
    const RefImage z = noisy_plane(w, h, sigma, 11, [](int x, int) {
        return x < 48 ? 1.0 + 0.005 * x : 1.0 + 0.5 * (x % 6 < 3);
    }, &clean);
    const RefImage narrow = box_candidate(z, 1), wide = box_candidate(z, 4);
    const RefImage var = constant(w, h, float(sigma * sigma)), one = constant(w, h, 1.0f);
    const RefImage r0 = zdenoise_ref::sure_risk(narrow, z, var, one);
    const RefImage r1 = zdenoise_ref::sure_risk(wide, z, var, one);
    zdenoise::SelectionOptions o;
    RefImage weights;
    const RefImage out = zdenoise_ref::select_by_risk({ &narrow, &wide }, { &r0, &r1 }, o,
                                                      &weights);
    const int margin = o.risk_radius + o.map_radius + 4;  // the wide box's reach
    const double left = mse(out, clean, 0, edge - margin);
    const double right = mse(out, clean, edge + margin, w);
    EXPECT_LE(left, 1.05 * mse(wide, clean, 0, edge - margin));
    EXPECT_LT(mse(wide, clean, 0, edge - margin), 0.5 * mse(narrow, clean, 0, edge - margin));
    EXPECT_LE(right, 1.05 * mse(narrow, clean, edge + margin, w));
    // Across the boundary: no worse than the worse filter there, and the
    // mean weight changes by at most one map box column a column.
    EXPECT_LE(mse(out, clean, edge - 4, edge + 4),
              std::max(mse(wide, clean, edge - 4, edge + 4), mse(narrow, clean, edge - 4, edge + 4)));
    double prev = -1.0, steepest = 0.0;
    for (int x = 0; x < w; ++x) {
        double m = 0.0;
        for (int y = 0; y < h; ++y)
            m += weights.at(x, y, 1) / h;
        if (prev >= 0.0)
            steepest = std::max(steepest, std::fabs(m - prev));
        prev = m;
    }
    EXPECT_LE(steepest, 1.0 / (2 * o.map_radius + 1) + 1e-6);
}

// regression_filter() with select = 1: the same pixels for any thread count
// and part of the frame; never worse than today's filter on a scene of
// faces that the feature regression pools; options checked.
TEST(SelectedFilter, PartsAndThreadsGiveTheWholeImage)
{
    const synth::Scene s = synth::staircase(56, 84, 8, { 8, 808 });
    for (bool halves : { false, true }) {
    SCOPED_TRACE(halves ? "risk from the halves" : "risk from SURE");
    zdenoise::Guides g;
    g.normal = &s.normal, g.depth = &s.depth, g.object_id = &s.object_id;
    if (halves)
        g.half_a = &s.half_a, g.half_b = &s.half_b;
    zdenoise::FilterOptions opt;
    opt.r_max  = 8;
    opt.select = 1;
    const ImageBuf z = zdenoise::demodulate(s.noisy, s.albedo);
    const ImageBuf whole = zdenoise::regression_filter(z, s.albedo, g, opt, nullptr, {}, 1);
    ASSERT_FALSE(whole.has_error()) << whole.geterror();
    for (int nt : { 2, 3 })
        for (ROI roi : { ROI(0, 56, 0, 84), ROI(9, 40, 30, 61), ROI(0, 56, 83, 84) }) {
            const ImageBuf part = zdenoise::regression_filter(z, s.albedo, g, opt, nullptr, roi, nt);
            ASSERT_FALSE(part.has_error()) << part.geterror();
            roi.chbegin = 0, roi.chend = 3;
            std::vector<float> a(roi.npixels() * 3), b(a.size());
            whole.get_pixels(roi, OIIO::TypeFloat, a.data());
            part.get_pixels(roi, OIIO::TypeFloat, b.data());
            EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * 4), 0)
                << "threads " << nt << ", roi y " << roi.ybegin << "-" << roi.yend;
        }
    }
}

TEST(SelectedFilter, NeverWorseThanTodaysFilterAndKeepsTheLight)
{
    for (const synth::Scene& s : { synth::sawtooth(64, 48, 4, { 4, 3 }),
                                   synth::shadow_edge(64, 48, { 4, 3 }),
                                   synth::fine_texture(64, 48, { 4, 3 }) }) {
        for (bool halves : { false, true }) {
        SCOPED_TRACE(s.name + (halves ? ", risk from the halves" : ", risk from SURE"));
        zdenoise::Guides g;
        g.normal = &s.normal, g.depth = &s.depth, g.object_id = &s.object_id;
        if (halves)
            g.half_a = &s.half_a, g.half_b = &s.half_b;
        // Today's filter is select = 0 (the default is the selection).
        zdenoise::FilterOptions today, selected;
        today.select    = 0;
        selected.select = 1;
        const ImageBuf a = zdenoise::denoise(s.noisy, s.albedo, g, today);
        const ImageBuf b = zdenoise::denoise(s.noisy, s.albedo, g, selected);
        ASSERT_FALSE(b.has_error()) << b.geterror();
        const double ea = synth::rel_mse(a, s.clean), eb = synth::rel_mse(b, s.clean);
        EXPECT_LE(eb, 1.05 * ea) << "today " << ea << ", selected " << eb;
        EXPECT_LT(eb, synth::rel_mse(s.noisy, s.clean) / 3.0);
        const double ma = synth::mean_luminance(a, 0, s.w, 0, s.h);
        const double mb = synth::mean_luminance(b, 0, s.w, 0, s.h);
        const double mc = synth::mean_luminance(s.clean, 0, s.w, 0, s.h);
        std::printf("  %-14s %-6s relMSE today %.5f selected %.5f, energy %.4f %.4f\n",
                    s.name.c_str(), halves ? "halves" : "SURE", ea, eb, ma / mc, mb / mc);
        // Today's filter loses a few percent of the light of 4-sample gamma
        // noise (docs/LIGHT.md); the selection must not lose more.
        EXPECT_LE(std::fabs(mb / mc - 1.0), std::fabs(ma / mc - 1.0) + 0.005);
        }
    }
}

TEST(SelectedFilter, OptionsAreChecked)
{
    EXPECT_EQ(zdenoise::FilterOptions::algorithm_defaults().select, 0)
        << "--preset spec is the paper's filter alone";
    const synth::Scene s = synth::shadow_edge(16, 16);
    zdenoise::FilterOptions opt;
    opt.select = 2;
    const ImageBuf out = zdenoise::denoise(s.noisy, s.albedo, {}, opt);
    EXPECT_TRUE(out.has_error());
    EXPECT_NE(out.geterror().find("select"), std::string::npos) << out.geterror();
    ImageBuf dst;
    zdenoise::FeatureRegressionOptions fo;
    fo.radius = 0;
    EXPECT_FALSE(zdenoise::feature_regression(dst, s.noisy, s.albedo, s.noisy, {}, fo));
    EXPECT_NE(dst.geterror().find("radius"), std::string::npos) << dst.geterror();
}
