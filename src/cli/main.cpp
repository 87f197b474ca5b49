// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// zdenoise: the command-line tool. Conventions follow oiiotool: options
// take their values as the following arguments, input options take an
// optional `:ch=` modifier selecting channels (`--albedo:ch=R,G,B a.exr`).

#include <cctype>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include <zdenoise/zdenoise.h>

#include "../job/atomic_write.h"
#include "../job/job.h"
#include "../job/option_names.h"
#include "../job/recipe.h"
#include "sequence.h"

using namespace OIIO;
using OIIO::Strutil::fmt::format;
using namespace zdenoise;

namespace {

constexpr int kExitError = 1;
constexpr int kExitUsage = 2;

const char* kUsage = R"(zdenoise )" ZDENOISE_VERSION_STRING R"( -- denoise Monte Carlo renders (Zhdanov, Ershov & Voloboy 2018)

Usage: zdenoise --in NOISY -o OUTPUT [options]
       zdenoise --in NOISY --write-recipe RECIPE.zdn [options]

Inputs (each FILE may take a channel selection, oiiotool style:
--albedo:ch=R,G,B FILE, or a layer name: --albedo:ch="Denoising Albedo" FILE):
  --in FILE            Noisy render (radiance R,G,B and optional A).
  --albedo FILE        Noise-free albedo (R,G,B). Required unless --in is a
                       Blender Cycles multilayer EXR.
  --normal FILE        Normal guide (X,Y,Z).
  --depth FILE         Depth guide (Z).
  --id FILE            Object id guide (one channel, or id,coverage pairs).
  --variance FILE      Per-pixel variance of the radiance (1 or 3 channels).
  --halves A B         Two independent half renders (radiance = (A+B)/2).
  --no-normal, --no-depth, --no-id
                       Do not use the guide picked by default.
  A Blender Cycles multilayer EXR (channels <layer>.Combined.R ...) needs no
  other input: Combined, Denoising Albedo, Denoising Normal, Denoising Depth
  and CryptoObject (else IndexOB) are taken from it. So are Arnold-style
  AOVs (X with X_albedo, N, Z, crypto_object) and specular depth layers
  (spec0..spec5 with spec0_albedo.., residual); see docs/LAYERS.md.

Layers (docs/LAYERS.md):
  --mode MODE          'layers': denoise each layer (lobe or specular depth)
                       with its own albedo, add the residual;
                       'beauty': denoise the beauty with the albedo. Default:
                       layers when --layer is given, else beauty (layers are
                       better where lobe passes exist; docs/LAYERS.md).
  --layer NAME=RADIANCE:ALBEDO[:divided][:reflected]
                       A layer of the --in file (repeatable; replaces the
                       detected layers). RADIANCE and ALBEDO are channel
                       selections as for :ch= (a layer name or a list of
                       channels); RADIANCE may sum sets with '+'
                       (DiffDir+DiffInd). 'divided': the radiance is already
                       divided by the albedo (Cycles' Dir/Ind passes).
                       'reflected': light through a glossy or specular bounce
                       (reflection, refraction): a stricter edge test.
  --residual CHANNELS  What is added unfiltered (e.g. Emit+Env). Default: the
                       beauty minus the layers.
  --aovs               Also write each denoised layer as NAME.R,G,B.

Output:
  -o FILE              Output image: the --in file with its radiance channels
                       denoised; every other channel and the metadata kept,
                       each channel in its input pixel type. Written to a
                       temporary file, then renamed.
  -d TYPE              Output pixel type, 'half' or 'float' (default: each
                       channel's input type). Cryptomatte channels stay float.
  --force              Allow the output to replace one of the inputs.
  --write-recipe FILE  Instead of denoising, write a recipe (.zdn) for these
                       options: any OpenImageIO program with the zdenoise
                       plugin reads it as the denoised image
                       (share/zdn-format.md).

Colour (OpenColorIO; docs/COLOUR.md):
  --colorconfig FILE   OCIO config (default: $OCIO, else the bundled
                       share/zdenoise/ocio/config.ocio).
  --iscolorspace NAME  Colour space of the noisy input (default: an EXR's
                       chromaticities, else the config's scene_linear; a
                       PNG/JPEG's tag, sRGB). -v says what was assumed.
  --albedo-colorspace NAME
                       Colour space of the albedo (default: as --in when
                       from the same file, else guessed the same way).
  --ocolorspace NAME   Colour space of the output (default: the input's).
  --working-colorspace NAME
                       Space the filter works in (default: scene_linear).
                       Demodulation is per channel: use the renderer's
                       rendering space.

Filter parameters (docs/FILTER.md):
  --preset NAME        Start from a parameter set: 'tuned' (default, tuned on
                       the public benchmark) or 'spec' (ALGORITHM.md section
                       8: edge-k 3, value-k 2, sigma-good 1); the options
                       below override it wherever they stand.
  --rmin N             Smallest window half-size (default 2)
  --rmax N             Largest window half-size (default 16)
  --eta X              Target relative noise at the window centre (0.02)
  --edge-k X           Strong-variation stop: multiple of the noise (1.5)
  --tau-min X          Strong-variation stop: smallest level (0.05)
  --value-k X          Strength of the value weight (1)
  --sigma-good X       Noisiest point taking part in fits (3)
  --albedo-eps X       Smallest albedo demodulated (0.001)
  --depth-tol X        Relative depth departure ending a surface (0.02)
  --normal-cut X       Normal weight is 0 at or below this dot product (0.5)
  --normal-power X     Normal weight exponent (4)
  --quadrant-power X   Quadrant weight exponent (8)
  --radius-growth X    Radius tried after R: max(R+1, R*X) (2: radii 2, 4, 8,
                       16; 1 = ALGORITHM.md's R+1, as --preset spec)
  --stride N           Fit windows at every N-th pixel, and at every pixel
                       near an edge (3; 1 = the exact filter, 1.5x as slow,
                       within 2% of the same relMSE; docs/PERFORMANCE.md)
  --stride-edges 0|1   0: the lattice only, also at edges (preview: 2x
                       faster again, up to 27% worse relMSE) (1)

Frame sequences (oiiotool's conventions) and batches:
  --frames LIST        Frames to denoise: 1001-1100, 1-99x2 (every 2nd),
                       1,5,10-20; any FILE (and -o) may then name a frame
                       pattern: shot.#.exr (4 digits), shot.@@@.exr (one
                       digit per @), shot.%04d.exr.
  --skip-existing      Leave frames whose output exists (re-runs).
  --fail-fast          Stop at the first failed frame (default: report it,
                       denoise the others, exit 1 at the end).
  --report FILE.json   Per-frame wall time, parameters, filter statistics.
  --print-chunks N     Print the frame list in chunks of N frames, one
                       --frames list per line, and exit (farm dispatch:
                       share/zdenoise/farm/zdenoise-sbatch).

General:
  --mem-limit SIZE     Refuse a frame needing more memory than SIZE (bytes,
                       or with a K, M, G or T suffix), before reading its
                       pixels. Default: half the machine's memory.
  --tile N             Read, denoise and write the frame in strips of N
                       rows (each read with the filter's halo of
                       2*rmax+4 rows around it): memory follows N, not the
                       frame. Default: automatic, the whole frame when it is
                       small, else strips that fit the memory. Results do
                       not depend on it.
  --threads N          Threads (default: all cores); results do not depend
                       on it.
  -v                   Verbose: inputs, parameters, progress, timings,
                       statistics.
  --help               This text.
  --version            Print the version.
)";

/// Thrown inside main's helpers only, caught in main: a one-line message
/// and an exit code.
struct Failure {
    std::string message;
    int code;
};

[[noreturn]] void
fail(const std::string& message, int code = kExitError)
{
    throw Failure { message, code };
}

struct Args {
    job::Job job;
    std::string preset = "tuned";
    std::string output;
    std::string recipe;  ///< --write-recipe
    bool force   = false;
    bool verbose = false;
    cli::SequenceOptions batch;  ///< frame sequences, reports (sequence.h)
};

double
parse_number(const std::string& opt, const std::string& value)
{
    double v = 0.0;
    if (!job::parse_real(value, v))
        fail(format("{} needs a number, got '{}'", opt, value), kExitUsage);
    return v;
}

int
parse_int(const std::string& opt, const std::string& value)
{
    int v = 0;
    if (!job::parse_whole(value, v))
        fail(format("{} needs a whole number, got '{}'", opt, value),
             kExitUsage);
    return v;
}

/// "8G", "512M", "1048576": a size in bytes, with a binary suffix.
uint64_t
parse_size(const std::string& opt, const std::string& value)
{
    std::string digits = value;
    double scale       = 1.0;
    const std::string suffixes = "KMGT";
    if (!digits.empty()) {
        size_t k = suffixes.find(char(std::toupper(digits.back())));
        if (k != std::string::npos) {
            scale = std::ldexp(1.0, 10 * int(k + 1));
            digits.pop_back();
        }
    }
    const double v = parse_number(opt, digits) * scale;
    if (v < 1.0 || v > 1.8e19)
        fail(format("{} needs a size such as 512M or 8G, got '{}'", opt,
                    value),
             kExitUsage);
    return uint64_t(v);
}

Args
parse_args(int argc, char* argv[])
{
    Args a;
    std::vector<std::string> av(argv + 1, argv + argc);
    // The preset is the base the other filter options modify, wherever it
    // stands on the command line.
    for (size_t k = 0; k + 1 < av.size(); ++k)
        if (av[k] == "--preset") {
            a.preset = av[k + 1];
            if (!job::apply_preset(a.preset, a.job.filter))
                fail(format("--preset: unknown preset '{}' (known: {})",
                            a.preset, job::preset_names()),
                     kExitUsage);
        }
    size_t i   = 0;
    auto value = [&](const std::string& opt) -> std::string {
        if (i + 1 >= av.size())
            fail(format("{} needs a value", opt), kExitUsage);
        return av[++i];
    };
    std::map<std::string, job::InputArg*> inputs
        = { { "--in", &a.job.in },       { "--albedo", &a.job.albedo },
            { "--normal", &a.job.normal }, { "--depth", &a.job.depth },
            { "--id", &a.job.id },       { "--variance", &a.job.variance } };
    std::map<std::string, std::string*> colour_options
        = { { "--colorconfig", &a.job.colour.config },
            { "--iscolorspace", &a.job.colour.input_space },
            { "--albedo-colorspace", &a.job.colour.albedo_space },
            { "--ocolorspace", &a.job.colour.output_space },
            { "--working-colorspace", &a.job.colour.working_space } };
    std::map<std::string, float*> floats;
    std::map<std::string, int*> ints = { { "--threads", &a.job.threads },
                                         { "--tile", &a.job.tile_rows } };
    for (const job::FilterOptionName& o : job::filter_option_names()) {
        if (o.real)
            floats[std::string("--") + o.name] = &(a.job.filter.*o.real);
        else
            ints[std::string("--") + o.name] = &(a.job.filter.*o.whole);
    }
    for (; i < av.size(); ++i) {
        std::string arg = av[i];
        // oiiotool-style modifiers: --albedo:ch=R,G,B
        std::string opt = arg, modifiers;
        size_t colon    = arg.find(':');
        if (Strutil::starts_with(arg, "--") && colon != std::string::npos) {
            opt       = arg.substr(0, colon);
            modifiers = arg.substr(colon + 1);
        }
        if (opt == "--help" || opt == "-h") {
            fputs(kUsage, stdout);
            std::exit(0);
        } else if (opt == "--version") {
            printf("zdenoise %s\n", ZDENOISE_VERSION_STRING);
            std::exit(0);
        } else if (inputs.count(opt) || opt == "--halves") {
            std::string channels;
            if (!modifiers.empty()) {
                if (!Strutil::starts_with(modifiers, "ch="))
                    fail(format("{}: unknown modifier '{}' (only :ch= is "
                                "known)",
                                opt, modifiers),
                         kExitUsage);
                channels = modifiers.substr(3);
            }
            if (opt == "--halves") {
                a.job.half_a = { value(opt), channels, true };
                a.job.half_b = { value(opt), channels, true };
            } else {
                *inputs[opt] = { value(opt), channels, true };
            }
        } else if (!modifiers.empty()) {
            fail(format("option {} takes no modifiers", opt), kExitUsage);
        } else if (opt == "-o") {
            a.output = value(opt);
        } else if (opt == "--write-recipe") {
            a.recipe = value(opt);
        } else if (opt == "--mem-limit") {
            a.job.mem_limit = parse_size(opt, value(opt));
        } else if (opt == "--preset") {
            value(opt);  // applied above
        } else if (opt == "--frames") {
            a.batch.frames = value(opt);
        } else if (opt == "--report") {
            a.batch.report = value(opt);
        } else if (opt == "--fail-fast") {
            a.batch.fail_fast = true;
        } else if (opt == "--skip-existing") {
            a.batch.skip_existing = true;
        } else if (opt == "--print-chunks") {
            a.batch.print_chunks = parse_int(opt, value(opt));
            if (a.batch.print_chunks < 1)
                fail("--print-chunks needs a chunk size >= 1", kExitUsage);
        } else if (colour_options.count(opt)) {
            *colour_options[opt] = value(opt);
        } else if (floats.count(opt)) {
            *floats[opt] = float(parse_number(opt, value(opt)));
        } else if (ints.count(opt)) {
            *ints[opt] = parse_int(opt, value(opt));
        } else if (opt == "--mode") {
            const std::string mode = value(opt);
            if (!job::parse_mode(mode, a.job.mode))
                fail(format("--mode: unknown mode '{}' (known: layers, "
                            "beauty)",
                            mode),
                     kExitUsage);
        } else if (opt == "--layer") {
            const std::string text = value(opt);
            a.job.layers.emplace_back();
            if (!job::parse_layer(text, a.job.layers.back()))
                fail(format("--layer needs NAME=RADIANCE:ALBEDO[:divided][:reflected], "
                            "got '{}'",
                            text),
                     kExitUsage);
        } else if (opt == "--residual") {
            a.job.residual = value(opt);
        } else if (opt == "--aovs") {
            a.job.write_layers = true;
        } else if (opt == "-d") {
            const std::string type = value(opt);
            if (!job::parse_data_type(type, a.job.data_type))
                fail(format("-d: unknown type '{}' (known: half, float)",
                            type),
                     kExitUsage);
        } else if (opt == "--no-normal") {
            a.job.no_normal = true;
        } else if (opt == "--no-depth") {
            a.job.no_depth = true;
        } else if (opt == "--no-id") {
            a.job.no_id = true;
        } else if (opt == "--force") {
            a.force = true;
        } else if (opt == "-v") {
            a.verbose = true;
        } else {
            fail(format("unknown option '{}' (see zdenoise --help)", arg),
                 kExitUsage);
        }
    }
    if (!a.job.in.given)
        fail("no input: give --in FILE (see zdenoise --help)", kExitUsage);
    if (a.output.empty() && a.recipe.empty() && !a.batch.print_chunks)
        fail("no output: give -o FILE (see zdenoise --help)", kExitUsage);
    if (!a.output.empty() && !a.recipe.empty())
        fail("give either -o FILE (denoise) or --write-recipe FILE (write a "
             "recipe to denoise later), not both",
             kExitUsage);
    if (a.job.threads < 0)
        fail(format("--threads needs a number >= 0, got {}", a.job.threads),
             kExitUsage);
    if (a.job.tile_rows < 0)
        fail(format("--tile needs a number of rows >= 1 (or 0: automatic), "
                    "got {}",
                    a.job.tile_rows),
             kExitUsage);
    return a;
}


// Interruption (SIGINT, SIGTERM): the only files zdenoise creates before
// their final rename are temporary ones, so the handler removes the one
// being written and exits with the shell's 128 + signal. A handler may
// call only async-signal-safe functions: unlink, _exit, and reading the
// name write_atomically() prepared.
extern "C" void
on_interrupt(int signal)
{
    if (const char* tmp = job::temporary_file_in_flight())
        ::unlink(tmp);
    ::_exit(128 + signal);
}

void
remove_temporary_files_on_interrupt()
{
    struct sigaction action = {};
    action.sa_handler       = on_interrupt;
    sigemptyset(&action.sa_mask);
    for (int signal : { SIGINT, SIGTERM })
        sigaction(signal, &action, nullptr);
}


int
run(int argc, char* argv[])
{
    Args a = parse_args(argc, argv);
    remove_temporary_files_on_interrupt();
    std::string err;
    if (!a.recipe.empty() && cli::is_batch(a.job, a.recipe, a.batch))
        fail("--write-recipe writes the recipe of one image: no frame "
             "patterns, --frames or batch options",
             kExitUsage);
    if (!a.recipe.empty()) {
        if (!job::write_recipe(a.job, a.preset, a.recipe, err))
            fail(err);
        if (a.verbose)
            printf("zdenoise: wrote recipe '%s'\n", a.recipe.c_str());
        return 0;
    }
    if (a.job.threads > 0)
        OIIO::attribute("threads", a.job.threads);
    a.batch.verbose = a.verbose;
    a.batch.force   = a.force;
    if (cli::is_batch(a.job, a.output, a.batch)) {
        const int status = cli::run_batch(a.job, a.output, a.batch, err);
        if (status != 0)
            fail(err, status);
        return 0;
    }
    Timer total;

    // Never overwrite an input unless asked.
    if (!a.force)
        for (const std::string& in : job::input_paths(a.job))
            if (cli::same_file(in, a.output))
                fail(format("the output '{}' is also an input; use --force "
                            "to replace it",
                            a.output));

    int last_tenth = -1;
    if (a.verbose) {
        const bool tty = isatty(fileno(stderr));
        // tty by value: the callback runs after this block has ended.
        a.job.filter.progress = [&last_tenth, tty](float f) {
            int tenth = int(f * 10.0f);
            if (tenth != last_tenth) {
                last_tenth = tenth;
                fprintf(stderr, tty ? "\rzdenoise: filtering %3d%%"
                                    : "zdenoise: filtering %3d%%\n",
                        tenth * 10);
                if (tty && tenth == 10)
                    fputc('\n', stderr);
            }
        };
    }
    // Read, denoised and written strip by strip (job.h).
    job::JobResult result;
    const bool ok = job::run_job_to_file(a.job, a.output, result, err);
    if (a.verbose)
        for (const std::string& line : result.log)
            printf("zdenoise: %s\n", line.c_str());
    if (!ok)
        fail(err);

    if (a.verbose) {
        const FilterStats& stats = result.stats;
        const double n = double(std::max<int64_t>(stats.pixels, 1));
        const double w = double(std::max<int64_t>(stats.windows, 1));
        printf("zdenoise: windows %lld, mean radius %.2f; stopped by "
               "quality %.1f%%, size %.1f%%, edge %.1f%%\n",
               (long long)stats.windows, stats.mean_radius,
               100.0 * stats.stop_quality / w, 100.0 * stats.stop_size / w,
               100.0 * stats.stop_edge / w);
        printf("zdenoise: passed through %.2f%% of pixels (%lld), "
               "non-finite input pixels %lld\n",
               100.0 * stats.passthrough_pixels / n,
               (long long)stats.passthrough_pixels,
               (long long)stats.nonfinite_pixels);
        printf("zdenoise: read %.2fs, denoise %.2fs, write %.2fs, total "
               "%.2fs -> '%s'\n",
               result.read_seconds, result.denoise_seconds,
               result.write_seconds, total(), a.output.c_str());
    }
    return 0;
}

}  // namespace


int
main(int argc, char* argv[])
{
    try {
        return run(argc, argv);
    } catch (const Failure& f) {
        fprintf(stderr, "zdenoise: error: %s\n", f.message.c_str());
        return f.code;
    } catch (const std::exception& e) {
        fprintf(stderr, "zdenoise: error: %s\n", e.what());
        return kExitError;
    }
}
