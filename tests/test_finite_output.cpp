// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// From finite input, no option combination gives a NaN, an Inf or a
// negative value where the render has none (issue 32, item 4): each option
// of the filter's table at its range's ends, and random combinations of
// them, on synthetic scenes and on the bundled Cycles crop.

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/imagebufalgo.h>

#include <zdenoise/zdenoise.h>

#include "synthetic_scenes.h"

using OIIO::ImageBuf;
using OIIO::ImageSpec;
using OIIO::TypeFloat;

namespace {
const std::string kSourceDir = ZDENOISE_SOURCE_DIR;
}

namespace {

/// The first RGB value of `out` that is not finite or is negative, as text
/// ("" if none).
std::string
first_bad_value(const ImageBuf& out)
{
    const ImageSpec& s = out.spec();
    for (int y = s.y; y < s.y + s.height; ++y)
        for (int x = s.x; x < s.x + s.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const float v = out.getchannel(x, y, 0, c);
                if (!std::isfinite(v) || v < 0.0f)
                    return "pixel (" + std::to_string(x) + ", " + std::to_string(y)
                           + ") channel " + std::to_string(c) + " = " + std::to_string(v);
            }
    return "";
}

/// One filter option and the ends of its range (the command's table,
/// src/job/options.cpp, and check_options() in regression_filter.cpp).
struct OptionRange {
    const char* name;
    std::function<void(zdenoise::FilterOptions&, double)> set;
    std::vector<double> values;
};

const std::vector<OptionRange>&
option_ranges()
{
    using O = zdenoise::FilterOptions;
    static const std::vector<OptionRange> ranges = {
        { "r_min", [](O& o, double v) { o.r_min = int(v); }, { 1, 2, 4 } },
        { "r_max", [](O& o, double v) { o.r_max = int(v); }, { 4, 8, 16, 32 } },
        { "eta_target", [](O& o, double v) { o.eta_target = float(v); }, { 0, 1e-4, 0.5, 10 } },
        { "edge_k", [](O& o, double v) { o.edge_k = float(v); }, { 0, 0.5, 3, 100 } },
        { "tau_min", [](O& o, double v) { o.tau_min = float(v); }, { 0, 0.01, 1, 100 } },
        { "value_k", [](O& o, double v) { o.value_k = float(v); }, { 0, 0.1, 2, 1000 } },
        { "sigma_good", [](O& o, double v) { o.sigma_good = float(v); }, { 0, 0.1, 1, 1e30 } },
        { "albedo_eps", [](O& o, double v) { o.albedo_eps = float(v); }, { 1e-30, 1e-6, 0.1, 10 } },
        { "depth_tolerance", [](O& o, double v) { o.depth_tolerance = float(v); }, { 0, 0.001, 1, 1e6 } },
        { "normal_cut", [](O& o, double v) { o.normal_cut = float(v); }, { -1, 0, 0.9, 0.999 } },
        { "normal_power", [](O& o, double v) { o.normal_power = float(v); }, { 1e-3, 1, 16, 1000 } },
        { "quadrant_power", [](O& o, double v) { o.quadrant_power = float(v); }, { 0, 1, 3, 100 } },
        { "radius_growth", [](O& o, double v) { o.radius_growth = float(v); }, { 1, 1.5, 4 } },
        { "centre_stride", [](O& o, double v) { o.centre_stride = int(v); }, { 1, 2, 3, 8 } },
        { "stride_edges", [](O& o, double v) { o.stride_edges = int(v); }, { 0, 1, 2 } },
        { "outlier_spread", [](O& o, double v) { o.outlier_spread = int(v); }, { 0, 1 } },
        { "value_noise", [](O& o, double v) { o.value_noise = int(v); }, { 0, 1 } },
        { "select", [](O& o, double v) { o.select = int(v); }, { 0, 1 } },
        { "pyramid_radius", [](O& o, double v) { o.pyramid_radius = int(v); }, { 0, 4, 8, 16 } },
    };
    return ranges;
}

/// A combination the filter refuses (r_max below r_min, a pyramid radius
/// above r_max is allowed): skipped, not an error of this test.
bool
refused(const zdenoise::FilterOptions& o)
{
    return o.r_max < o.r_min;
}

struct Input {
    std::string name;
    ImageBuf radiance, albedo, normal, depth, id;
    zdenoise::Guides guides() const
    {
        zdenoise::Guides g;
        g.normal    = normal.initialized() ? &normal : nullptr;
        g.depth     = depth.initialized() ? &depth : nullptr;
        g.object_id = id.initialized() ? &id : nullptr;
        return g;
    }
};

Input
from_scene(const synth::Scene& s, bool id = true)
{
    Input in;
    in.name     = s.name;
    in.radiance = s.noisy;
    in.albedo   = s.albedo;
    in.normal   = s.normal;
    in.depth    = s.depth;
    if (id)
        in.id = s.object_id;
    return in;
}

/// Denoise `in` with `opt`; a refusal fails, a bad value fails with the
/// options named.
void
expect_finite(const Input& in, const zdenoise::FilterOptions& opt, const std::string& what)
{
    ImageBuf out;
    const zdenoise::Guides g = in.guides();
    ASSERT_TRUE(zdenoise::denoise(out, in.radiance, in.albedo, g, opt)) << in.name << ", " << what
                                                                       << ": " << out.geterror();
    const std::string bad = first_bad_value(out);
    EXPECT_EQ(bad, "") << in.name << ", " << what;
}

/// The synthetic inputs: texture, steps, Cryptomatte objects, fireflies and
/// zero albedo, at 2 spp (the noisiest, where windows grow most).
std::vector<Input>
synthetic_inputs()
{
    const int W = 40, H = 32;
    std::vector<Input> in;
    in.push_back(from_scene(synth::fine_texture(W, H, { 2, 61 })));
    in.push_back(from_scene(synth::staircase(W, H, 6, { 2, 62 })));
    in.push_back(from_scene(synth::two_objects_cryptomatte(W, H, { 2, 63 })));
    in.push_back(from_scene(synth::shadow_edge(W, H, { 2, 64 })));
    return in;
}

}  // namespace


// A window fitted on the pyramid's level 1 whose full-resolution pixels hold
// no good fit point (synth::corrugated_patch): its radiance range at full
// resolution is empty, and the splat clamped to it gave -Inf (issue 32's
// three infinite pixels at --rmax 32 --pyramid 16). It takes the range of
// the blocks it was fitted on.
TEST(FiniteOutput, PyramidWindowWithoutGoodPointsAtFullResolution)
{
    const synth::Scene s = synth::corrugated_patch(40, 40, { 1024, 65 });
    zdenoise::Guides g;
    g.normal   = &s.normal;
    g.variance = &s.variance;
    for (int select : { 0, 1 }) {
        zdenoise::FilterOptions opt;
        opt.select         = select;
        opt.r_max          = 8;
        opt.pyramid_radius = 4;
        opt.centre_stride  = 1;
        ImageBuf out;
        ASSERT_TRUE(zdenoise::denoise(out, s.noisy, s.albedo, g, opt)) << out.geterror();
        EXPECT_EQ(first_bad_value(out), "") << "select " << select;
        // And within the light the render has (0.5, nearly noise-free).
        EXPECT_NEAR(synth::mean_luminance(out, 16, 24, 16, 24), 0.25, 0.01)
            << "select " << select;
    }
}


// Each option at the ends of its range, the others at their defaults.
TEST(FiniteOutput, EachOptionAtTheEndsOfItsRange)
{
    for (const Input& in : synthetic_inputs())
        for (const OptionRange& r : option_ranges())
            for (double v : r.values) {
                zdenoise::FilterOptions opt;
                r.set(opt, v);
                if (refused(opt))
                    continue;
                expect_finite(in, opt, std::string(r.name) + " = " + std::to_string(v));
            }
}


// Random combinations of the ends of every option's range (a fixed seed:
// the same combinations on every run).
TEST(FiniteOutput, RandomCombinationsOfOptions)
{
    std::mt19937 rng(32);
    const std::vector<Input> inputs = synthetic_inputs();
    for (int k = 0; k < 48; ++k) {
        zdenoise::FilterOptions opt;
        std::string what;
        for (const OptionRange& r : option_ranges()) {
            const double v = r.values[rng() % r.values.size()];
            r.set(opt, v);
            what += std::string(r.name) + "=" + std::to_string(v) + " ";
        }
        if (refused(opt))
            continue;
        expect_finite(inputs[size_t(k) % inputs.size()], opt, what);
    }
}


// The bundled Cycles crop (16 spp, real fireflies, HDR lamp): the ends of
// the radii, the pyramid and the selection together.
TEST(FiniteOutput, CyclesCropWithLargeWindowsAndThePyramid)
{
    ImageBuf file(kSourceDir + "/share/samples/cornell_textured_spp16_crop.exr");
    ASSERT_TRUE(file.read(0, 0, true, TypeFloat)) << file.geterror();
    auto pass = [&](const std::vector<std::string>& names) {
        std::vector<int> order;
        for (const std::string& n : names)
            order.push_back(file.spec().channelindex("ViewLayer." + n));
        ImageBuf b;
        EXPECT_TRUE(OIIO::ImageBufAlgo::channels(b, file, int(order.size()), order))
            << b.geterror();
        return b;
    };
    Input in;
    in.name     = "cornell_textured crop";
    in.radiance = pass({ "Combined.R", "Combined.G", "Combined.B" });
    in.albedo   = pass({ "Denoising Albedo.R", "Denoising Albedo.G", "Denoising Albedo.B" });
    in.normal   = pass({ "Denoising Normal.X", "Denoising Normal.Y", "Denoising Normal.Z" });
    in.depth    = pass({ "Denoising Depth.Z" });
    in.id       = pass({ "CryptoObject00.r", "CryptoObject00.g", "CryptoObject00.b",
                         "CryptoObject00.a" });
    for (int r_max : { 16, 32 })
        for (int pyramid : { 0, 4, 16 })
            for (int select : { 0, 1 }) {
                zdenoise::FilterOptions opt;
                opt.r_max          = r_max;
                opt.pyramid_radius = pyramid;
                opt.select         = select;
                expect_finite(in, opt,
                              "r_max " + std::to_string(r_max) + ", pyramid "
                                  + std::to_string(pyramid) + ", select "
                                  + std::to_string(select));
            }
}
