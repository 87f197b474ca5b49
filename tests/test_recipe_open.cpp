// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Opening a recipe (.zdn) for its header, as iinfo, `oiiotool --info` or
// an image browser does, reads the inputs' headers only
// (job::output_spec()); the first pixel read denoises, once. As a user
// notices it: a recipe whose input's pixels are unreadable opens, and its
// first read fails with the command's message; what a header shows wrong
// still fails at open; the spec from the headers is the spec the run
// gives; reads from several threads, and reads after the input is gone,
// give the command's pixels.

#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include "cli_harness.h"
#include "job/job.h"
#include "job/output.h"
#include "job/recipe.h"

using namespace OIIO;
using namespace cli_harness;
namespace job = zdenoise::job;

namespace {

const std::string kSourceDir = ZDENOISE_SOURCE_DIR;
const std::string kSample    = kSourceDir
                            + "/share/samples/cornell_textured_spp16_crop.exr";

/// The spec a run gives its sink, as a file holds it; the rows dropped.
class SpecSink final : public job::OutputSink {
public:
    ImageSpec spec;
    bool begin(const ImageSpec& image_spec, const std::vector<TypeDesc>& formats,
               std::string& /*error*/) override
    {
        spec = job::native_spec(image_spec, formats);
        return true;
    }
    bool holds_image() const override { return true; }  // as the plugin's
    bool rows(int, int, const void*, std::string&) override { return true; }
};

/// Everything a spec says, a line each: windows, channels with their pixel
/// types, and every attribute with its type and value.
std::vector<std::string>
described(const ImageSpec& s)
{
    std::vector<std::string> lines = {
        Strutil::fmt::format("data {},{},{} {}x{}x{}", s.x, s.y, s.z, s.width, s.height,
                             s.depth),
        Strutil::fmt::format("display {},{},{} {}x{}x{}", s.full_x, s.full_y, s.full_z,
                             s.full_width, s.full_height, s.full_depth),
        Strutil::fmt::format("tiles {}x{}x{}", s.tile_width, s.tile_height, s.tile_depth),
        Strutil::fmt::format("format {} alpha {} z {}", s.format.c_str(), s.alpha_channel,
                             s.z_channel),
    };
    for (int c = 0; c < s.nchannels; ++c)
        lines.push_back(Strutil::fmt::format("channel {} {}", s.channel_name(c),
                                             s.channelformat(c).c_str()));
    for (const ParamValue& p : s.extra_attribs)
        lines.push_back(Strutil::fmt::format("attribute {} {} {}", p.name().c_str(),
                                             p.type().c_str(),
                                             p.get_string(0)));
    return lines;
}

/// A test folder holding the bundled sample (a recipe reads files in its
/// folder only, share/zdn-format.md).
class RecipeOpen : public FolderTest {
protected:
    void SetUp() override
    {
        FolderTest::SetUp();
        ASSERT_TRUE(Filesystem::copy(kSample, path("sample.exr")));
    }

    void write_text(const std::string& name, const std::string& text) const
    {
        std::ofstream(path(name)) << text;
    }

    /// Write the recipe `name` for the sample, with the given extra keys.
    void write_recipe(const std::string& name, const std::string& extra = "") const
    {
        write_text(name, "{\"zdenoise-recipe\": 1, \"in\": \"sample.exr\""
                             + (extra.empty() ? "" : ", " + extra) + "}");
    }

    /// Run a Debian OIIO program (or python3) with the build's plugin.
    RunResult host(const std::string& program, const std::string& args) const
    {
        return run_command("OIIO_LIBRARY_PATH=" + quoted(ZDENOISE_PLUGIN_DIR) + " "
                               + host_program(program) + " " + args,
                           path(".host"));
    }

    /// Run a Python script with Debian's python3 and its OpenImageIO module.
    RunResult python(const std::string& script) const
    {
        write_text("script.py", "import OpenImageIO as oiio\n" + script);
        return host(ZDENOISE_SYSTEM_PYTHON, quoted(path("script.py")));
    }

    /// Skip unless Debian's OIIO programs (and python3, if `with_python`)
    /// are there.
    bool have_programs(bool with_python) const
    {
        const std::string iinfo = ZDENOISE_IINFO, oiiotool = ZDENOISE_OIIOTOOL,
                          py = ZDENOISE_SYSTEM_PYTHON;
        return !iinfo.empty() && !oiiotool.empty() && (!with_python || !py.empty());
    }
};

}  // namespace


TEST_F(RecipeOpen, SpecFromTheHeadersIsTheSpecTheRunGives)
{
    // An auxiliary image: the sample's albedo alone, RGB float.
    ImageBuf sample(kSample);
    const int albedo = sample.spec().channelindex("ViewLayer.Denoising Albedo.R");
    ASSERT_GE(albedo, 0);
    ImageBuf aux = ImageBufAlgo::channels(sample, 3, { albedo, albedo + 1, albedo + 2 },
                                          {}, { "R", "G", "B" });
    ASSERT_TRUE(aux.write(path("aux.exr"), TypeFloat)) << aux.geterror();

    const std::string layers
        = "\"mode\": \"layers\", \"aovs\": true, \"data-type\": \"float\", \"layers\": ["
          "\"diff=ViewLayer.DiffDir+ViewLayer.DiffInd:ViewLayer.DiffCol:divided\", "
          "\"gloss=ViewLayer.GlossDir:ViewLayer.GlossCol:reflected:divided\"], "
          "\"residual\": \"ViewLayer.Emit+ViewLayer.Env\"";
    const struct {
        const char* name;
        std::string keys;
    } recipes[] = {
        { "beauty.zdn", "" },
        { "half.zdn", "\"data-type\": \"half\"" },
        { "layers.zdn", layers },
        { "path.zdn", "\"mode\": \"path\"" },
        { "aux.zdn", "\"aux\": \"aux.exr\"" },
        // The bundled config, found next to the test program.
        { "acescg.zdn", "\"ocolorspace\": \"ACEScg\"" },
        { "diagnostics.zdn", "\"diagnostics\": true" },
    };
    for (const auto& r : recipes) {
        SCOPED_TRACE(r.name);
        write_recipe(r.name, r.keys);
        job::Job recipe;
        std::string error;
        ASSERT_TRUE(job::read_recipe(path(r.name), recipe, error)) << error;
        recipe.threads = 2;
        SpecSink from_headers, run;
        ImageSpec header_spec;
        ASSERT_TRUE(job::output_spec(recipe, from_headers, header_spec, error)) << error;
        job::JobResult result;
        ASSERT_TRUE(job::run_job(recipe, run, result, error)) << error;
        EXPECT_EQ(described(header_spec), described(run.spec));
        EXPECT_TRUE(from_headers.spec.undefined()) << "the sink is not begun";
    }
}


TEST_F(RecipeOpen, OpenReadsHeadersOnlyAndTheFirstReadFailsAsTheCommandDoes)
{
    if (!have_programs(true))
        GTEST_SKIP() << "Debian's oiiotool, iinfo or python3 not found";
    // The sample cut short: its header whole, the last rows of pixels gone.
    std::ifstream whole(kSample, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(whole)),
                            std::istreambuf_iterator<char>());
    std::ofstream(path("cut.exr"), std::ios::binary) << bytes.substr(0, bytes.size() * 6 / 10);
    write_text("cut.zdn", R"({"zdenoise-recipe": 1, "in": "cut.exr"})");

    RunResult r = zdenoise("--in " + quoted(path("cut.exr")) + " -o " + quoted(path("cli.exr")));
    ASSERT_NE(r.status, 0);
    const std::string prefix = "zdenoise: error: ";
    ASSERT_EQ(r.err.rfind(prefix, 0), 0u) << r.err;
    const std::string message = r.err.substr(prefix.size(), r.err.find('\n') - prefix.size());
    EXPECT_NE(message.find("cut.exr"), std::string::npos) << message;

    // Opened for its header: the spec, as the sample's output has it.
    r = host(ZDENOISE_IINFO, quoted(path("cut.zdn")));
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("96 x   96, 54 channel, float zdenoise"), std::string::npos) << r.out;

    // Read: the command's message, after the recipe's name; a second read
    // fails alike.
    const std::string expected = "recipe '" + path("cut.zdn") + "': " + message;
    r = python("reader = oiio.ImageInput.open(" + quoted(path("cut.zdn")) + ")\n"
               "print('opened' if reader else oiio.geterror())\n"
               "for attempt in range(2):\n"
               "    pixels = reader.read_image(oiio.FLOAT)\n"
               "    print(pixels is None, reader.geterror())\n");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.out, "opened\nTrue " + expected + "\nTrue " + expected + "\n");

    r = host(ZDENOISE_OIIOTOOL, quoted(path("cut.zdn")) + " -o " + quoted(path("out.exr")));
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
    EXPECT_FALSE(Filesystem::exists(path("out.exr")));
}


TEST_F(RecipeOpen, WhatAHeaderShowsFailsAtOpen)
{
    if (!have_programs(false))
        GTEST_SKIP() << "Debian's iinfo not found";
    const struct {
        const char* name;
        std::string keys;
        std::string problem;  ///< expected in the message
    } cases[] = {
        { "missing_channel.zdn",
          "\"albedo\": {\"path\": \"sample.exr\", \"channels\": \"Diffuse.R,Diffuse.G,Diffuse.B\"}",
          "Diffuse.R" },
        { "bad_filter.zdn", "\"rmin\": 5, \"rmax\": 3", "r_max" },
        { "missing_layer_channel.zdn", "\"layers\": [\"x=ViewLayer.Nope:ViewLayer.DiffCol\"]",
          "ViewLayer.Nope" },
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.name);
        write_recipe(c.name, c.keys);
        // iinfo opens the recipe and reads no pixel.
        RunResult r = host(ZDENOISE_IINFO, quoted(path(c.name)));
        EXPECT_NE(r.status, 0) << r.out;
        EXPECT_NE(r.err.find("recipe '" + path(c.name) + "': "), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(c.problem), std::string::npos) << r.err;
    }
}


TEST_F(RecipeOpen, ReadsFromThreadsRunTheRecipeOnceAndGiveTheCommandsPixels)
{
    if (!have_programs(true))
        GTEST_SKIP() << "Debian's oiiotool, iinfo or python3 not found";
    write_recipe("shot.zdn");
    RunResult r = zdenoise("--in " + quoted(path("sample.exr")) + " -o "
                           + quoted(path("cli.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    // Four threads read a band each from a reader just opened; then the
    // input is removed and the whole image read again: from memory, as
    // the job ran once.
    r = python("import os, threading\n"
               "import numpy as np\n"
               "reader = oiio.ImageInput.open(" + quoted(path("shot.zdn")) + ")\n"
               "spec = reader.spec()\n"
               "bands = [None] * 4\n"
               "def read(k):\n"
               "    bands[k] = reader.read_scanlines(0, 0, 24 * k, 24 * k + 24, 0, 0,\n"
               "                                     spec.nchannels, oiio.FLOAT)\n"
               "threads = [threading.Thread(target=read, args=(k,)) for k in range(4)]\n"
               "for t in threads: t.start()\n"
               "for t in threads: t.join()\n"
               "assert all(b is not None for b in bands), reader.geterror()\n"
               "cli = oiio.ImageInput.open(" + quoted(path("cli.exr")) + ").read_image(oiio.FLOAT)\n"
               "os.remove(" + quoted(path("sample.exr")) + ")\n"
               "again = reader.read_image(oiio.FLOAT)\n"
               "assert again is not None, reader.geterror()\n"
               "print(np.array_equal(np.concatenate(bands), cli, equal_nan=True),\n"
               "      np.array_equal(again, cli, equal_nan=True))\n");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.out, "True True\n") << "bands from threads, then again after the input is gone";
}


TEST_F(RecipeOpen, AnInputRewrittenAfterOpenFailsTheRead)
{
    if (!have_programs(true))
        GTEST_SKIP() << "Debian's oiiotool, iinfo or python3 not found";
    write_recipe("shot.zdn");
    // Opened at 96x96; the render is then rewritten at 48x48 (by another
    // program: this one's ImageCache would serve the old file), a second
    // later: OIIO's cache tells a changed file by its time, in seconds (on
    // the CI machine the rewrite fell within the second and the old header
    // was served).
    write_text("rewrite.sh", "sleep 1.1\n" + host_program(ZDENOISE_OIIOTOOL) + " "
                                 + quoted(path("sample.exr")) + " --cut 48x48+0+0 -o "
                                 + quoted(path("sample.exr")) + "\n");
    RunResult r = python(
        "import subprocess\n"
        "reader = oiio.ImageInput.open(" + quoted(path("shot.zdn")) + ")\n"
        "subprocess.run(['sh', " + quoted(path("rewrite.sh")) + "], check=True)\n"
        "print(reader.spec().width, reader.read_image(oiio.FLOAT) is None, reader.geterror())\n");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.out, "96 True recipe '" + path("shot.zdn")
                         + "': its inputs changed since it was opened; open it again\n");
}
