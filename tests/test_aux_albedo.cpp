// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// pool_aux_albedo() (docs/AUX.md, "Wrong auxiliary pixels") as a user
// notices it: an auxiliary albedo that misses the sky is not let through
// (the render's own is used there, and counted), noise is never taken for
// a wrong pixel, pooling a few-sample auxiliary albedo with a many-sample
// render's beats either, a noise-free one is kept as it is; the result is
// the plain reference's, and the same over any part and thread count.

#include <cmath>
#include <random>
#include <vector>

#include <OpenImageIO/imagebufalgo.h>

#include <gtest/gtest.h>

#include <zdenoise/zdenoise.h>

using namespace OIIO;

namespace {

constexpr int kW = 64, kH = 48;

/// The exact albedo one sample at the continuous point (x, y) sees: fine
/// vertical stripes (0.2 / 0.7, a period of 2.5 px) on the left, a flat
/// 0.5 grey on the right and, above y = 12, the sky (4.7, 5.2, 6.0).
void
scene_at(float x, float y, float* a)
{
    if (y < 12.0f) {
        a[0] = 4.7f, a[1] = 5.2f, a[2] = 6.0f;
        return;
    }
    const float v = x < 32.0f
                        ? (std::fmod(x + 0.37f * y, 2.3f) < 1.1f ? 0.2f : 0.7f)
                        : 0.5f;
    a[0] = a[1] = a[2] = v;
}

/// The scene's albedo as a renderer writes it with `samples` jittered
/// samples a pixel (0: exact, 64x64 strata); `sky` false gives 0 above
/// y = 12, as an auxiliary render with a black world does.
ImageBuf
render(int samples, uint32_t seed, bool sky = true)
{
    ImageBuf img(ImageSpec(kW, kH, 3, TypeFloat));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const int side = samples ? int(std::lround(std::sqrt(float(samples))))
                             : 64;
    const int n    = side * side;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            float sum[3] = { 0, 0, 0 };
            for (int s = 0; s < n; ++s) {
                const float jx = samples ? u(rng) : 0.5f;
                const float jy = samples ? u(rng) : 0.5f;
                float a[3];
                scene_at(x + (float(s % side) + jx) / float(side),
                         y + (float(s / side) + jy) / float(side), a);
                if (!sky && y + (float(s / side) + jy) / float(side) < 12.0f)
                    a[0] = a[1] = a[2] = 0.0f;
                for (int c = 0; c < 3; ++c)
                    sum[c] += a[c];
            }
            for (int c = 0; c < 3; ++c)
                sum[c] /= float(n);
            img.setpixel(x, y, sum);
        }
    return img;
}

/// The plain reference: docs/AUX.md's rule written out pixel by pixel in
/// double, from getpixel().
ImageBuf
reference_pool(const ImageBuf& aux, const ImageBuf& own,
               const zdenoise::AuxAlbedoOptions& o, int& rejected)
{
    ImageBuf out(ImageSpec(kW, kH, 3, TypeFloat));
    rejected = 0;
    // The mixture variance over the two albedos' 5x5 range.
    auto var = [&](double v, int x, int y, int c) {
        double lo = v, hi = v;
        for (const ImageBuf* img : { &aux, &own })
            for (int qy = std::max(y - 2, 0); qy <= std::min(y + 2, kH - 1); ++qy)
                for (int qx = std::max(x - 2, 0); qx <= std::min(x + 2, kW - 1);
                     ++qx) {
                    lo = std::min(lo, double(img->getchannel(qx, qy, 0, c)));
                    hi = std::max(hi, double(img->getchannel(qx, qy, 0, c)));
                }
        return (hi - v) * (v - lo);
    };
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            bool disagree = false;
            for (int c = 0; c < 3; ++c) {
                const double a = aux.getchannel(x, y, 0, c);
                const double r = own.getchannel(x, y, 0, c);
                const double wr = o.aux_samples ? std::pow(o.render_samples, 1.5) : 0.0;
                const double wa = o.aux_samples ? std::pow(o.aux_samples, 1.5) : 1.0;
                const double mean = (wr * r + wa * a) / (wr + wa);
                double v = var(mean, x, y, c) / o.render_samples;
                if (o.aux_samples)
                    v += var(mean, x, y, c) / o.aux_samples;
                if (std::abs(r - a)
                    > 4.0 * std::sqrt(v) + o.precision * (std::abs(r) + std::abs(a)))
                    disagree = true;
            }
            rejected += disagree;
            const double wr = o.aux_samples ? std::pow(o.render_samples, 1.5) : 0.0;
            const double wa = o.aux_samples ? std::pow(o.aux_samples, 1.5) : 1.0;
            float px[3];
            for (int c = 0; c < 3; ++c) {
                const double a = aux.getchannel(x, y, 0, c);
                const double r = own.getchannel(x, y, 0, c);
                px[c] = float(disagree ? r : (wr * r + wa * a) / (wr + wa));
            }
            out.setpixel(x, y, px);
        }
    return out;
}

double
mse(const ImageBuf& a, const ImageBuf& b, ROI roi)
{
    double s = 0.0;
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x)
            for (int c = 0; c < 3; ++c) {
                const double d = a.getchannel(x, y, 0, c) - b.getchannel(x, y, 0, c);
                s += d * d;
            }
    return s / double(roi.npixels() * 3);
}

const ROI kGround(0, kW, 12, kH);
const ROI kSky(0, kW, 0, 11);  // clear of the horizon's mixed row

}  // namespace


TEST(AuxAlbedo, AnAuxThatMissesTheSkyIsNotLetThrough)
{
    const ImageBuf exact = render(0, 1);
    const ImageBuf own   = render(16, 2);
    const ImageBuf aux   = render(0, 3, /*sky=*/false);
    zdenoise::AuxAlbedoOptions o;
    o.render_samples = 16;
    zdenoise::AuxAlbedoStats st;
    ImageBuf pooled;
    ASSERT_TRUE(zdenoise::pool_aux_albedo(pooled, aux, own, o, &st));
    // The sky takes the render's own (flat there, so exact).
    EXPECT_LT(mse(pooled, exact, kSky), 1e-8);
    EXPECT_GT(mse(aux, exact, kSky), 10.0);
    // Every sky pixel is counted, and no more than a few ground pixels
    // besides the horizon's row.
    EXPECT_GE(st.rejected, uint64_t(12 * kW));
    EXPECT_LE(st.rejected, uint64_t(13 * kW + kW / 10));
    EXPECT_EQ(st.pixels, uint64_t(kW * kH));
    // The ground keeps the noise-free aux (but at a few pixels where the
    // render's samples all fell on one stripe).
    const ROI ground(0, kW, 13, kH);
    EXPECT_LT(mse(pooled, exact, ground), 0.1 * mse(own, exact, ground));
}


TEST(AuxAlbedo, NoiseIsNotTakenForAWrongPixel)
{
    // Both albedos are right, at 4 and at 64 samples: under 0.5 % of the
    // pixels are rejected.
    for (int n : { 4, 64 }) {
        const ImageBuf own = render(n, 10 + uint32_t(n));
        const ImageBuf aux = render(16, 20 + uint32_t(n));
        zdenoise::AuxAlbedoOptions o;
        o.render_samples = n;
        o.aux_samples    = 16;
        zdenoise::AuxAlbedoStats st;
        ImageBuf pooled;
        ASSERT_TRUE(zdenoise::pool_aux_albedo(pooled, aux, own, o, &st));
        EXPECT_LT(double(st.rejected), 0.005 * double(st.pixels)) << n;
    }
}


TEST(AuxAlbedo, PoolingBeatsEitherAlbedo)
{
    // 16-sample aux beside a 16-sample render: the pooled albedo's error
    // is at most 0.7x the better one's (two equal estimates: 0.5x).
    const ImageBuf exact = render(0, 1);
    const ImageBuf own   = render(16, 31);
    const ImageBuf aux   = render(16, 32);
    zdenoise::AuxAlbedoOptions o;
    o.render_samples = 16;
    o.aux_samples    = 16;
    ImageBuf pooled;
    ASSERT_TRUE(zdenoise::pool_aux_albedo(pooled, aux, own, o));
    const double e_own = mse(own, exact, kGround), e_aux = mse(aux, exact, kGround);
    EXPECT_LT(mse(pooled, exact, kGround), 0.7 * std::min(e_own, e_aux));
    // A render of many samples beside an aux of few: the pooled albedo is
    // no worse than the render's own (the aux counts less, not more).
    const ImageBuf many = render(64, 33);
    const ImageBuf few  = render(4, 34);
    o.render_samples    = 64;
    o.aux_samples       = 4;
    ASSERT_TRUE(zdenoise::pool_aux_albedo(pooled, few, many, o));
    EXPECT_LE(mse(pooled, exact, kGround), 1.0 * mse(many, exact, kGround));
}


TEST(AuxAlbedo, IsThePlainReferencesForAnyPartAndThreads)
{
    const ImageBuf own = render(4, 41);
    const ImageBuf aux = render(16, 42, /*sky=*/false);
    for (int aux_samples : { 0, 16 }) {
        zdenoise::AuxAlbedoOptions o;
        o.render_samples = 4;
        o.aux_samples    = aux_samples;
        int rejected     = 0;
        const ImageBuf want = reference_pool(aux, own, o, rejected);
        zdenoise::AuxAlbedoStats st;
        ImageBuf whole;
        ASSERT_TRUE(zdenoise::pool_aux_albedo(whole, aux, own, o, &st, {}, 1));
        EXPECT_EQ(st.rejected, uint64_t(rejected));
        auto cmp = ImageBufAlgo::compare(whole, want, 1e-5f, 1e-5f);
        EXPECT_EQ(cmp.nfail, 0u) << "aux samples " << aux_samples
                                 << " max error " << cmp.maxerror;
        // A part computed from the images over it and its halo, at 3
        // threads, counting its core only: the whole image's pixels.
        const ROI core(0, kW, 20, 30);
        const int h = zdenoise::aux_albedo_halo();
        const ROI held(0, kW, core.ybegin - h, core.yend + h);
        ImageBuf aux_part, own_part, part;
        ImageBufAlgo::cut(aux_part, aux, held);
        ImageBufAlgo::cut(own_part, own, held);
        aux_part.set_origin(0, held.ybegin);
        own_part.set_origin(0, held.ybegin);
        o.counted = core;
        ASSERT_TRUE(zdenoise::pool_aux_albedo(part, aux_part, own_part, o, &st,
                                              core, 3));
        ImageBuf whole_core;
        ImageBufAlgo::cut(whole_core, whole, core);
        whole_core.set_origin(0, core.ybegin);
        cmp = ImageBufAlgo::compare(part, whole_core, 0.0f, 0.0f);
        EXPECT_EQ(cmp.nfail, 0u);
        EXPECT_EQ(st.pixels, uint64_t(core.npixels()));
    }
}


TEST(AuxAlbedo, RefusesBadSamples)
{
    const ImageBuf a = render(0, 1);
    zdenoise::AuxAlbedoOptions o;
    o.render_samples = 0;
    ImageBuf dst;
    EXPECT_FALSE(zdenoise::pool_aux_albedo(dst, a, a, o));
    EXPECT_NE(dst.geterror().find("render_samples = 0"), std::string::npos);
}
