// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The library against the plain reference implementation of docs/FILTER.md
// (reference_filter.cpp) on small images, with and without each guide and
// noise source, and with non-default options. The two differ only in
// summation order and float-vs-double arithmetic, so the tolerance is tight.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <zdenoise/simd.h>
#include <zdenoise/zdenoise.h>

#include "reference_filter.h"
#include "synthetic_scenes.h"

using OIIO::ImageBuf;
using synth::Scene;
using zdenoise_ref::RefImage;

namespace {

constexpr int W = 40, H = 36;

/// Compare a library result with the reference: RGB within `tol` of the
/// value scale (max |ref| over RGB), other channels exactly.
void
expect_matches_reference(const ImageBuf& lib, const RefImage& ref,
                         const std::string& what, double tol = 1e-4)
{
    ASSERT_FALSE(lib.has_error()) << what << ": " << lib.geterror();
    RefImage got = zdenoise_ref::from_imagebuf(lib);
    ASSERT_EQ(got.w, ref.w) << what;
    ASSERT_EQ(got.h, ref.h) << what;
    ASSERT_EQ(got.nch, ref.nch) << what;
    double scale = 0.0;
    for (int y = 0; y < ref.h; ++y)
        for (int x = 0; x < ref.w; ++x)
            for (int c = 0; c < 3; ++c)
                if (std::isfinite(ref.at(x, y, c)))
                    scale = std::max(scale, double(std::abs(ref.at(x, y, c))));
    scale = std::max(scale, 1e-6);
    double worst = 0.0;
    int wx = -1, wy = -1, wc = -1, nbad = 0, nonfinite = 0, other_bad = 0;
    for (int y = 0; y < ref.h; ++y)
        for (int x = 0; x < ref.w; ++x) {
            for (int c = 0; c < 3; ++c) {
                float a = got.at(x, y, c), b = ref.at(x, y, c);
                if (!std::isfinite(a)) {
                    ++nonfinite;
                    continue;
                }
                double d = std::abs(double(a) - double(b)) / scale;
                if (d > tol)
                    ++nbad;
                if (d > worst) {
                    worst = d;
                    wx = x, wy = y, wc = c;
                }
            }
            for (int c = 3; c < ref.nch; ++c) {
                float a = got.at(x, y, c), b = ref.at(x, y, c);
                if (std::memcmp(&a, &b, sizeof(float)) != 0)
                    ++other_bad;
            }
        }
    std::printf("  %-44s max |lib-ref|/scale %.3g (scale %.4g)\n", what.c_str(),
                worst, scale);
    EXPECT_EQ(nonfinite, 0) << what << ": non-finite RGB values in the output";
    EXPECT_EQ(other_bad, 0) << what << ": non-RGB channels not copied exactly";
    if (wx >= 0) {
        EXPECT_LE(worst, tol)
            << what << ": " << nbad << " of " << ref.w * ref.h * 3
            << " values differ from the reference by more than " << tol
            << " of the scale " << scale << "; worst at (" << wx << "," << wy
            << ") channel " << wc << ": library " << got.at(wx, wy, wc)
            << ", reference " << ref.at(wx, wy, wc);
    }
}

void
expect_stats_match(const zdenoise::FilterStats& st,
                   const zdenoise_ref::RefStats& rs, const zdenoise::FilterOptions& opt,
                   const std::string& what)
{
    std::printf("  %-44s windows %lld/%lld  quality %lld/%lld  size %lld/%lld  "
                "edge %lld/%lld  radius %.3f/%.3f (lib/ref)\n",
                what.c_str(), (long long)st.windows, (long long)rs.windows,
                (long long)st.stop_quality, (long long)rs.stop_quality,
                (long long)st.stop_size, (long long)rs.stop_size,
                (long long)st.stop_edge, (long long)rs.stop_edge, st.mean_radius,
                rs.mean_radius);
    // plausible on their own
    EXPECT_EQ(st.pixels, rs.pixels) << what;
    EXPECT_EQ(st.stop_quality + st.stop_size + st.stop_edge, st.windows)
        << what << ": every window stops for exactly one reason";
    EXPECT_GE(st.mean_radius, double(opt.r_min) - 1e-9) << what;
    EXPECT_LE(st.mean_radius, double(opt.r_max) + 1e-9) << what;
    // and the same as the reference's (decisions are identical but for
    // values that sit within rounding of a threshold)
    auto near = [](int64_t a, int64_t b) {
        return std::llabs(a - b) <= std::max<int64_t>(1, b / 200);
    };
    EXPECT_EQ(st.windows, rs.windows) << what << ": windows (fit-point centres)";
    EXPECT_TRUE(near(st.stop_quality, rs.stop_quality))
        << what << ": stop_quality " << st.stop_quality << " vs reference "
        << rs.stop_quality;
    EXPECT_TRUE(near(st.stop_size, rs.stop_size))
        << what << ": stop_size " << st.stop_size << " vs reference "
        << rs.stop_size;
    EXPECT_TRUE(near(st.stop_edge, rs.stop_edge))
        << what << ": stop_edge " << st.stop_edge << " vs reference "
        << rs.stop_edge;
    EXPECT_NEAR(st.mean_radius, rs.mean_radius, 0.02) << what;
    EXPECT_EQ(st.nonfinite_pixels, rs.nonfinite_pixels) << what;
    EXPECT_EQ(st.passthrough_pixels, rs.passthrough_pixels)
        << what << ": passthrough_pixels (read as: pixels with >= 1 RGB "
                   "channel not given a filtered value)";
}

/// The diagnostic maps (radius, stop, noise, error) as the reference's:
/// noise to float rounding; radius, stop and error on all but the pixels
/// that a window whose decision sits within rounding of a threshold
/// reaches (at most 2 %).
void
expect_diagnostics_match(const ImageBuf& lib, const RefImage& ref,
                         const std::string& what)
{
    ASSERT_FALSE(lib.has_error()) << what << ": " << lib.geterror();
    ASSERT_EQ(lib.nchannels(), 4) << what;
    RefImage got = zdenoise_ref::from_imagebuf(lib);
    ASSERT_EQ(got.w, ref.w) << what;
    ASSERT_EQ(got.h, ref.h) << what;
    int differ = 0, noise_bad = 0;
    for (int y = 0; y < ref.h; ++y)
        for (int x = 0; x < ref.w; ++x) {
            auto rel = [&](int c) {
                const double a = got.at(x, y, c), b = ref.at(x, y, c);
                return std::abs(a - b) / std::max(std::abs(b), 1e-6);
            };
            noise_bad += rel(2) > 1e-4;
            differ += rel(0) > 1e-4 || got.at(x, y, 1) != ref.at(x, y, 1)
                      || rel(3) > 1e-3;
        }
    std::printf("  %-44s %d of %d pixels differ\n", what.c_str(), differ,
                ref.w * ref.h);
    EXPECT_EQ(noise_bad, 0) << what << ": the noise map";
    EXPECT_LE(differ, ref.w * ref.h / 50) << what;
}

/// One comparison case: a scene, which guides to give, options, and an
/// optional edit of the inputs (made before anything is run).
zdenoise::FilterOptions
small_options()
{
    zdenoise::FilterOptions opt;
    opt.r_max         = 5;
    opt.centre_stride = 1;  // the exact filter; StridedCentres has the rest
    opt.select        = 0;  // the reference is today's filter (sections 2-8)
    return opt;
}

struct Case {
    std::string name;
    Scene s;
    bool normal = false, depth = false, id = false, variance = false,
         halves = false;
    zdenoise::FilterOptions opt = small_options();
    bool whole_denoise = false;  // also compare denoise() end to end

    Case(std::string n, Scene sc) : name(std::move(n)), s(std::move(sc)) {}
};

void
run_case(const Case& k, const ImageBuf* quotient_override = nullptr)
{
    SCOPED_TRACE(k.name);
    const Scene& s = k.s;
    // inputs as RefImages (kept alive for the RefGuides pointers)
    RefImage L   = zdenoise_ref::from_imagebuf(s.noisy);
    RefImage La  = zdenoise_ref::from_imagebuf(s.albedo);
    RefImage N   = zdenoise_ref::from_imagebuf(s.normal);
    RefImage D   = zdenoise_ref::from_imagebuf(s.depth);
    RefImage I   = zdenoise_ref::from_imagebuf(s.object_id);
    RefImage V   = zdenoise_ref::from_imagebuf(s.variance);
    RefImage A   = zdenoise_ref::from_imagebuf(s.half_a);
    RefImage B   = zdenoise_ref::from_imagebuf(s.half_b);
    zdenoise_ref::RefGuides rg;
    zdenoise::Guides g;
    if (k.normal)
        rg.normal = &N, g.normal = &s.normal;
    if (k.depth)
        rg.depth = &D, g.depth = &s.depth;
    if (k.id)
        rg.object_id = &I, g.object_id = &s.object_id;
    if (k.variance)
        rg.variance = &V, g.variance = &s.variance;
    if (k.halves) {
        rg.half_a = &A, rg.half_b = &B;
        g.half_a = &s.half_a, g.half_b = &s.half_b;
    }

    // the filter alone, both fed the same quotient
    RefImage z = quotient_override
                     ? zdenoise_ref::from_imagebuf(*quotient_override)
                     : zdenoise_ref::demodulate(L, La, k.opt.albedo_eps);
    ImageBuf zbuf = zdenoise_ref::to_imagebuf(z);
    zdenoise_ref::RefStats rs;
    RefImage ref_maps;
    RefImage ref = zdenoise_ref::regression_filter(z, La, rg, k.opt, &rs,
                                                   &ref_maps);
    zdenoise::FilterStats st;
    ImageBuf lib_maps;
    zdenoise::FilterOptions with_maps = k.opt;
    with_maps.diagnostics             = &lib_maps;
    ImageBuf lib = zdenoise::regression_filter(zbuf, s.albedo, g, with_maps,
                                               &st);
    expect_matches_reference(lib, ref, k.name + " [filter]");
    expect_stats_match(st, rs, k.opt, k.name + " [filter]");
    expect_diagnostics_match(lib_maps, ref_maps, k.name + " [diagnostics]");
    if (rs.absent_windows)
        std::printf("  %-44s %lld centres with no good point (absent fit)\n",
                    k.name.c_str(), (long long)rs.absent_windows);

    if (k.whole_denoise) {
        RefImage refd = zdenoise_ref::denoise(L, La, rg, k.opt);
        ImageBuf libd = zdenoise::denoise(s.noisy, s.albedo, g, k.opt);
        expect_matches_reference(libd, refd, k.name + " [denoise]");
    }
}

}  // namespace


TEST(FilterReference, SelfEstimatedNoiseNoGuides)
{
    Case k{ "texture, estimated noise", synth::fine_texture(W, H, { 8, 11 }) };
    k.whole_denoise = true;
    run_case(k);
}

TEST(FilterReference, VarianceGuideWithQualityStops)
{
    // low noise and a loose target: many windows stop on quality
    Case k{ "texture, variance, eta 0.05", synth::fine_texture(W, H, { 64, 12 }) };
    k.variance       = true;
    k.opt.eta_target = 0.05f;
    run_case(k);
}

TEST(FilterReference, HalvesOnShadowEdge)
{
    Case k{ "shadow edge, halves", synth::shadow_edge(W, H, { 16, 13 }) };
    k.halves        = true;
    k.whole_denoise = true;
    run_case(k);
}

TEST(FilterReference, EdgeStopsAndQualityStopsWithLargerWindows)
{
    // low noise, r_max 8: windows stop on the edge (stepping back) and on
    // quality
    Case k{ "shadow edge, 64 spp, variance, r_max 8",
            synth::shadow_edge(W, H, { 64, 28 }) };
    k.variance    = true;
    k.opt.r_max   = 8;
    run_case(k);
    Case q{ "staircase, 128 spp, depth, halves, r_max 8",
            synth::staircase(W, H, 9, { 128, 29 }) };
    q.depth = q.halves = true;
    q.opt.r_max        = 8;
    q.whole_denoise    = true;
    run_case(q);
}

// The speed option: lattice windows first, then the fit points near edges
// or on surfaces the lattice misses (docs/FILTER.md section 8).
TEST(FilterReference, StridedCentres)
{
    // 80x72 with r_max 8: blocks of 64 (66 at stride 3) columns by 32 (33)
    // rows, so cells straddle block borders in x and y.
    for (int stride : { 2, 3 })
        for (int edges : { 1, 0, 2 }) {
            const std::string name = "stride " + std::to_string(stride) + ", edges "
                                     + std::to_string(edges);
            Case k{ "shadow edge, 16 spp, " + name, synth::shadow_edge(80, 72, { 16, 40 }) };
            k.opt.r_max         = 8;
            k.opt.centre_stride = stride;
            k.opt.stride_edges  = edges;
            run_case(k);
            Case q{ "staircase, 32 spp, depth, normal, " + name,
                    synth::staircase(80, 72, 5, { 32, 41 }) };
            q.depth = q.normal = true;
            q.opt.r_max         = 8;
            q.opt.centre_stride = stride;
            q.opt.stride_edges  = edges;
            q.whole_denoise     = true;
            run_case(q);
        }
}

// Large radii fitted on the pyramid's level 1 (docs/FILTER.md 5.1): radii
// 4 and 8 on the 2x2 blocks, across creases, depth steps and object ids,
// with every centre and strided.
TEST(FilterReference, PyramidFits)
{
    for (int stride : { 1, 3 }) {
        const std::string name = ", pyramid 4, stride " + std::to_string(stride);
        Case k{ "shadow edge, 16 spp, normal, depth" + name,
                synth::shadow_edge(80, 72, { 16, 40 }) };
        k.normal = k.depth      = true;
        k.opt.r_max             = 8;
        k.opt.pyramid_radius    = 4;
        k.opt.centre_stride     = stride;
        run_case(k);
        Case q{ "staircase, 32 spp, depth, normal, id" + name,
                synth::staircase(80, 72, 5, { 32, 41 }) };
        q.depth = q.normal = q.id = true;
        q.opt.r_max             = 8;
        q.opt.pyramid_radius    = 4;
        q.opt.centre_stride     = stride;
        q.whole_denoise         = true;
        run_case(q);
    }
    // The comparison is of the pyramid's fits: they are not the exact ones.
    const Scene s = synth::shadow_edge(80, 72, { 16, 40 });
    zdenoise::FilterOptions exact = small_options();
    exact.r_max                   = 8;
    zdenoise::FilterOptions pyramid = exact;
    pyramid.pyramid_radius          = 4;
    const ImageBuf z = zdenoise::demodulate(s.noisy, s.albedo);
    const std::vector<float> a = synth::pixels(
        zdenoise::regression_filter(z, s.albedo, {}, exact));
    const std::vector<float> b = synth::pixels(
        zdenoise::regression_filter(z, s.albedo, {}, pyramid));
    size_t differ = 0;
    for (size_t i = 0; i < a.size(); ++i)
        differ += std::fabs(a[i] - b[i]) > 1e-4f * std::fabs(a[i]);
    EXPECT_GT(differ, a.size() / 10);
}

// Every instruction set the fit and splat kernels are compiled for that
// this CPU runs (AVX-512, AVX2, SSE4, the portable scalar code) gives the
// reference's result, exact and on the pyramid, with every guide; and the
// sets' outputs and hat diagonals agree with each other within rounding.
TEST(FilterReference, EveryInstructionSetMatchesTheReference)
{
    const std::vector<std::string> targets = zdenoise::simd_targets();
    ASSERT_FALSE(targets.empty());
    const Scene s = synth::staircase(W, H, 5, { 16, 43 });
    const ImageBuf z = zdenoise::demodulate(s.noisy, s.albedo);
    zdenoise::Guides g;
    g.normal = &s.normal, g.depth = &s.depth, g.object_id = &s.object_id;
    std::vector<std::vector<float>> outputs, hats;
    for (const std::string& t : targets) {
        SCOPED_TRACE(t);
        ASSERT_TRUE(zdenoise::set_simd_target(t));
        Case k{ "staircase, 16 spp, depth, normal, id, halves",
                synth::staircase(W, H, 5, { 16, 43 }) };
        k.depth = k.normal = k.id = k.halves = true;
        k.opt.r_max     = 8;
        k.whole_denoise = true;
        run_case(k);
        k.name += ", pyramid 4";
        k.opt.pyramid_radius = 4;
        run_case(k);
        // The guide kernel's Cryptomatte overlap, and the powers' other
        // code paths (libm pow for the normal, exp(p log r) for the blend).
        Case c{ "cryptomatte", synth::two_objects_cryptomatte(W, H, { 8, 20 }) };
        c.id = true;
        run_case(c);
        Case p{ "staircase, normal power 2, quadrant power 3",
                synth::staircase(W, H, 5, { 16, 44 }) };
        p.normal = p.depth       = true;
        p.opt.normal_power   = 2.0f;
        p.opt.quadrant_power = 3.0f;
        run_case(p);
        // --preset spec: the method's own defaults (radius growth 1, no
        // outlier spread, the method's value term, every fit point a centre).
        Case m{ "staircase, --preset spec", synth::staircase(W, H, 5, { 16, 45 }) };
        m.normal = m.depth = true;
        m.opt       = zdenoise::FilterOptions::algorithm_defaults();
        m.opt.r_max = 5;
        run_case(m);
        // Today's filter with its hat diagonal (the selection's candidate 0).
        zdenoise::FilterOptions opt;
        opt.select = 0;
        opt.r_max  = 8;
        ImageBuf hat;
        opt.hat_diagonal = &hat;
        outputs.push_back(synth::pixels(zdenoise::regression_filter(z, s.albedo, g, opt)));
        hats.push_back(synth::pixels(hat));
        for (size_t i = 0; i < outputs.back().size(); ++i)
            ASSERT_NEAR(outputs.back()[i], outputs.front()[i],
                        1e-5f * (1.0f + std::fabs(outputs.front()[i])))
                << "pixel value " << i << " against " << targets.front();
        for (size_t i = 0; i < hats.back().size(); ++i)
            ASSERT_NEAR(hats.back()[i], hats.front()[i], 1e-4f)
                << "hat diagonal " << i << " against " << targets.front();
    }
    ASSERT_TRUE(zdenoise::set_simd_target(""));
}

TEST(FilterReference, PyramidWindowWithoutGoodPointsAtFullResolution)
{
    // The blocks' range where a window has no fine good point.
    Case k{ "corrugated patch, pyramid 4", synth::corrugated_patch(W, H, { 1024, 65 }) };
    k.normal = k.variance = true;
    k.opt.r_max          = 8;
    k.opt.pyramid_radius = 4;
    k.whole_denoise      = true;
    run_case(k);
}

TEST(FilterReference, GeometricRadiusGrowth)
{
    // radius_growth 1.5 tries radii 2, 3, 4, 6, 8 and 2 tries 2, 4, 8 (up
    // to r_max); an edge steps back to the radius tried before, not R - 1.
    for (float growth : { 1.5f, 2.0f }) {
        const std::string g = ", growth " + std::to_string(growth);
        Case k{ "shadow edge, 16 spp, normal, depth, r_max 5" + g,
                synth::shadow_edge(W, H, { 16, 31 }) };
        k.normal = k.depth  = true;
        k.opt.radius_growth = growth;
        run_case(k);
        Case q{ "staircase, 128 spp, depth, halves, r_max 8" + g,
                synth::staircase(W, H, 9, { 128, 29 }) };
        q.depth = q.halves  = true;
        q.opt.r_max         = 8;
        q.opt.radius_growth = growth;
        q.whole_denoise     = true;
        run_case(q);
    }
}

// Noise estimated from z (no variance, no halves) with windows that stop on
// quality: eta_R <= eta_target compares a value the chi-square median
// scales, so a constant off by 8e-5 (0.4549 for 0.4549364) turns one
// centre's stop near the target into a larger or smaller window, and the
// pixels few other windows reach (corners, last rows) by 3e-4.
TEST(FilterReference, EstimatedNoiseWithQualityStops)
{
    for (float growth : { 1.0f, 2.0f }) {
        const std::string g = ", growth " + std::to_string(growth);
        Case k{ "shadow edge, 16 spp, estimated, r_max 8" + g,
                synth::shadow_edge(W, H, { 16, 31 }) };
        k.opt.r_max         = 8;
        k.opt.radius_growth = growth;
        run_case(k);
        Case m{ "shadow edge, 16 spp, estimated, r_max 8, seed 45" + g,
                synth::shadow_edge(W, H, { 16, 45 }) };
        m.opt.r_max         = 8;
        m.opt.radius_growth = growth;
        run_case(m);
        Case q{ "staircase, 64 spp, depth, estimated" + g,
                synth::staircase(W, H, 9, { 64, 32 }) };
        q.depth             = true;
        q.opt.radius_growth = growth;
        run_case(q);
    }
}

TEST(FilterReference, DirectionalNoiseEstimate)
{
    // A direct layer's noise (FILTER.md 3, 14), alone and as the halves' floor.
    Case q{ "staircase, 16 spp, guides, directional", synth::staircase(W, H, 6, { 16, 33 }) };
    q.normal = q.depth = q.id = q.whole_denoise = true;
    q.opt.directional_noise = 1;
    run_case(q);
    Case h{ "shadow edge, halves, directional", synth::shadow_edge(W, H, { 8, 34 }) };
    h.halves = true, h.opt.directional_noise = 1;
    run_case(h);
}

TEST(FilterReference, VarianceGuideWinsOverHalves)
{
    Case k{ "texture, variance + halves", synth::fine_texture(W, H, { 16, 14 }) };
    k.variance = k.halves = true;
    run_case(k);
}

TEST(FilterReference, NormalGuideOnSawtooth)
{
    Case k{ "saw-tooth, normals, variance", synth::sawtooth(W, H, 3, { 8, 15 }) };
    k.normal = k.variance = true;
    run_case(k);
    Case e{ "saw-tooth, normals, estimated", synth::sawtooth(W, H, 3, { 8, 16 }) };
    e.normal = true;
    run_case(e);
}

TEST(FilterReference, DepthGuideOnStaircase)
{
    Case k{ "staircase, depth, variance", synth::staircase(W, H, 6, { 32, 17 }) };
    k.depth = k.variance = true;
    run_case(k);
    Case e{ "staircase, depth, estimated", synth::staircase(W, H, 6, { 8, 18 }) };
    e.depth = true;
    run_case(e);
}

TEST(FilterReference, PlainIdGuide)
{
    Case k{ "two objects, id, estimated", synth::two_objects(W, H, { 8, 19 }) };
    k.id  = true;
    run_case(k);
}

TEST(FilterReference, CryptomatteIdGuide)
{
    Case k{ "cryptomatte, estimated", synth::two_objects_cryptomatte(W, H, { 8, 20 }) };
    k.id            = true;
    k.whole_denoise = true;
    run_case(k);
    Case v{ "cryptomatte, variance", synth::two_objects_cryptomatte(W, H, { 8, 21 }) };
    v.id = v.variance = true;
    run_case(v);
}

TEST(FilterReference, ZeroAlbedoAndNonFiniteWithAllGuides)
{
    Case k{ "holes, all guides, variance", synth::holes(W, H, { 8, 22 }) };
    k.normal = k.depth = k.id = k.variance = true;
    k.whole_denoise                        = true;
    run_case(k);
    Case e{ "holes, estimated", synth::holes(W, H, { 8, 23 }) };
    run_case(e);
}

// Depth holes (0, 1e10, NaN: "no surface", passed through) and normals of
// zero length ("none").
TEST(FilterReference, NoSurfaceDepthAndMissingNormals)
{
    Case k{ "staircase, depth holes, null normals",
            synth::staircase(W, H, 6, { 16, 24 }) };
    k.normal = k.depth = true;
    const float holes[] = { 0.0f, 1e10f, std::numeric_limits<float>::quiet_NaN(),
                            -1.0f };
    int i = 0;
    for (int y = 2; y < H; y += 7)
        for (int x = 1 + (y % 4); x < W; x += 6, ++i) {
            float d = holes[i % 4];
            k.s.depth.setpixel(x, y, &d, 1);
        }
    const float zero[3] = { 0, 0, 0 };
    for (int x = 0; x < W; x += 3)
        k.s.normal.setpixel(x, 13, zero, 3);  // a row of "none" normals
    for (int y = 20; y < 24; ++y)
        for (int x = 30; x < 34; ++x)
            k.s.normal.setpixel(x, y, zero, 3);  // a block of them
    k.whole_denoise = true;
    run_case(k);
}

// Every option away from its default.
TEST(FilterReference, NonDefaultOptions)
{
    Case k{ "saw-tooth, all options changed", synth::sawtooth(W, H, 5, { 8, 25 }) };
    k.normal = k.depth = k.variance = true;
    zdenoise::FilterOptions& o      = k.opt;
    o.r_min          = 1;
    o.r_max          = 4;
    o.eta_target     = 0.06f;
    o.edge_k         = 1.5f;
    o.tau_min        = 0.1f;
    o.value_k        = 0.7f;
    o.sigma_good     = 0.4f;
    o.albedo_eps     = 0.02f;
    o.depth_tolerance = 0.05f;
    o.normal_cut     = 0.1f;
    o.normal_power   = 2.0f;
    o.quadrant_power = 3.0f;
    run_case(k);
}

// RGBA quotient (alpha 0 = no surface) with an extra AOV channel copied.
TEST(FilterReference, AlphaAndExtraChannels)
{
    Case k{ "texture RGBA+AOV, alpha holes", synth::fine_texture(W, H, { 8, 26 }) };
    k.variance = true;
    RefImage L  = zdenoise_ref::from_imagebuf(k.s.noisy);
    RefImage La = zdenoise_ref::from_imagebuf(k.s.albedo);
    RefImage z3 = zdenoise_ref::demodulate(L, La, k.opt.albedo_eps);
    RefImage z(W, H, 5);
    z.alpha = 3;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            for (int c = 0; c < 3; ++c)
                z.at(x, y, c) = z3.at(x, y, c);
            bool hole     = (x - 25) * (x - 25) + (y - 12) * (y - 12) < 20
                        || (x + y) % 17 == 0;
            z.at(x, y, 3) = hole ? 0.0f : (x % 5 == 0 ? 0.5f : 1.0f);
            z.at(x, y, 4) = float(x * 100 + y);  // an AOV
        }
    z.at(3, 3, 4)   = std::numeric_limits<float>::quiet_NaN();
    ImageBuf zbuf   = zdenoise_ref::to_imagebuf(z);
    ASSERT_EQ(zbuf.spec().alpha_channel, 3);
    run_case(k, &zbuf);
}

// Demodulation and remodulation: library == reference, and remodulate
// inverts demodulate, with zero, tiny, negative and non-finite albedo and
// extra channels.
TEST(FilterReference, DemodulateRemodulate)
{
    Scene s    = synth::holes(W, H, { 8, 27 });
    RefImage L = zdenoise_ref::from_imagebuf(s.noisy);
    RefImage La = zdenoise_ref::from_imagebuf(s.albedo);
    // add an alpha channel to the radiance and odd albedo values
    RefImage L4(W, H, 4);
    L4.alpha = 3;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            for (int c = 0; c < 3; ++c)
                L4.at(x, y, c) = L.at(x, y, c) * (1.0f + 10.0f * (x == 7));
            L4.at(x, y, 3) = (x + y) % 3 ? 1.0f : 0.25f;
        }
    const float odd[] = { 5e-4f, 1e-3f, -0.2f, std::numeric_limits<float>::infinity(),
                          std::numeric_limits<float>::quiet_NaN(), 1.5e-3f, 40.0f };
    for (int i = 0; i < 7; ++i)
        for (int c = 0; c < 3; ++c)
            La.at(5 + 4 * i, 30, c) = odd[(i + c) % 7];
    for (float eps : { 1e-3f, 0.05f }) {
        SCOPED_TRACE("albedo_eps " + std::to_string(eps));
        ImageBuf Lb  = zdenoise_ref::to_imagebuf(L4);
        ImageBuf Lab = zdenoise_ref::to_imagebuf(La);
        RefImage zr  = zdenoise_ref::demodulate(L4, La, eps);
        ImageBuf zl  = zdenoise::demodulate(Lb, Lab, eps);
        ASSERT_FALSE(zl.has_error()) << zl.geterror();
        RefImage zg = zdenoise_ref::from_imagebuf(zl);
        ASSERT_EQ(zg.nch, 4);
        for (size_t i = 0; i < zr.px.size(); ++i) {
            float a = zg.px[i], b = zr.px[i];
            if (!std::isfinite(b)) {  // NaN stays NaN, +-Inf stays
                EXPECT_TRUE(std::isnan(b) ? std::isnan(a) : a == b)
                    << "demodulate: library " << a << " vs reference " << b
                    << " at value " << i;
                continue;
            }
            EXPECT_LE(std::abs(a - b), 1e-6 * std::abs(b))
                << "demodulate: library " << a << " vs reference " << b
                << " at value " << i;
        }
        RefImage Lr = zdenoise_ref::remodulate(zr, La, eps);
        ImageBuf Ll = zdenoise::remodulate(zl, Lab, eps);
        ASSERT_FALSE(Ll.has_error()) << Ll.geterror();
        RefImage Lg = zdenoise_ref::from_imagebuf(Ll);
        int bad_lib = 0, bad_ref = 0;
        for (size_t i = 0; i < L4.px.size(); ++i) {
            float orig = L4.px[i];
            if (!std::isfinite(orig)) {  // NaN stays NaN, +-Inf stays
                auto same = [&](float v) {
                    return std::isnan(orig) ? std::isnan(v) : v == orig;
                };
                bad_lib += !same(Lg.px[i]);
                bad_ref += !same(Lr.px[i]);
                continue;
            }
            double tol = 1e-6 * std::abs(orig);
            bad_lib += !(std::abs(Lg.px[i] - orig) <= tol);
            bad_ref += !(std::abs(Lr.px[i] - orig) <= tol);
        }
        EXPECT_EQ(bad_lib, 0) << "library remodulate(demodulate(L)) != L";
        EXPECT_EQ(bad_ref, 0) << "reference remodulate(demodulate(L)) != L";
    }
}


// Outliers split and spread (section 3a) and a hole no window reaches filled
// (section 7): a firefly field and a 16 px NaN patch with r_max 5, with
// normals and depth.
TEST(FilterReference, FirefliesAndAHole)
{
    Case k{ "fireflies and a hole", synth::staircase(W, H, 8, { 16, 23 }) };
    k.normal = k.depth = true;
    k.whole_denoise    = true;
    std::vector<float> px = synth::pixels(k.s.noisy);
    std::mt19937 rng(5);
    for (size_t i = 0; i < px.size() / 3; ++i)
        if (rng() % 60 == 0)
            for (int c = 0; c < 3; ++c)
                px[3 * i + c] *= 30.0f;
    for (int y = 8; y < 24; ++y)
        for (int x = 10; x < 26; ++x)
            for (int c = 0; c < 3; ++c)
                px[(size_t(y) * W + x) * 3 + c] = std::numeric_limits<float>::quiet_NaN();
    k.s.noisy = synth::make_image(W, H, 3, px);
    run_case(k);
}
