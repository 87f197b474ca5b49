// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The job streams a frame through in strips of rows (src/job/job.h,
// --tile): a run in strips writes exactly the file the whole-frame run
// writes (every pixel of every channel, in its pixel type, and the
// metadata), from scanline or tiled files, in beauty and layers mode; and
// its memory follows the strip, not the frame.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "cli_test.h"

using namespace OIIO;
using namespace cli_test;

namespace {

/// A number in [0, 1) from a pixel and a seed: noise without the state of
/// a random generator, so that any band of rows is written alone.
float
hash01(uint32_t x, uint32_t y, uint32_t seed)
{
    uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ seed * 0xcb1ab31fu;
    h ^= h >> 13;
    h *= 0x5bd1e995u;
    h ^= h >> 15;
    return float(h >> 8) / float(1 << 24);
}

/// What write_frame() puts in a file.
struct FrameOptions {
    int width = 0, height = 0;
    float noise = 0.02f;  ///< relative amplitude of the noise
    int tile    = 0;      ///< 0: scanlines; else tiles of this size
    int x = 0, y = 0;     ///< data window origin
    bool passes = true;   ///< Cryptomatte, more passes, metadata
    float sky   = 0.05f;  ///< share of the rows (at the top) without surface
    bool lobes  = false;  ///< Cycles' lobe passes (for --mode layers)
    const char* compression = "zip";
};

/// A Blender Cycles style multilayer EXR with real surfaces: a floor, a
/// back wall and a box in front of it (each its own normal, depth and
/// object), a checker albedo, smooth light with multiplicative noise, sky
/// (no surface) above. Written a band of rows at a time:
/// never whole in memory.
void
write_frame(const std::string& path, const FrameOptions& o)
{
    const std::string P = "ViewLayer.";
    std::vector<std::string> names;
    std::vector<TypeDesc> types;
    auto add = [&](const std::string& layer, const char* comps, TypeDesc t) {
        for (const char* c = comps; *c; ++c) {
            names.push_back(P + layer + "." + std::string(1, *c));
            types.push_back(t);
        }
    };
    add("Combined", "RGBA", TypeHalf);
    add("Denoising Albedo", "RGB", TypeHalf);
    add("Denoising Normal", "XYZ", TypeFloat);
    add("Denoising Depth", "Z", TypeFloat);
    if (o.passes) {
        for (int k = 0; k < 4; ++k) {
            names.push_back(P + "CryptoObject00." + std::string(1, "rgba"[k]));
            types.push_back(TypeFloat);
        }
        add("DiffCol", "RGB", TypeHalf);
        add("IndexOB", "X", TypeFloat);
    }
    if (o.lobes) {
        add("DiffDir", "RGB", TypeHalf);
        add("DiffInd", "RGB", TypeHalf);
        add("GlossCol", "RGB", TypeHalf);
        add("GlossDir", "RGB", TypeHalf);
        add("GlossInd", "RGB", TypeHalf);
        add("Emit", "RGB", TypeHalf);
        add("Env", "RGB", TypeHalf);
    }
    const int nch = int(names.size());
    ImageSpec spec(o.width, o.height, nch, TypeHalf);
    spec.x = spec.full_x = o.x;
    spec.y = spec.full_y = o.y;
    spec.channelnames    = names;
    spec.channelformats  = types;
    spec.alpha_channel   = 3;
    spec.attribute("compression", o.compression);
    if (o.tile)
        spec.tile_width = spec.tile_height = o.tile;
    if (o.passes) {
        spec.attribute("cryptomatte/3ae39a5/name", P + "CryptoObject");
        spec.attribute("cryptomatte/3ae39a5/hash", "MurmurHash3_32");
        spec.attribute("zdenoise_test.note", "streamed");
    }
    auto out = ImageOutput::create(path);
    ASSERT_TRUE(out && out->open(path, spec)) << OIIO::geterror();

    const int band = o.tile ? o.tile : 64;
    std::vector<float> px(size_t(nch) * size_t(o.width) * size_t(band));
    const float ids[3] = { 1.5e-3f, -2.75e7f, 6.125e-12f };  // hash-like
    for (int y0 = 0; y0 < o.height; y0 += band) {
        const int y1 = std::min(y0 + band, o.height);
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < o.width; ++x) {
                float* p = &px[(size_t(y - y0) * size_t(o.width) + size_t(x))
                               * size_t(nch)];
                const float u = float(x) / float(o.width);
                const float v = float(y) / float(o.height);
                // 0 sky, 1 floor, 2 wall, 3 box (in front, on the floor).
                int obj = v < o.sky ? 0 : v > 0.6f ? 1 : 2;
                if (obj && u > 0.3f && u < 0.55f && v > 0.35f && v < 0.8f)
                    obj = 3;
                const float n[4][3] = { { 0, 0, 0 },
                                        { 0, 1, 0 },
                                        { 0, 0, 1 },
                                        { 0.6f, 0.2f, 0.77f } };
                const float depth = obj == 0   ? 0.0f
                                    : obj == 1 ? 2.0f + 8.0f * (1.0f - v)
                                    : obj == 2 ? 10.0f
                                               : 6.0f + u;
                const bool check = ((x / 5) + (y / 5)) % 2 == 0;
                const float alb[3] = { check ? 0.7f : 0.3f,
                                       obj == 3 ? 0.2f : 0.5f,
                                       0.4f + 0.1f * float(obj) };
                const float light = obj == 0 ? 0.0f
                                             : (0.4f + 0.6f * u) * (obj == 1 ? 0.8f : 1.0f);
                const float grain = 1.0f + o.noise * (2.0f * hash01(uint32_t(x), uint32_t(y), 1) - 1.0f);
                for (int c = 0; c < 3; ++c)
                    p[c] = obj == 0 ? 0.05f : alb[c] * light * grain;
                p[3] = 1.0f;
                for (int c = 0; c < 3; ++c)
                    p[4 + c] = obj == 0 ? 0.0f : alb[c];
                for (int c = 0; c < 3; ++c)
                    p[7 + c] = n[obj][c];
                p[10] = depth;
                float* q = p + 11;
                if (o.passes) {
                    q[0] = obj ? ids[obj - 1] : 0.0f;
                    q[1] = obj ? 1.0f : 0.0f;
                    q[2] = q[3] = 0.0f;
                    for (int k = 0; k < 3; ++k)
                        q[4 + k] = alb[k];  // DiffCol
                    q[7] = float(obj);      // IndexOB
                    q += 8;
                }
                if (o.lobes)
                    for (int k = 0; k < 3; ++k) {
                        q[k]      = 0.7f * light * grain;     // DiffDir
                        q[3 + k]  = 0.2f * light * grain;     // DiffInd
                        q[6 + k]  = 0.04f;                    // GlossCol
                        q[9 + k]  = 0.5f * light * grain;     // GlossDir
                        q[12 + k] = 0.0f;                     // GlossInd
                        q[15 + k] = 0.0f;                     // Emit
                        q[18 + k] = obj == 0 ? 0.05f : 0.0f;  // Env
                    }
            }
        const bool ok = o.tile ? out->write_tiles(o.x, o.x + o.width, o.y + y0,
                                                  o.y + y1, 0, 1, TypeFloat,
                                                  px.data())
                               : out->write_scanlines(o.y + y0, o.y + y1, 0,
                                                      TypeFloat, px.data());
        ASSERT_TRUE(ok) << out->geterror();
    }
    ASSERT_TRUE(out->close()) << out->geterror();
}

/// Expect two files to hold the same image: data and display windows,
/// channels, each channel's pixel type, every pixel bit for bit, and the
/// metadata (all but the time of writing).
void
expect_same_file(const std::string& a, const std::string& b)
{
    auto ia = ImageInput::open(a), ib = ImageInput::open(b);
    ASSERT_TRUE(ia && ib) << OIIO::geterror();
    const ImageSpec &sa = ia->spec(), &sb = ib->spec();
    ASSERT_EQ(sa.roi(), sb.roi());
    EXPECT_EQ(sa.roi_full(), sb.roi_full());
    ASSERT_EQ(sa.channelnames, sb.channelnames);
    for (int c = 0; c < sa.nchannels; ++c)
        ASSERT_EQ(sa.channelformat(c), sb.channelformat(c)) << sa.channelnames[size_t(c)];
    auto attributes = [](const ImageSpec& s) {
        std::vector<std::string> v;
        for (const ParamValue& p : s.extra_attribs)
            if (p.name() != "DateTime")
                v.push_back(p.name().string() + "=" + p.get_string(0));
        std::sort(v.begin(), v.end());
        return v;
    };
    EXPECT_EQ(attributes(sa), attributes(sb));
    const size_t row = sa.scanline_bytes(true);
    std::vector<unsigned char> pa(row * 64), pb(row * 64);
    for (int y = sa.y; y < sa.y + sa.height; y += 64) {
        const int y1 = std::min(y + 64, sa.y + sa.height);
        ASSERT_TRUE(ia->read_scanlines(0, 0, y, y1, 0, 0, sa.nchannels,
                                       TypeUnknown, pa.data()));
        ASSERT_TRUE(ib->read_scanlines(0, 0, y, y1, 0, 0, sb.nchannels,
                                       TypeUnknown, pb.data()));
        ASSERT_EQ(std::memcmp(pa.data(), pb.data(), row * size_t(y1 - y)), 0)
            << "rows " << y << "-" << y1 - 1 << " differ";
    }
}

class StreamTest : public CliTest {};

}  // namespace


TEST_F(StreamTest, StripsWriteTheWholeFrameFileAt1080p)
{
    // Low noise (windows stop small) and sky above most rows keep the
    // filter quick; strip boundaries fall in the sky and on the surfaces
    // below it.
    FrameOptions f { 1920, 1080, 0.01f };
    f.sky = 0.85f;
    write_frame(path("frame.exr"), f);
    RunResult whole = run("--in " + path("frame.exr") + " -o " + path("whole.exr")
                          + " --tile 1080 -v");
    ASSERT_EQ(whole.status, 0) << whole.err;
    EXPECT_NE(whole.out.find("whole frame at once"), std::string::npos) << whole.out;
    RunResult strips = run("--in " + path("frame.exr") + " -o " + path("strips.exr")
                           + " --tile 96 -v");
    ASSERT_EQ(strips.status, 0) << strips.err;
    // The halo: the filter's 2 * 16 + 6 + 2 and the selection's 44 (its
    // choice's 10, the feature regressions' 31, the noise bound's 3), the
    // energy correction's 3 * 12 + 1 (docs/FILTER.md section 7b), and one
    // for the alpha's test of the filtered coverage (denoise_alpha()).
    EXPECT_NE(strips.out.find("12 strips of 96 rows, each read with 122 rows of halo"),
              std::string::npos)
        << strips.out;
    expect_same_file(path("whole.exr"), path("strips.exr"));

    // The statistics do not depend on the strips either.
    auto stats_line = [](const std::string& out) {
        const size_t at = out.find("zdenoise: windows");
        return out.substr(at, out.find('\n', at) - at);
    };
    EXPECT_EQ(stats_line(whole.out), stats_line(strips.out));
}


TEST_F(StreamTest, StripsOfTiledFilesOffsetWindowsAndLayersAreExact)
{
    // A tiled input whose data window is not at the origin; a guide from
    // another file covering more pixels (cut to the noisy input's); layers
    // with their denoised AOVs; output types from -d; strips of one row.
    FrameOptions f { 160, 120, 0.05f, 32, 7, -5 };
    f.lobes = true;
    write_frame(path("tiled.exr"), f);
    FrameOptions big { 190, 160, 0.05f, 0, 0, -20 };
    big.passes = false;
    write_frame(path("guides.exr"), big);
    // Rows read around a strip: the filter's halo, 2 * 6 + 6 + 2 (the
    // default stride 3 reaches 2 further), the selection's 44, and in
    // layers mode also the reach of the residual layer's mask, r_max; one
    // more for the alpha's test of the filtered coverage (the frame has
    // Combined.A), and in path mode the direct layer's test, which reads
    // the same row, and the direct light's routing, 3 + 2 * 8. The energy
    // correction's reach (docs/FILTER.md section 7b) is cut to 3 * 2 + 1
    // so that strips of one row stay quick; it is exact all the same.
    struct Case {
        const char* name;
        std::string args;
        const char* tile;
        const char* around;
    } cases[] = {
        { "beauty", " --mode beauty", "1", "72" },
        { "path (no flags: the file has DiffDir)", "", "1", "97" },
        { "layers", " --mode layers --aovs -d float", "23", "78" },
        // The layers' colours prefiltered: 5 rows more for the prefilter.
        { "layers, prefiltered colours", " --mode layers --albedo-samples 4", "23", "83" },
        { "guide file",
          " --mode beauty --normal:ch=\"Denoising Normal\" " + path("guides.exr"), "50", "72" },
        { "today's filter", " --mode beauty --select 0", "1", "28" },
        // The box core (docs/FILTER.md section 15): radius 8 on cells of 2
        // reaches 20, the choice 7, the noise 6, the correction 7 (40), and
        // path mode's own reach as above (26).
        { "box core, path", " --core 1 --box-radius 8", "5", "66" },
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const std::string common = "--in " + path("tiled.exr") + c.args
                                   + " --rmax 6 --energy-radius 2";
        RunResult whole = run(common + " -o " + path("whole.exr") + " --tile 120");
        ASSERT_EQ(whole.status, 0) << whole.err;
        RunResult strips = run(common + " -o " + path("strips.exr") + " --tile " + c.tile
                               + " -v");
        ASSERT_EQ(strips.status, 0) << strips.err;
        EXPECT_NE(strips.out.find(std::string(" strips of ") + c.tile
                                  + " rows, each read with " + c.around + " rows"),
                  std::string::npos)
            << strips.out;
        expect_same_file(path("whole.exr"), path("strips.exr"));
    }

    // Automatic: a small frame is denoised whole; --tile is carried by a
    // recipe (share/zdn-format.md).
    RunResult automatic = run("--in " + path("tiled.exr") + " -o " + path("auto.exr") + " -v");
    ASSERT_EQ(automatic.status, 0) << automatic.err;
    EXPECT_NE(automatic.out.find("whole frame at once"), std::string::npos) << automatic.out;
    RunResult recipe = run("--in " + path("tiled.exr") + " --tile 40 --write-recipe "
                           + path("shot.zdn"));
    ASSERT_EQ(recipe.status, 0) << recipe.err;
    EXPECT_NE(slurp(path("shot.zdn")).find("\"tile\": 40"), std::string::npos)
        << slurp(path("shot.zdn"));
}


TEST_F(StreamTest, MemoryFollowsTheStripNotTheFrame)
{
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "AddressSanitizer's shadow memory and quarantine make "
                    "resident memory meaningless";
#elif defined(__has_feature)
#    if __has_feature(address_sanitizer)
    GTEST_SKIP() << "AddressSanitizer's shadow memory and quarantine make "
                    "resident memory meaningless";
#    endif
#endif
    // 2048 x 8192 with albedo, normal and depth: as float, the inputs the
    // filter uses alone are 2048 * 8192 * 11 * 4 bytes = 704 MiB. Tall, so
    // that a strip (64 rows and twice the halo of 84, with the selection's
    // planes, about 256 bytes a pixel) is a small part of it. Mostly sky,
    // so that the filter has little to do, and run-length encoded, which
    // is quick to write and read.
    const int w = 2048, h = 8192;
    FrameOptions f { w, h, 0.0f };
    f.passes      = false;
    f.sky         = 0.99f;
    f.compression = "rle";
    write_frame(path("big.exr"), f);
    const double whole_frame = double(w) * h * 11 * 4;
    RunResult r = cli_harness::run_command(
        cli_harness::quoted(ZDENOISE_PEAK_RSS) + " " + cli_harness::quoted(ZDENOISE_CLI)
            + " --in " + path("big.exr") + " -o " + path("out.exr") + " --tile 64",
        path(".run"));
    ASSERT_EQ(r.status, 0) << r.err;
    const int64_t peak = std::stoll(r.out) * 1024;
    // Half of it: the program and its libraries alone take ~130 MiB; the
    // strips of 64 rows, a few tens.
    EXPECT_LT(double(peak), 0.5 * whole_frame)
        << "peak resident memory " << peak / (1 << 20) << " MiB";
    std::printf("  2048x8192 in strips of 64 rows: peak %lld MiB (the "
                "inputs used, as float: %.0f MiB)\n",
                (long long)(peak >> 20), whole_frame / (1 << 20));
}
