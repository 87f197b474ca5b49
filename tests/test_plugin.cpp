// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The OIIO plugin as a user meets it: Debian's oiiotool, iinfo, idiff and
// Python module, with OIIO_LIBRARY_PATH at the build's plugin folder,
// reading recipes (.zdn) as the image `zdenoise` writes; broken recipes
// failing through OIIO's error mechanism with a message naming the recipe
// and the problem, never a crash or a hang.

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <zdenoise/version.h>

#include "cli_harness.h"

using namespace OIIO;
using cli_harness::host_program;

namespace {

const std::string kCli       = ZDENOISE_CLI;
const std::string kSourceDir = ZDENOISE_SOURCE_DIR;
const std::string kPluginDir = ZDENOISE_PLUGIN_DIR;
const std::string kOiiotool  = ZDENOISE_OIIOTOOL;
const std::string kIinfo     = ZDENOISE_IINFO;
const std::string kIdiff     = ZDENOISE_IDIFF;
const std::string kPython    = ZDENOISE_SYSTEM_PYTHON;
const std::string kSample    = kSourceDir
                            + "/share/samples/cornell_textured_spp16_crop.exr";

/// A host program that hangs is killed after this many seconds (status 124).
constexpr int kTimeoutSeconds = 120;

struct RunResult {
    int status = -1;  ///< exit status; -1 when killed by a signal
    std::string out, err;
};

std::string
slurp(const std::string& path)
{
    std::ifstream f(path);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

std::string
quoted(const std::string& s)
{
    std::string q = "'";
    for (char c : s)
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

class PluginTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        for (const std::string* program : { &kOiiotool, &kIinfo, &kIdiff })
            if (program->empty())
                GTEST_SKIP() << "oiiotool, iinfo or idiff not found "
                                "(Debian package openimageio-tools)";
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir = Filesystem::temp_directory_path() + "/zdenoise_plugin_"
              + info->name() + "_" + std::to_string(::getpid());
        Filesystem::remove_all(dir);
        Filesystem::create_directory(dir);
        // A recipe reads files in its folder only (share/zdn-format.md).
        ASSERT_TRUE(Filesystem::copy(kSample, path("sample.exr")));
    }
    void TearDown() override
    {
        if (!dir.empty())
            Filesystem::remove_all(dir);
    }

    std::string path(const std::string& name) const { return dir + "/" + name; }

    /// Run a shell command line (arguments already quoted) with OIIO's
    /// plugin search path at the build's plugin folder.
    RunResult run(const std::string& command) const
    {
        RunResult r;
        std::string cmd = "OIIO_LIBRARY_PATH=" + quoted(kPluginDir) + " timeout "
                          + std::to_string(kTimeoutSeconds) + " sh -c "
                          + quoted(command) + " >" + quoted(path("stdout.txt"))
                          + " 2>" + quoted(path("stderr.txt"));
        int rc   = std::system(cmd.c_str());
        r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
        r.out    = slurp(path("stdout.txt"));
        r.err    = slurp(path("stderr.txt"));
        Filesystem::remove(path("stdout.txt"));
        Filesystem::remove(path("stderr.txt"));
        return r;
    }

    RunResult zdenoise(const std::string& args) const
    {
        return run(quoted(kCli) + " " + args);
    }

    RunResult oiiotool(const std::string& args) const
    {
        return run(host_program(kOiiotool) + " " + args);
    }

    /// Run a Python script with Debian's python3 and its OpenImageIO module.
    RunResult python(const std::string& script) const
    {
        std::ofstream(path("script.py")) << "import OpenImageIO as oiio\n" << script;
        return run(host_program(kPython) + " " + quoted(path("script.py")));
    }

    void write_text(const std::string& name, const std::string& text) const
    {
        std::ofstream f(path(name));
        f << text;
    }

    /// idiff finds the two images identical (every channel, every pixel).
    void expect_identical(const std::string& a, const std::string& b) const
    {
        RunResult r = run(host_program(kIdiff) + " " + quoted(a) + " " + quoted(b));
        EXPECT_EQ(r.status, 0) << "idiff " << a << " " << b << ":\n" << r.out << r.err;
    }

    std::string dir;
};

/// A recipe for the bundled sample (its copy in the test's folder) with
/// the given extra JSON lines.
std::string
sample_recipe(const std::string& extra = "")
{
    return "{\n  \"zdenoise-recipe\": 1,\n  \"in\": \"sample.exr\""
           + (extra.empty() ? "" : ",\n  " + extra) + "\n}\n";
}

/// Named metadata of a file, as iinfo would list it.
std::map<std::string, std::string>
metadata(const std::string& file)
{
    std::map<std::string, std::string> m;
    auto in = ImageInput::open(file);
    if (!in)
        return m;
    for (const ParamValue& p : in->spec().extra_attribs)
        m[p.name().string()] = p.get_string();
    return m;
}

}  // namespace


TEST_F(PluginTest, OiiotoolReadsRecipeAsTheImageZdenoiseWrites)
{
    write_text("shot.zdn", sample_recipe());
    RunResult r = zdenoise("--in " + quoted(kSample) + " -o " + quoted(path("cli.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    r = oiiotool(quoted(path("shot.zdn")) + " -o " + quoted(path("plugin.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("cli.exr"), path("plugin.exr"));

    // Same channels, pixel types and metadata (oiiotool stamps its own
    // Software and history), including zdenoise's own: the plugin on the
    // search path must not make OIIO's writers drop "zdenoise." metadata.
    auto cli = ImageInput::open(path("cli.exr")), plugin = ImageInput::open(path("plugin.exr"));
    ASSERT_TRUE(cli && plugin);
    EXPECT_EQ(plugin->spec().channelnames, cli->spec().channelnames);
    EXPECT_EQ(plugin->spec().format, cli->spec().format);
    EXPECT_EQ(plugin->spec().channelformats, cli->spec().channelformats);
    auto from_cli = metadata(path("cli.exr")), from_plugin = metadata(path("plugin.exr"));
    for (const auto& [name, value] : from_cli) {
        if (name != "Software" && name != "Exif:ImageHistory") {
            EXPECT_EQ(from_plugin[name], value) << "metadata " << name;
        }
    }
    EXPECT_EQ(from_cli["zdenoise.version"], ZDENOISE_VERSION_STRING);
    EXPECT_NE(from_plugin["zdenoise.parameters"], "");
}


TEST_F(PluginTest, KeepsEachChannelsPixelType)
{
    // Half beauty and float depth in one file; a float albedo.
    ImageSpec spec(24, 20, 5, TypeFloat);
    spec.channelnames = { "R", "G", "B", "A", "depth.Z" };
    ImageBuf noisy(spec);
    ImageBufAlgo::noise(noisy, "uniform", 0.2f, 0.6f, true, 7);
    noisy.set_write_format({ TypeHalf, TypeHalf, TypeHalf, TypeHalf, TypeFloat });
    ASSERT_TRUE(noisy.write(path("mixed.exr"))) << noisy.geterror();
    noisy.set_write_format(TypeHalf);
    ASSERT_TRUE(noisy.write(path("half.exr"))) << noisy.geterror();
    ImageBuf albedo(ImageSpec(24, 20, 3, TypeFloat));
    ImageBufAlgo::fill(albedo, { 0.5f, 0.4f, 0.3f });
    ASSERT_TRUE(albedo.write(path("albedo.exr"))) << albedo.geterror();

    for (const std::string name : { "mixed", "half" }) {
        SCOPED_TRACE(name);
        write_text(name + ".zdn", "{\"zdenoise-recipe\": 1, \"in\": \"" + name
                                      + ".exr\", \"albedo\": {\"path\": \"albedo.exr\", "
                                        "\"channels\": \"R,G,B\"}}");
        RunResult r = zdenoise("--in " + quoted(path(name + ".exr")) + " --albedo "
                               + quoted(path("albedo.exr")) + " -o "
                               + quoted(path(name + "_cli.exr")));
        ASSERT_EQ(r.status, 0) << r.err;
        r = run(host_program(kIinfo) + " " + quoted(path(name + ".zdn")));
        EXPECT_NE(r.out.find(name == "mixed" ? "half/half/half/half/float zdenoise" : "half zdenoise"),
                  std::string::npos)
            << r.out << r.err;
        r = oiiotool(quoted(path(name + ".zdn")) + " -o " + quoted(path(name + "_oiiotool.exr")));
        ASSERT_EQ(r.status, 0) << r.err;
        expect_identical(path(name + "_cli.exr"), path(name + "_oiiotool.exr"));
    }
    // oiiotool 2.4 writes mixed-type inputs (EXR or recipe alike) as float,
    // but a uniform type as that type.
    auto half = ImageInput::open(path("half_oiiotool.exr"));
    ASSERT_TRUE(half);
    EXPECT_EQ(half->spec().format, TypeHalf) << "half input must give half output";

    // ImageBuf::write keeps each channel's type.
    if (kPython.empty())
        return;
    RunResult r = python("oiio.ImageBuf(" + quoted(path("mixed.zdn")) + ").write("
                         + quoted(path("mixed_python.exr")) + ")\n");
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("mixed_cli.exr"), path("mixed_python.exr"));
    auto mixed = ImageInput::open(path("mixed_python.exr"));
    ASSERT_TRUE(mixed);
    EXPECT_EQ(mixed->spec().channelformat(0), TypeHalf);
    EXPECT_EQ(mixed->spec().channelformat(4), TypeFloat) << "depth.Z must stay float";
}


TEST_F(PluginTest, InputPathsAreRelativeToTheRecipesFolder)
{
    Filesystem::create_directory(path("shots"));
    Filesystem::create_directory(path("shots/renders"));
    ASSERT_TRUE(Filesystem::copy(kSample, path("shots/renders/shot.exr")));
    write_text("shots/shot.zdn",
               R"({"zdenoise-recipe": 1, "in": "renders/shot.exr"})");
    RunResult r = zdenoise("--in " + quoted(kSample) + " -o " + quoted(path("cli.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    // Run from another folder.
    r = run("cd / && " + host_program(kOiiotool) + " " + quoted(path("shots/shot.zdn")) + " -o "
            + quoted(path("plugin.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("cli.exr"), path("plugin.exr"));
}


TEST_F(PluginTest, RecipesReadOnlyFilesInTheirFolder)
{
    // The recipes' folder, and a folder beside it they may not read.
    Filesystem::create_directory(path("recipes"));
    Filesystem::create_directory(path("outside"));
    ASSERT_TRUE(Filesystem::copy(kSample, path("outside/shot.exr")));
    ASSERT_TRUE(Filesystem::copy(kSample, path("recipes/own.exr")));
    ASSERT_EQ(::symlink(path("outside/shot.exr").c_str(), path("recipes/link.exr").c_str()), 0);
    ASSERT_EQ(::symlink("../outside", path("recipes/linked").c_str()), 0);
    ASSERT_EQ(::mkfifo(path("recipes/fifo.exr").c_str(), 0600), 0);
    const std::string outside = path("outside/shot.exr");
    const std::string recipes = path("recipes");
    auto recipe = [](const std::string& key, const std::string& value) {
        return "{\"zdenoise-recipe\": 1, \"in\": \"own.exr\", \"" + key + "\": \"" + value
               + "\"}";
    };
    struct Case {
        const char* name;
        std::string text;
        std::string problem;  ///< expected in the message
        bool listed_reads;    ///< read once ZDENOISE_RECIPE_PATH lists outside/
    } cases[] = {
        { "absolute.zdn", recipe("in", outside),
          "\"in\" is '" + outside + "': an absolute path outside the recipe's folder", true },
        { "dotdot.zdn", recipe("in", "../outside/shot.exr"),
          "\"in\" is '../outside/shot.exr': '..' leads out of the recipe's folder", true },
        { "deep_dotdot.zdn", recipe("albedo", "a/../../outside/shot.exr"),
          "\"albedo\" is 'a/../../outside/shot.exr': '..' leads out of",
          true },
        { "symlink.zdn", recipe("in", "link.exr"),
          "\"in\" is 'link.exr': a symbolic link leads out of the recipe's folder", true },
        { "linked_folder.zdn", recipe("in", "linked/shot.exr"),
          "\"in\" is 'linked/shot.exr': a symbolic link leads out of",
          true },
        { "halves.zdn",
          "{\"zdenoise-recipe\": 1, \"in\": \"own.exr\", \"halves\": [\"own.exr\", \"" + outside
              + "\"]}",
          "\"halves\" is '" + outside + "'", true },
        { "colorconfig.zdn", recipe("colorconfig", "/etc/passwd"),
          "\"colorconfig\" is '/etc/passwd': an absolute path outside", false },
        { "fifo.zdn", recipe("in", "fifo.exr"), "\"in\" is 'fifo.exr': not a regular file",
          false },
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        write_text("recipes/" + std::string(c.name), c.text);
        const std::string name = path("recipes/" + std::string(c.name));
        RunResult r = oiiotool(quoted(name) + " -o " + quoted(path("out.exr")));
        EXPECT_EQ(r.status, 1) << r.err;
        EXPECT_NE(r.err.find("recipe '" + name + "': " + c.problem), std::string::npos) << r.err;
        if (c.problem.find("not a regular file") == std::string::npos) {
            EXPECT_NE(r.err.find("or in the folders ZDENOISE_RECIPE_PATH lists"),
                      std::string::npos)
                << "the message names the variable that allows more: " << r.err;
        }
        EXPECT_FALSE(Filesystem::exists(path("out.exr")));
        r = run("ZDENOISE_RECIPE_PATH=" + quoted("/nonexistent:" + path("outside")) + " "
                + host_program(kIinfo) + " " + quoted(name));
        EXPECT_EQ(r.status == 0, c.listed_reads) << r.out << r.err;
    }
    // A file name's override is confined like the recipe's own keys.
    write_text("recipes/own.zdn", recipe("albedo", "own.exr"));
    RunResult r = oiiotool(quoted(path("recipes/own.zdn") + "?in=" + outside) + " -o "
                           + quoted(path("out.exr")));
    EXPECT_EQ(r.status, 1) << r.err;
    r = run(host_program(kIinfo) + " " + quoted(path("recipes/own.zdn") + "?in=" + outside));
    EXPECT_NE(r.err.find("\"in\" is '" + outside + "': an absolute path outside"),
              std::string::npos)
        << r.out << r.err;
    // An absolute path inside the recipe's folder is read.
    write_text("recipes/own_absolute.zdn", recipe("albedo", recipes + "/own.exr"));
    r = run(host_program(kIinfo) + " " + quoted(path("recipes/own_absolute.zdn")));
    EXPECT_EQ(r.status, 0) << r.err;
    // A malformed ZDENOISE_RECIPE_PATH fails every recipe, naming it.
    r = run("ZDENOISE_RECIPE_PATH=relative/folder " + host_program(kIinfo) + " "
            + quoted(path("recipes/own.zdn")));
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("ZDENOISE_RECIPE_PATH: 'relative/folder' is not an absolute folder"),
              std::string::npos)
        << r.err;
}


TEST_F(PluginTest, RecipeCostIsBounded)
{
    struct Case {
        const char* name;
        std::string text;
        std::string problem;  ///< expected in the message
        std::string limits;   ///< a ZDENOISE_RECIPE_LIMITS that allows it
    } cases[] = {
        { "rmax.zdn", sample_recipe("\"rmax\": 40"),
          "\"rmax\" is 40: more than the 32 a recipe may ask for "
          "(ZDENOISE_RECIPE_LIMITS=rmax=N allows more)",
          "rmax=40" },
        { "rmax_override.zdn?rmax=33", sample_recipe(), "\"rmax\" is 33", "rmax=0" },
        { "layers.zdn",
          sample_recipe("\"mode\": \"layers\", \"layers\": ["
                        + [] {
                              std::string list;
                              for (int k = 0; k < 17; ++k)
                                  list += std::string(k ? ", " : "") + "\"l" + std::to_string(k)
                                          + "=ViewLayer.DiffDir:ViewLayer.DiffCol:divided\"";
                              return list;
                          }()
                        + "]"),
          "\"layers\" lists 17 layers: more than the 16 a recipe may "
          "(ZDENOISE_RECIPE_LIMITS=layers=N allows more)",
          "layers=17" },
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const std::string file = std::string(c.name).substr(0, std::string(c.name).find('?'));
        write_text(file, c.text);
        // iinfo reports an override's refusal (oiiotool 2.4: "does not exist").
        RunResult r = run(host_program(kIinfo) + " " + quoted(path(c.name)));
        EXPECT_NE(r.status, 0) << r.err;
        EXPECT_NE(r.err.find("recipe '" + path(file) + "': " + c.problem), std::string::npos)
            << r.err;
        r = run("ZDENOISE_RECIPE_LIMITS=" + c.limits + " " + host_program(kIinfo) + " "
                + quoted(path(c.name)));
        EXPECT_EQ(r.status, 0) << r.err;
    }
    // The image: the sample is 96x96.
    write_text("shot.zdn", sample_recipe());
    RunResult r = run("ZDENOISE_RECIPE_LIMITS='rmax=16, pixels=9215' " + host_program(kIinfo) + " "
                      + quoted(path("shot.zdn")));
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("recipe '" + path("shot.zdn") + "': '" + path("sample.exr")
                         + "' is 96x96, 9216 pixels: more than the 9215 a recipe may denoise "
                         "(ZDENOISE_RECIPE_LIMITS=pixels=N allows more)"),
              std::string::npos)
        << r.err;
    r = run("ZDENOISE_RECIPE_LIMITS=pixels=9K " + host_program(kIinfo) + " "
            + quoted(path("shot.zdn")));
    EXPECT_EQ(r.status, 0) << r.err;
    // A malformed value fails every recipe, naming the variable.
    r = run("ZDENOISE_RECIPE_LIMITS=radius=8 " + host_program(kIinfo) + " "
            + quoted(path("shot.zdn")));
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("ZDENOISE_RECIPE_LIMITS: 'radius=8' must be rmax=N, layers=N or "
                         "pixels=N"),
              std::string::npos)
        << r.err;
}


TEST_F(PluginTest, FileNameArgumentsOverrideTheRecipe)
{
    write_text("shot.zdn", sample_recipe("\"eta\": 0.02"));
    RunResult r = zdenoise("--in " + quoted(kSample) + " --eta 0.05 -o "
                           + quoted(path("cli.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    r = oiiotool(quoted(path("shot.zdn") + "?eta=0.05&threads=1") + " -o "
                 + quoted(path("plugin.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("cli.exr"), path("plugin.exr"));
    EXPECT_NE(metadata(path("plugin.exr"))["zdenoise.parameters"].find("eta=0.05"),
              std::string::npos);

    // ?preset=spec replaces the recipe's filter options by the preset's.
    r = zdenoise("--in " + quoted(kSample) + " --preset spec -o " + quoted(path("spec.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    r = oiiotool(quoted(path("shot.zdn") + "?preset=spec") + " -o "
                 + quoted(path("plugin_spec.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("spec.exr"), path("plugin_spec.exr"));
}


TEST_F(PluginTest, IinfoPrintsTheSpec)
{
    write_text("shot.zdn", sample_recipe());
    RunResult r = run(host_program(kIinfo) + " -v " + quoted(path("shot.zdn")));
    ASSERT_EQ(r.status, 0) << r.err;
    for (const char* expected : { "96 x   96, 54 channel, float zdenoise",
                                  "ViewLayer.Combined.R", "ViewLayer.DiffCol.G",
                                  "cryptomatte/542cafa/manifest", "zdenoise.version",
                                  "zdenoise.parameters" })
        EXPECT_NE(r.out.find(expected), std::string::npos)
            << "iinfo -v lacks '" << expected << "':\n" << r.out;
}


TEST_F(PluginTest, PythonImageBufOpensRecipe)
{
    if (kPython.empty())
        GTEST_SKIP() << "/usr/bin/python3 not found";
    write_text("shot.zdn", sample_recipe());
    RunResult r = zdenoise("--in " + quoted(kSample) + " -o " + quoted(path("cli.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    r = python("recipe = oiio.ImageBuf(" + quoted(path("shot.zdn")) + ")\n"
               "cli = oiio.ImageBuf(" + quoted(path("cli.exr")) + ")\n"
               "spec = recipe.spec()\n"
               "assert not recipe.has_error, recipe.geterror()\n"
               "cmp = oiio.ImageBufAlgo.compare(recipe, cli, 0.0, 0.0)\n"
               "print(spec.width, spec.height, spec.nchannels, recipe.file_format_name,\n"
               "      cmp.nfail, cmp.maxerror)\n");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.out, "96 96 54 zdenoise 0 0.0\n") << r.err;
}


TEST_F(PluginTest, BrokenRecipesAreOiioErrorsNotCrashes)
{
    write_text("other.zdn", sample_recipe());
    struct Case {
        const char* name;
        std::string text;
        std::string problem;  ///< expected in the message
    } cases[] = {
        { "malformed.zdn", "{\"zdenoise-recipe\": 1, \"in\": ", "not valid JSON" },
        { "not_a_recipe.zdn", "{\"in\": \"x.exr\"}", "not a zdenoise recipe" },
        { "missing_input.zdn", "{\"zdenoise-recipe\": 1, \"in\": \"nope.exr\"}",
          "nope.exr': no such file" },
        { "missing_channel.zdn",
          sample_recipe("\"albedo\": {\"path\": \"sample.exr\", "
                        "\"channels\": \"Diffuse.R,Diffuse.G,Diffuse.B\"}"),
          "Diffuse.R" },
        { "typo.zdn", sample_recipe("\"etaa\": 0.03"), "unknown key \"etaa\"" },
        { "bad_value.zdn", sample_recipe("\"rmax\": \"big\""), "\"rmax\" must be a number" },
        // Found by fuzz_recipe: it became infinity, written back as null.
        { "huge_value.zdn", sample_recipe("\"edge-k\": 4e50"), "\"edge-k\" is out of range" },
        { "bad_filter.zdn", sample_recipe("\"rmin\": 5, \"rmax\": 3"), "r_max" },
        { "recursive.zdn", "{\"zdenoise-recipe\": 1, \"in\": \"other.zdn\"}",
          "itself a recipe" },
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        write_text(c.name, c.text);
        RunResult r = oiiotool(quoted(path(c.name)) + " -o " + quoted(path("out.exr")));
        EXPECT_EQ(r.status, 1) << "oiiotool must fail cleanly:\n" << r.err;
        EXPECT_NE(r.err.find(std::string("recipe '") + path(c.name) + "'"), std::string::npos)
            << r.err;
        EXPECT_NE(r.err.find(c.problem), std::string::npos) << r.err;
        EXPECT_FALSE(Filesystem::exists(path("out.exr")));
    }
    if (kPython.empty())
        return;
    RunResult r = python("buf = oiio.ImageBuf(" + quoted(path("missing_input.zdn")) + ")\n"
                         "print(buf.read(), buf.geterror())\n");
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("False"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("nope.exr': no such file"), std::string::npos) << r.out;
}


TEST_F(PluginTest, ValidFileDoesNotDenoise)
{
    if (kPython.empty())
        GTEST_SKIP() << "/usr/bin/python3 not found";
    // A recipe whose input is missing: valid_file() says "a recipe" without
    // running it; only open() finds the problem.
    write_text("missing_input.zdn", "{\"zdenoise-recipe\": 1, \"in\": \"nope.exr\"}");
    write_text("plain.json", "{\"in\": \"nope.exr\"}");
    RunResult r = python(
        "reader = oiio.ImageInput.create(" + quoted(path("missing_input.zdn")) + ")\n"
        "print(reader.format_name(), reader.valid_file(" + quoted(path("missing_input.zdn"))
        + "),\n      reader.valid_file(" + quoted(path("plain.json")) + "),\n"
        "      reader.valid_file(" + quoted(kSample) + "))\n");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.out, "zdenoise True False False\n");
}


TEST_F(PluginTest, WriteRecipeRoundTrip)
{
    Filesystem::create_directory(path("renders"));
    Filesystem::create_directory(path("recipes"));
    ASSERT_TRUE(Filesystem::copy(kSample, path("renders/shot.exr")));
    const std::string flags = "--in " + quoted(path("renders/shot.exr"))
                              + " --no-depth --eta 0.03 --rmax 12 --stride 2 --threads 1";
    // The inputs lie outside the recipe's folder: not written unless
    // ZDENOISE_RECIPE_PATH lets the plugin read them.
    RunResult r = zdenoise(flags + " --write-recipe " + quoted(path("recipes/shot.zdn")));
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("cannot write recipe '" + path("recipes/shot.zdn")
                         + "': it would not be read: \"in\" is '../renders/shot.exr': '..' "
                           "leads out of the recipe's folder"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("or list their folder in ZDENOISE_RECIPE_PATH"), std::string::npos)
        << r.err;
    EXPECT_FALSE(Filesystem::exists(path("recipes/shot.zdn")));
    const std::string allow = "ZDENOISE_RECIPE_PATH=" + quoted(path("renders")) + " ";
    r = run(allow + quoted(kCli) + " " + flags + " --write-recipe "
            + quoted(path("recipes/shot.zdn")));
    ASSERT_EQ(r.status, 0) << r.err;
    std::vector<std::string> names;
    Filesystem::get_directory_entries(path("recipes"), names);
    EXPECT_EQ(names.size(), 1u) << "only the recipe: nothing denoised, no temporary left";
    const std::string recipe = slurp(path("recipes/shot.zdn"));
    EXPECT_NE(recipe.find("\"../renders/shot.exr\""), std::string::npos)
        << "paths relative to the recipe's folder:\n" << recipe;
    EXPECT_NE(recipe.find("\"eta\": 0.03"), std::string::npos) << recipe;

    r = zdenoise(flags + " -o " + quoted(path("cli.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    r = run(allow + host_program(kOiiotool) + " " + quoted(path("recipes/shot.zdn")) + " -o "
            + quoted(path("plugin.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("cli.exr"), path("plugin.exr"));

    // Nor one asking for more than a recipe may.
    r = zdenoise("--in " + quoted(path("sample.exr")) + " --rmax 40 --write-recipe "
                 + quoted(path("big.zdn")));
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("\"rmax\" is 40: more than the 32"), std::string::npos) << r.err;
    EXPECT_FALSE(Filesystem::exists(path("big.zdn")));

    // A recipe may not name a recipe.
    r = zdenoise("--in " + quoted(path("recipes/shot.zdn")) + " --write-recipe "
                 + quoted(path("again.zdn")));
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("itself a recipe"), std::string::npos) << r.err;
    EXPECT_FALSE(Filesystem::exists(path("again.zdn")));
}


TEST_F(PluginTest, LayerOptionsRoundTripThroughRecipes)
{
    Filesystem::create_directory(path("renders"));
    ASSERT_TRUE(Filesystem::copy(kSample, path("renders/shot.exr")));
    const std::string flags
        = "--in " + quoted(path("renders/shot.exr"))
          + " --mode layers --aovs -d float"
            " --layer 'diff=ViewLayer.DiffDir+ViewLayer.DiffInd:ViewLayer.DiffCol:divided'"
            " --layer 'gloss=ViewLayer.GlossDir:ViewLayer.GlossCol:reflected:divided'"
            " --residual ViewLayer.Emit+ViewLayer.Env";
    RunResult r = zdenoise(flags + " --write-recipe " + quoted(path("shot.zdn")));
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string recipe = slurp(path("shot.zdn"));
    for (const char* key :
         { "\"mode\": \"layers\"", "\"aovs\": true", "\"data-type\": \"float\"",
           "\"diff=ViewLayer.DiffDir+ViewLayer.DiffInd:ViewLayer.DiffCol:divided\"",
           "\"gloss=ViewLayer.GlossDir:ViewLayer.GlossCol:divided:reflected\"",
           "\"residual\": \"ViewLayer.Emit+ViewLayer.Env\"" })
        EXPECT_NE(recipe.find(key), std::string::npos) << "recipe lacks " << key << ":\n"
                                                       << recipe;

    r = zdenoise(flags + " -o " + quoted(path("cli.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    r = oiiotool(quoted(path("shot.zdn")) + " -o " + quoted(path("plugin.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("cli.exr"), path("plugin.exr"));
    auto plugin = ImageInput::open(path("plugin.exr"));
    ASSERT_TRUE(plugin);
    EXPECT_GE(plugin->spec().channelindex("diff.G"), 0) << "--aovs came through the recipe";
}


TEST_F(PluginTest, RecipeDiagnosticsAddTheMapsAsTheCommandDoes)
{
    write_text("maps.zdn", sample_recipe("\"diagnostics\": true"));
    RunResult r = zdenoise("--in " + quoted(kSample) + " -o "
                           + quoted(path("cli.exr")) + " --diagnostics");
    ASSERT_EQ(r.status, 0) << r.err;
    r = oiiotool(quoted(path("maps.zdn")) + " -o " + quoted(path("plugin.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("cli.exr"), path("plugin.exr"));
    auto plugin = ImageInput::open(path("plugin.exr"));
    ASSERT_TRUE(plugin);
    const std::vector<std::string>& names = plugin->spec().channelnames;
    for (const char* n : { "zdenoise.radius", "zdenoise.stop", "zdenoise.noise",
                           "zdenoise.error" })
        EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
}


// --temporal in a recipe (docs/TEMPORAL.md): the recipe keeps the patterned
// inputs, its "frame" and the shot's range; read, it is the frame the
// sequence run writes, neighbours included. "?frame=N" reads another frame.
TEST_F(PluginTest, TemporalRecipeReadsTheFrameWithItsNeighbours)
{
    // Three frames of a static shot, each with noise of its own on the
    // beauty (the guides the same), so that the neighbours count.
    auto sample = ImageInput::open(kSample);
    ASSERT_TRUE(sample);
    const std::vector<std::string> names = sample->spec().channelnames;
    std::string beauty, rest;
    for (size_t c = 0; c < names.size(); ++c)
        (c < 3 ? beauty : rest) += (c == 0 || c == 3 ? "" : ",") + names[c];
    const std::string beauty_channels = beauty, other_channels = rest;
    for (int f : { 1, 2, 3 }) {
        RunResult r = oiiotool(
            quoted(kSample) + " --ch " + quoted(beauty_channels)
            + " --noise:type=uniform:min=0:max=0.05:seed=" + std::to_string(f) + " "
            + quoted(kSample) + " --ch " + quoted(other_channels) + " --chappend -o "
            + quoted(path("shot.000" + std::to_string(f) + ".exr")));
        ASSERT_EQ(r.status, 0) << r.err;
    }
    const std::string in = "--in " + quoted(path("shot.#.exr"))
                           + " --temporal 1 --static-camera --threads 1";
    RunResult r = zdenoise(in + " --frames 1-3 -o " + quoted(path("cli.#.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    r = zdenoise("--in " + quoted(path("shot.0002.exr")) + " -o " + quoted(path("alone.exr")));
    ASSERT_EQ(r.status, 0) << r.err;

    r = zdenoise(in + " --frames 2 --shot-range 1-3 --write-recipe " + quoted(path("shot.zdn")));
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string recipe = slurp(path("shot.zdn"));
    for (const char* line : { "\"path\": \"shot.#.exr\"", "\"temporal\": 1",
                              "\"static-camera\": true", "\"frame\": \"2\"",
                              "\"shot-range\": \"1-3\"" })
        EXPECT_NE(recipe.find(line), std::string::npos) << line << " in\n" << recipe;
    r = oiiotool(quoted(path("shot.zdn")) + " -o " + quoted(path("plugin.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("cli.0002.exr"), path("plugin.exr"));
    ImageBuf alone(path("alone.exr")), plugin(path("plugin.exr"));
    EXPECT_GT(ImageBufAlgo::compare(alone, plugin, 0.0f, 0.0f).maxerror, 0.0)
        << "the neighbours count";
    r = oiiotool(quoted(path("shot.zdn") + "?frame=3") + " -o " + quoted(path("plugin3.exr")));
    ASSERT_EQ(r.status, 0) << r.err;
    expect_identical(path("cli.0003.exr"), path("plugin3.exr"));

    // What a recipe of one frame cannot be.
    r = zdenoise(in + " --frames 2 --write-recipe " + quoted(path("no_shot.zdn")));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("--temporal needs --shot-range"), std::string::npos) << r.err;
    r = zdenoise(in + " --frames 1-3 --shot-range 1-3 --write-recipe " + quoted(path("x.zdn")));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("need --frames of one frame"), std::string::npos) << r.err;
    write_text("bad.zdn", "{\"zdenoise-recipe\": 1, \"in\": \"shot.#.exr\", \"temporal\": 1, "
                          "\"static-camera\": true, \"frame\": \"2\"}");
    r = oiiotool(quoted(path("bad.zdn")) + " -o " + quoted(path("bad.exr")));
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("\"temporal\" needs \"shot-range\""), std::string::npos) << r.err;
    r = oiiotool(quoted(path("shot.zdn") + "?frame=4") + " -o " + quoted(path("bad.exr")));
    EXPECT_NE(r.status, 0) << "frame 4 lies beyond the shot";
}
