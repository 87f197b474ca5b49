// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Bad inputs as a render farm produces them: truncated and empty files,
// files of the wrong format, mismatched or oversized images, missing
// channels, non-finite and extreme values, unwritable or full output
// locations, interruption. Each bad file is refused the same way by the
// command and by the job library the OIIO plugin uses: one line naming the
// file and the problem, a non-zero exit, no crash, no file left behind and
// an existing output untouched. Extreme values are not errors: the result
// is defined (docs/FILTER.md section 10), never NaN and never a firefly.

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imagecache.h>

#include <zdenoise/zdenoise.h>

#include "job/job.h"
#include "cli_test.h"

extern char** environ;

using namespace OIIO;
using namespace cli_test;
namespace job = zdenoise::job;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

/// Count the non-finite values in channels [0, nch) of `img`.
int64_t
count_nonfinite(const ImageBuf& img, int nch = 3)
{
    int64_t n = 0;
    for (ImageBuf::ConstIterator<float> it(img); !it.done(); ++it)
        for (int c = 0; c < nch; ++c)
            n += !std::isfinite(it[c]);
    return n;
}

class BadInputTest : public CliTest {
protected:
    /// The job the command line `--in noisy --albedo albedo -o out` runs.
    job::Job make_job(const std::string& noisy, const std::string& albedo) const
    {
        job::Job j;
        j.in     = { noisy, "", true };
        j.albedo = { albedo, "", true };
        return j;
    }

    /// The command line running `j` into `output`.
    static std::string cli_args(const job::Job& j, const std::string& output)
    {
        std::string args;
        auto input = [&](const char* opt, const job::InputArg& a) {
            if (a.given)
                args += std::string(" ") + opt
                        + (a.channels.empty() ? "" : ":ch=" + a.channels)
                        + " '" + a.path + "'";
        };
        input("--in", j.in);
        input("--albedo", j.albedo);
        input("--normal", j.normal);
        input("--depth", j.depth);
        if (j.mem_limit)
            args += " --mem-limit " + std::to_string(j.mem_limit);
        return args + " -o '" + output + "'";
    }

    /// Expect `j` refused by the command and by run_job, each with one line
    /// containing every one of `needles`; an existing output must survive
    /// and no file may appear.
    void expect_refused(const job::Job& j, std::vector<std::string> needles)
    {
        SCOPED_TRACE("job on '" + j.in.path + "'");
        write_image("out.exr", 4, 4, { "R", "G", "B" }, 0.25f);
        const std::string old_output        = slurp(path("out.exr"));
        const std::vector<std::string> before = files();

        RunResult r = run(cli_args(j, path("out.exr")));
        for (const std::string& needle : needles)
            expect_one_line_error(r, needle);
        EXPECT_EQ(r.status, 1);
        EXPECT_EQ(slurp(path("out.exr")), old_output)
            << "an existing output must be untouched";
        EXPECT_EQ(files(), before) << "no file may be left behind";

        job::JobResult result;
        std::string error;
        EXPECT_FALSE(job::run_job(j, result, error));
        EXPECT_EQ(error.find('\n'), std::string::npos) << error;
        for (const std::string& needle : needles)
            EXPECT_NE(error.find(needle), std::string::npos)
                << "run_job's error should name '" << needle << "': " << error;
        Filesystem::remove(path("out.exr"));
    }

    /// Run `j` through the command into out.exr and return the output.
    ImageBuf denoise_with_cli(const job::Job& j, const std::string& extra = "")
    {
        RunResult r = run(cli_args(j, path("out.exr")) + extra);
        EXPECT_EQ(r.status, 0) << r.err;
        // Written by another process: not what OIIO's cache may hold.
        ImageCache::create(true)->invalidate(ustring(path("out.exr")), true);
        ImageBuf out(path("out.exr"));
        EXPECT_TRUE(out.read(0, 0, true, TypeFloat)) << out.geterror();
        return out;
    }

    /// A 32x32 noisy RGB image and a matching albedo.
    job::Job small_job()
    {
        write_image("noisy.exr", 32, 32, { "R", "G", "B" }, 0.5f);
        write_image("albedo.exr", 32, 32, { "R", "G", "B" }, 0.5f);
        return make_job(path("noisy.exr"), path("albedo.exr"));
    }
};

}  // namespace


TEST_F(BadInputTest, TruncatedExrAtAnyOffsetIsRefused)
{
    // A render node that crashed mid-write leaves a prefix of the file.
    ImageSpec spec(64, 64, 3, TypeHalf);
    ImageBuf noisy(spec);
    ImageBufAlgo::noise(noisy, "uniform", 0.0f, 1.0f, false, 1);
    ASSERT_TRUE(noisy.write(path("whole.exr")));
    write_image("albedo.exr", 64, 64, { "R", "G", "B" }, 0.5f);
    const std::string whole = slurp(path("whole.exr"));
    ASSERT_GT(whole.size(), 1000u);
    for (size_t cut : { size_t(3), size_t(40), size_t(300), whole.size() / 2,
                        whole.size() - 100, whole.size() - 1 }) {
        SCOPED_TRACE("cut at " + std::to_string(cut) + " of "
                     + std::to_string(whole.size()));
        const std::string name = "cut" + std::to_string(cut) + ".exr";
        std::ofstream(path(name), std::ios::binary) << whole.substr(0, cut);
        expect_refused(make_job(path(name), path("albedo.exr")), { name });
        expect_refused(make_job(path("whole.exr"), path(name)), { name });
        Filesystem::remove(path(name));
    }
}


TEST_F(BadInputTest, EmptyFileIsRefused)
{
    job::Job j = small_job();
    std::ofstream(path("empty.exr")).close();
    j.albedo.path = path("empty.exr");
    expect_refused(j, { "empty.exr", "empty" });
}


TEST_F(BadInputTest, PngNamedExrIsRefused)
{
    ImageBuf png(ImageSpec(32, 32, 3, TypeUInt8));
    ImageBufAlgo::fill(png, { 0.5f, 0.5f, 0.5f });
    ASSERT_TRUE(png.write(path("picture.png")));
    Filesystem::rename(path("picture.png"), path("renamed.exr"));
    job::Job j = small_job();
    j.albedo.path = path("renamed.exr");
    expect_refused(j, { "renamed.exr", "png" });
}


TEST_F(BadInputTest, DeepExrIsRefused)
{
    ImageSpec spec(8, 8, 3, TypeFloat);
    spec.deep = true;
    ImageBuf deep(spec);
    ASSERT_TRUE(deep.write(path("deep.exr"))) << deep.geterror();
    write_image("albedo.exr", 8, 8, { "R", "G", "B" }, 0.5f);
    expect_refused(make_job(path("deep.exr"), path("albedo.exr")),
                   { "deep.exr", "deep" });
}


TEST_F(BadInputTest, GuideOfAnotherSizeOrPlaceIsRefused)
{
    job::Job j = small_job();
    write_image("small.exr", 16, 16, { "X", "Y", "Z" }, 0.5f);
    j.normal = { path("small.exr"), "", true };
    expect_refused(j, { "small.exr", "16x16" });

    // Same size, shifted data window: other pixels.
    ImageSpec spec(32, 32, 3, TypeFloat);
    spec.x = 8;
    ImageBuf shifted(spec);
    ASSERT_TRUE(shifted.write(path("shifted.exr")));
    j.normal = {};
    j.albedo.path = path("shifted.exr");
    expect_refused(j, { "shifted.exr", "32x32+8+0" });
}


TEST_F(BadInputTest, CroppedDataWindowIsDenoisedInPlace)
{
    // Renderers write a crop (data window) inside the frame (display
    // window); the output keeps both, and a guide covering the whole frame
    // is cut to the crop.
    ImageSpec spec(24, 16, 3, TypeFloat);
    spec.x = 10, spec.y = 20;
    spec.full_x = 0, spec.full_y = 0, spec.full_width = 64,
    spec.full_height = 48;
    ImageBuf noisy(spec);
    ImageBufAlgo::fill(noisy, { 0.5f, 0.5f, 0.5f });
    ASSERT_TRUE(noisy.write(path("crop.exr")));
    ImageBuf albedo(spec);
    ImageBufAlgo::fill(albedo, { 0.5f, 0.5f, 0.5f });
    ASSERT_TRUE(albedo.write(path("albedo_crop.exr")));
    write_image("albedo_full.exr", 64, 48, { "R", "G", "B" }, 0.5f);

    for (const char* albedo_name : { "albedo_crop.exr", "albedo_full.exr" }) {
        SCOPED_TRACE(albedo_name);
        ImageBuf out = denoise_with_cli(make_job(path("crop.exr"),
                                                 path(albedo_name)));
        const ImageSpec& s = out.spec();
        EXPECT_EQ(ROI(s.x, s.x + s.width, s.y, s.y + s.height),
                  ROI(10, 34, 20, 36));
        EXPECT_EQ(ROI(s.full_x, s.full_x + s.full_width, s.full_y,
                      s.full_y + s.full_height),
                  ROI(0, 64, 0, 48));
        EXPECT_NEAR(out.getchannel(12, 22, 0, 1), 0.5f, 1e-4f)
            << "a constant image stays constant";
    }
}


TEST_F(BadInputTest, MissingOrMisnamedChannelsAreRefused)
{
    job::Job j = small_job();
    write_image("normal.exr", 32, 32, { "N.x", "N.y" }, 0.5f);
    j.normal = { path("normal.exr"), "", true };
    expect_refused(j, { "normal.exr", "normal" });

    j.normal = { path("normal.exr"), "Normal", true };
    expect_refused(j, { "normal.exr", "Normal" });

    j.normal = {};
    j.depth  = { path("albedo.exr"), "Z", true };
    expect_refused(j, { "albedo.exr", "Z" });
}


TEST_F(BadInputTest, FrameTooLargeForMemoryIsRefusedBeforeReading)
{
    // A header declaring 100000 x 100000 pixels (a corrupt or absurd
    // render): the files hold no pixels. The frame streams in strips, but
    // even a strip of this width needs more than a small limit.
    auto empty_file = [&](const std::string& name, bool tiled) {
        ImageSpec spec(100000, 100000, 4, TypeHalf);
        if (tiled)
            spec.tile_width = spec.tile_height = 4096;
        spec.attribute("compression", "zip");
        auto out = ImageOutput::create(path(name));
        ASSERT_TRUE(out && out->open(path(name), spec)) << OIIO::geterror();
        out->close();
        ASSERT_LT(Filesystem::file_size(path(name)), 100000u);
    };
    empty_file("huge.exr", true);
    job::Job huge = make_job(path("huge.exr"), path("huge.exr"));
    huge.mem_limit = uint64_t(1) << 30;
    expect_refused(huge, { "huge.exr", "100000x100000", "memory limit", "strips of" });

    // With room for a strip, the frame's size is no reason to refuse it: it
    // streams (and this one fails at its first missing pixels). The job
    // keeping its output in memory (run_job) is still refused.
    empty_file("huge_scanlines.exr", false);
    huge = make_job(path("huge_scanlines.exr"), path("huge_scanlines.exr"));
    huge.mem_limit = uint64_t(64) << 30;
    RunResult streamed = run(cli_args(huge, path("out.exr")));
    expect_one_line_error(streamed, "cannot read '" + path("huge_scanlines.exr") + "'");
    EXPECT_EQ(streamed.err.find("memory limit"), std::string::npos) << streamed.err;
    EXPECT_EQ(files(), (std::vector<std::string> { "huge.exr", "huge_scanlines.exr" }));
    job::JobResult in_memory;
    std::string error;
    EXPECT_FALSE(job::run_job(huge, in_memory, error));
    EXPECT_NE(error.find("memory limit"), std::string::npos) << error;

    // Any frame, with a limit too low for it.
    job::Job j   = small_job();
    j.mem_limit  = 100000;
    expect_refused(j, { "noisy.exr", "32x32", "memory limit" });
    j.mem_limit = 100 << 20;
    denoise_with_cli(j);

    RunResult r = run(cli_args(small_job(), path("out.exr"))
                      + " --mem-limit lots");
    expect_one_line_error(r, "--mem-limit");
    EXPECT_EQ(r.status, 2);
}


TEST_F(BadInputTest, MemoryGuardCountsTheLayers)
{
    // Arnold-style AOVs: the beauty with its albedo, and two layers with
    // theirs. Layers mode holds each layer's images besides the beauty's.
    std::vector<std::string> channels = { "R", "G", "B" };
    for (const char* layer : { "albedo", "diffuse", "diffuse_albedo",
                               "specular", "specular_albedo" })
        for (const char* c : { ".R", ".G", ".B" })
            channels.push_back(std::string(layer) + c);
    write_image("aovs.exr", 256, 256, channels, 0.5f);
    auto needed_mib = [&](const std::string& mode) {
        // The whole frame as one strip (--tile 256): its layers' share.
        RunResult r = run("--in " + path("aovs.exr") + " --mode " + mode
                          + " --tile 256 --mem-limit 1M -o " + path("out.exr"));
        expect_one_line_error(r, "memory limit");
        const size_t at = r.err.find("needs about ");
        EXPECT_NE(at, std::string::npos) << r.err;
        return at == std::string::npos ? 0.0
                                       : std::stod(r.err.substr(at + 12));
    };
    const double beauty = needed_mib("beauty");
    const double layers = needed_mib("layers");
    EXPECT_GT(beauty, 20.0);
    // Two layers at least, 3 x 3 floats each.
    EXPECT_GE(layers - beauty, 2 * 36 * 256 * 256 / double(1 << 20));
    EXPECT_EQ(files(), (std::vector<std::string> { "aovs.exr" }));
}


TEST_F(BadInputTest, AllZeroAlbedoLeavesTheImageUnchanged)
{
    // Nothing can be demodulated: every pixel passes through (FILTER.md
    // section 1) rather than being blurred without its texture removed.
    ImageBuf noisy(ImageSpec(32, 32, 3, TypeFloat));
    ImageBufAlgo::noise(noisy, "uniform", 0.0f, 1.0f, false, 7);
    ASSERT_TRUE(noisy.write(path("noisy.exr")));
    write_image("albedo.exr", 32, 32, { "R", "G", "B" }, 0.0f);
    ImageBuf out = denoise_with_cli(make_job(path("noisy.exr"),
                                             path("albedo.exr")));
    EXPECT_TRUE(ImageBufAlgo::compare(out, noisy, 0.0f, 0.0f).nfail == 0)
        << "the output must equal the input";
}


TEST_F(BadInputTest, TinyAndThinImagesAreDenoised)
{
    for (auto size : { std::pair<int, int> { 1, 1 }, { 1, 65536 },
                       { 2, 3 } }) {
        SCOPED_TRACE(std::to_string(size.first) + "x"
                     + std::to_string(size.second));
        ImageBuf noisy(ImageSpec(size.first, size.second, 3, TypeFloat));
        ImageBufAlgo::noise(noisy, "uniform", 0.25f, 0.75f, false, 3);
        ImageBuf albedo(noisy.spec());
        ImageBufAlgo::fill(albedo, { 0.5f, 0.5f, 0.5f });
        ImageBuf out = zdenoise::denoise(noisy, albedo);
        ASSERT_FALSE(out.has_error()) << out.geterror();
        EXPECT_EQ(out.roi(), noisy.roi());
        EXPECT_EQ(count_nonfinite(out), 0);

        ASSERT_TRUE(noisy.write(path("noisy.exr")));
        ASSERT_TRUE(albedo.write(path("albedo.exr")));
        ImageBuf cli_out = denoise_with_cli(make_job(path("noisy.exr"),
                                                     path("albedo.exr")));
        EXPECT_EQ(cli_out.roi(), noisy.roi());
        EXPECT_EQ(count_nonfinite(cli_out), 0);
    }
}


TEST_F(BadInputTest, EmptyDataWindowIsRefused)
{
    // A header whose data window holds no pixel (max < min), as a corrupt
    // writer leaves it. (OIIO cannot hold a 0x0 ImageBuf: the library API
    // never sees one.)
    write_image("one.exr", 1, 1, { "R", "G", "B" }, 0.5f);
    std::string bytes = slurp(path("one.exr"));
    const std::string key("dataWindow\0box2i\0", 17);
    size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    at += key.size() + 4;  // the attribute size, then xmin ymin xmax ymax
    const int32_t box[4] = { 0, 0, -1, -1 };
    bytes.replace(at, sizeof(box), reinterpret_cast<const char*>(box),
                  sizeof(box));
    std::ofstream(path("empty_window.exr"), std::ios::binary) << bytes;
    write_image("albedo.exr", 1, 1, { "R", "G", "B" }, 0.5f);
    expect_refused(make_job(path("empty_window.exr"), path("albedo.exr")),
                   { "empty_window.exr" });
}


TEST_F(BadInputTest, ExtremeValuesGiveAFiniteResult)
{
    // NaN, +-Inf, negative and 1e30 values, sprinkled over each input of a
    // noisy gradient, must never reach the output as NaN or Inf, and pixels
    // far from them must still be denoised.
    const int w = 48, h = 40;
    const std::vector<float> extremes = { kNaN, kInf, -kInf, -1.0f, -1e30f,
                                          1e30f, 0.0f };
    // In the left half only: every extreme, in all channels of a pixel or
    // in its first channel alone.
    auto sprinkle = [&](ImageBuf& img) {
        size_t k = 0;
        for (int y = 1; y < h; y += 4)
            for (int x = 1 + y % 3; x < w / 2; x += 5, ++k) {
                const float v = extremes[k % extremes.size()];
                std::vector<float> px(size_t(img.nchannels()));
                img.getpixel(x, y, px.data());
                for (int c = 0; c < (k % 2 ? 1 : img.nchannels()); ++c)
                    px[size_t(c)] = v;
                img.setpixel(x, y, px.data());
            }
    };
    ImageBuf clean(ImageSpec(w, h, 3, TypeFloat));
    ImageBufAlgo::fill(clean, { 0.2f, 0.3f, 0.4f }, { 0.6f, 0.7f, 0.8f },
                       { 0.2f, 0.3f, 0.4f }, { 0.6f, 0.7f, 0.8f });
    ImageBuf noisy = ImageBufAlgo::copy(clean);
    ImageBufAlgo::noise(noisy, "gaussian", 0.0f, 0.1f, false, 11);
    ImageBuf albedo(clean.spec());
    ImageBufAlgo::fill(albedo, { 0.5f, 0.5f, 0.5f });
    ImageBuf normal(clean.spec());
    ImageBufAlgo::fill(normal, { 0.0f, 0.0f, 1.0f });
    ImageBuf depth(ImageSpec(w, h, 1, TypeFloat));
    ImageBufAlgo::fill(depth, { 5.0f });
    ImageBuf variance(ImageSpec(w, h, 1, TypeFloat));
    ImageBufAlgo::fill(variance, { 0.01f });

    struct Case {
        const char* name;
        ImageBuf* image;
    } cases[] = { { "radiance", &noisy }, { "albedo", &albedo },
                  { "normal", &normal }, { "depth", &depth },
                  { "variance", &variance } };
    for (Case& bad : cases) {
        SCOPED_TRACE(std::string("extreme values in the ") + bad.name);
        const ImageBuf saved = ImageBufAlgo::copy(*bad.image);
        sprinkle(*bad.image);
        zdenoise::Guides guides;
        guides.normal = &normal;
        guides.depth  = &depth;
        guides.variance = &variance;
        ImageBuf out = zdenoise::denoise(noisy, albedo, guides);
        ASSERT_FALSE(out.has_error()) << out.geterror();
        EXPECT_EQ(count_nonfinite(out), 0);
        // No bad value spreads into a firefly or a hole, not even at the
        // bad pixels: they take the value around them or keep their own.
        const auto range = ImageBufAlgo::computePixelStats(out);
        for (int c = 0; c < 3; ++c) {
            EXPECT_GT(range.min[size_t(c)], -1.0f) << "channel " << c;
            EXPECT_LT(range.max[size_t(c)], 2.0f) << "channel " << c;
        }
        // The right half holds no extreme value: denoised there.
        const ROI right(w / 2 + 4, w, 0, h);
        double err_out = 0, err_noisy = 0;
        for (int y = right.ybegin; y < right.yend; ++y)
            for (int x = right.xbegin; x < right.xend; ++x)
                for (int c = 0; c < 3; ++c) {
                    const double t = clean.getchannel(x, y, 0, c);
                    err_out += std::pow(out.getchannel(x, y, 0, c) - t, 2);
                    err_noisy += std::pow(noisy.getchannel(x, y, 0, c) - t, 2);
                }
        EXPECT_LT(err_out * 4, err_noisy) << "far from the bad pixels the "
                                             "image must still be denoised";
        *bad.image = saved;
    }
}


TEST_F(BadInputTest, QuotientsAtTheFloatLimitGiveAFiniteResult)
{
    // With an albedo_eps of 1e-30, an albedo of 1e30 under radiance of
    // -1e30 is an ordinary fit point (z = -1); a pixel of albedo 1e-30
    // among such points has bounds past the float range, [-Inf, -Inf]
    // once multiplied out. They must saturate both ways, or the window's
    // light there is -Inf (found by fuzz_denoise).
    const int w = 14, h = 16;
    ImageBuf radiance(ImageSpec(w, h, 3, TypeFloat)), albedo(radiance.spec());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const bool dark = (x * 7 + y * 3) % 5 == 0;
            const float l = x < w / 2 ? (dark ? -0.5f : -1e30f) : 0.5f;
            const float a = x < w / 2 ? (dark ? 1e-30f : 1e30f) : 0.5f;
            const float lp[3] = { l, l, l }, ap[3] = { a, a, a };
            radiance.setpixel(x, y, lp);
            albedo.setpixel(x, y, ap);
        }
    zdenoise::FilterOptions opt;
    opt.albedo_eps = 1e-30f;
    for (int select = 0; select < 2; ++select) {
        opt.select = select;
        ImageBuf out = zdenoise::denoise(radiance, albedo, {}, opt);
        ASSERT_FALSE(out.has_error()) << out.geterror();
        EXPECT_EQ(count_nonfinite(out), 0) << "select " << select;
    }
}


TEST_F(BadInputTest, UnwritableOutputLocationLeavesNothing)
{
    job::Job j = small_job();
    // An output "folder" that is a file: no user can write there.
    RunResult r = run(cli_args(j, path("noisy.exr/out.exr")));
    expect_one_line_error(r, "noisy.exr/out.exr");
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(files(), (std::vector<std::string> { "albedo.exr", "noisy.exr" }));

    // A read-only folder (root writes there anyway: then this part is moot).
    Filesystem::create_directory(path("locked"));
    write_image("locked/out.exr", 4, 4, { "R", "G", "B" }, 0.25f);
    const std::string old_output = slurp(path("locked/out.exr"));
    ::chmod(path("locked").c_str(), 0555);
    const bool locked = ::access(path("locked").c_str(), W_OK) != 0;
    r = run(cli_args(j, path("locked/out.exr")));
    ::chmod(path("locked").c_str(), 0755);
    if (locked) {
        expect_one_line_error(r, "locked/out.exr");
        EXPECT_EQ(slurp(path("locked/out.exr")), old_output);
        std::vector<std::string> left;
        Filesystem::get_directory_entries(path("locked"), left);
        EXPECT_EQ(left.size(), 1u);
    }
}


TEST_F(BadInputTest, FullDiskLeavesNothing)
{
    // A 64 KiB tmpfs: room for an old output but not for the new one.
    const std::string tiny = path("tiny");
    Filesystem::create_directory(tiny);
    if (::mount("tmpfs", tiny.c_str(), "tmpfs", 0, "size=64k") != 0)
        GTEST_SKIP() << "cannot mount a small tmpfs here (" << std::strerror(errno)
                     << "); run as root to test a full disk";
    struct Unmount {
        std::string dir;
        ~Unmount() { ::umount2(dir.c_str(), MNT_DETACH); }
    } unmount { tiny };

    ImageBuf noisy(ImageSpec(256, 256, 3, TypeFloat));
    ImageBufAlgo::noise(noisy, "uniform", 0.0f, 1.0f, false, 5);
    ASSERT_TRUE(noisy.write(path("noisy.exr")));
    write_image("albedo.exr", 256, 256, { "R", "G", "B" }, 0.5f);
    write_image("tiny/out.exr", 4, 4, { "R", "G", "B" }, 0.25f);
    const std::string old_output = slurp(tiny + "/out.exr");

    RunResult r = run(cli_args(make_job(path("noisy.exr"), path("albedo.exr")),
                               tiny + "/out.exr")
                      + " --rmax 2");
    expect_one_line_error(r, "tiny/out.exr");
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(slurp(tiny + "/out.exr"), old_output);
    std::vector<std::string> left;
    Filesystem::get_directory_entries(tiny, left);
    EXPECT_EQ(left.size(), 1u) << "the partial temporary file must be removed";
}


namespace {

/// Start the command with `args` (no shell), its stderr to `err_path`.
pid_t
spawn_cli(const std::vector<std::string>& args, const std::string& err_path)
{
    static const std::string cli = ZDENOISE_CLI;
    std::vector<char*> argv { const_cast<char*>(cli.c_str()) };
    for (const std::string& a : args)
        argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    pid_t pid = -1;
    if (posix_spawn(&pid, cli.c_str(), &actions, nullptr, argv.data(),
                    environ)
        != 0)
        pid = -1;
    posix_spawn_file_actions_destroy(&actions);
    return pid;
}

/// A started command and, once it has ended, its exit status (minus the
/// signal number when a signal killed it).
struct Child {
    pid_t pid  = -1;
    int status = 0;
    bool ended = false;

    void reap(int options)
    {
        int s = 0;
        if (!ended && ::waitpid(pid, &s, options) == pid) {
            ended  = true;
            status = WIFEXITED(s) ? WEXITSTATUS(s) : -WTERMSIG(s);
        }
    }
};

/// Wait up to `seconds` for `ready()`; false if the child ends first.
template<class Ready>
bool
wait_while_running(Child& child, double seconds, Ready ready)
{
    const auto end = std::chrono::steady_clock::now()
                     + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
        if (ready())
            return true;
        child.reap(WNOHANG);
        if (child.ended)
            return false;
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    return false;
}

int
exit_status(Child& child)
{
    child.reap(0);
    return child.status;
}

}  // namespace


TEST_F(BadInputTest, InterruptedWhileFilteringLeavesNothing)
{
    // A frame that takes seconds with a tight --eta.
    ImageBuf noisy(ImageSpec(384, 384, 3, TypeFloat));
    ImageBufAlgo::noise(noisy, "uniform", 0.0f, 1.0f, false, 9);
    ASSERT_TRUE(noisy.write(path("noisy.exr")));
    write_image("albedo.exr", 384, 384, { "R", "G", "B" }, 0.5f);
    for (int signal : { SIGINT, SIGTERM }) {
        SCOPED_TRACE(signal == SIGINT ? "SIGINT" : "SIGTERM");
        write_image("out.exr", 4, 4, { "R", "G", "B" }, 0.25f);
        const std::string old_output        = slurp(path("out.exr"));
        const std::vector<std::string> before = files();
        const std::string err = Filesystem::temp_directory_path()
                                + "/zdenoise_interrupt_"
                                + std::to_string(::getpid()) + ".txt";
        Child child;
        child.pid = spawn_cli({ "--in", path("noisy.exr"), "--albedo",
                                path("albedo.exr"), "-o", path("out.exr"),
                                "--eta", "0.0001", "-v" },
                              err);
        ASSERT_GT(child.pid, 0);
        const bool filtering = wait_while_running(child, 120, [&] {
            return slurp(err).find("filtering") != std::string::npos;
        });
        if (filtering)
            ::kill(child.pid, signal);
        const int status = exit_status(child);
        const std::string stderr_text = slurp(err);
        Filesystem::remove(err);
        ASSERT_TRUE(filtering) << "zdenoise ended before it could be "
                                  "interrupted (status "
                               << status << "):\n" << stderr_text;
        EXPECT_EQ(status, 128 + signal);
        EXPECT_EQ(slurp(path("out.exr")), old_output);
        EXPECT_EQ(files(), before);
    }
}


TEST_F(BadInputTest, InterruptedWhileWritingRemovesTheTemporaryFile)
{
    // Many channels of noise: a write that takes a while.
    ImageSpec spec(512, 512, 48, TypeFloat);
    ImageBuf noisy(spec);
    ImageBufAlgo::noise(noisy, "uniform", 0.0f, 1.0f, false, 13);
    ASSERT_TRUE(noisy.write(path("noisy.exr")));
    write_image("albedo.exr", 512, 512, { "R", "G", "B" }, 0.5f);
    write_image("out.exr", 4, 4, { "R", "G", "B" }, 0.25f);
    const std::string old_output        = slurp(path("out.exr"));
    const std::vector<std::string> before = files();

    const std::string err = Filesystem::temp_directory_path()
                            + "/zdenoise_interrupt_"
                            + std::to_string(::getpid()) + ".txt";
    Child child;
    child.pid = spawn_cli({ "--in", path("noisy.exr"), "--albedo",
                            path("albedo.exr"), "-o", path("out.exr"),
                            "--eta", "0.5", "--rmax", "3" },
                          err);
    ASSERT_GT(child.pid, 0);
    const std::string tmp = path(".out.exr.zdenoise-tmp-"
                                 + std::to_string(child.pid) + ".exr");
    const bool writing = wait_while_running(child, 120, [&] {
        return Filesystem::exists(tmp);
    });
    if (writing)
        ::kill(child.pid, SIGTERM);
    const int status = exit_status(child);
    Filesystem::remove(err);
    if (!writing)
        GTEST_SKIP() << "the write ended before it could be interrupted";
    EXPECT_EQ(status, 128 + SIGTERM);
    EXPECT_EQ(slurp(path("out.exr")), old_output);
    EXPECT_EQ(files(), before) << "the temporary output must be removed";
}
