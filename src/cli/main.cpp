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
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>
#ifdef __GLIBC__
#    include <malloc.h>
#endif

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include <zdenoise/zdenoise.h>

#include "job/atomic_write.h"
#include "job/failure.h"
#include "job/frames.h"
#include "job/job.h"
#include "job/options.h"
#include "job/validate.h"
#include "job/recipe.h"
#include "sequence.h"

using namespace OIIO;
using OIIO::Strutil::fmt::format;
using namespace zdenoise;
using zdenoise::cli::kExitError;
using zdenoise::cli::kExitUsage;

namespace {

/// Thrown inside main's helpers, caught in main: a one-line message and
/// an exit code.
[[noreturn]] void
fail(const std::string& message, int code = kExitError)
{
    throw job::Failure { message, code };
}

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
    uint64_t v = 0;
    if (!job::parse_size(value, v))
        fail(format("{} needs a size such as 512M or 8G, got '{}'", opt,
                    value),
             kExitUsage);
    return v;
}

/// Set `option` of `c` from its command-line value, read by `value`.
void
parse_value(const job::Option& option, const std::string& opt,
            const std::string& channels,
            const std::function<std::string()>& value, job::Command& c)
{
    using job::Field;
    using job::Kind;
    switch (option.kind) {
    case Kind::Input:
        std::get<Field<job::InputArg>>(option.field)(c) = { value(), channels,
                                                            true };
        break;
    case Kind::Halves:
        c.job.half_a = { value(), channels, true };
        c.job.half_b = { value(), channels, true };
        break;
    case Kind::Flag: std::get<Field<bool>>(option.field)(c) = true; break;
    case Kind::Text:
    case Kind::Name:
    case Kind::Path:
        std::get<Field<std::string>>(option.field)(c) = value();
        break;
    case Kind::Preset: value(); break;  // applied first
    case Kind::Real:
        std::get<Field<float>>(option.field)(c) = float(
            parse_number(opt, value()));
        break;
    case Kind::Whole:
        std::get<Field<int>>(option.field)(c) = parse_int(opt, value());
        break;
    case Kind::Size:
        std::get<Field<uint64_t>>(option.field)(c) = parse_size(opt, value());
        break;
    case Kind::Mode: {
        const std::string mode = value();
        if (!job::parse_mode(mode, c.job.mode))
            fail(format("--mode: unknown mode '{}' (known: beauty, layers, path)",
                        mode),
                 kExitUsage);
        break;
    }
    case Kind::Names: {
        const std::string name = value();
        if (name.empty())
            fail(format("{}: the name is empty", opt), kExitUsage);
        std::get<Field<std::vector<std::string>>>(option.field)(c).push_back(name);
        break;
    }
    case Kind::Layers: {
        const std::string text = value();
        c.job.layers.emplace_back();
        if (!job::parse_layer(text, c.job.layers.back()))
            fail(format("--layer needs NAME=RADIANCE:ALBEDO[:divided][:reflected], "
                        "got '{}'",
                        text),
                 kExitUsage);
        break;
    }
    case Kind::DataType: {
        const std::string type = value();
        if (!job::parse_data_type(type, c.job.data_type))
            fail(format("-d: unknown type '{}' (known: half, float)", type),
                 kExitUsage);
        break;
    }
    case Kind::Help: fputs(job::usage_text().c_str(), stdout); std::exit(0);
    case Kind::Version:
        printf("zdenoise %s\n", ZDENOISE_VERSION_STRING);
        std::exit(0);
    }
}


job::Command
parse_args(int argc, char* argv[])
{
    job::Command a;
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
    for (size_t i = 0; i < av.size(); ++i) {
        const std::string arg = av[i];
        // oiiotool-style modifiers: --albedo:ch=R,G,B
        std::string opt = arg, modifiers;
        size_t colon    = arg.find(':');
        if (Strutil::starts_with(arg, "--") && colon != std::string::npos) {
            opt       = arg.substr(0, colon);
            modifiers = arg.substr(colon + 1);
        }
        const job::Option* option = job::find_flag(opt);
        const bool input          = option
                           && (option->kind == job::Kind::Input
                               || option->kind == job::Kind::Halves);
        std::string channels;
        if (input && !modifiers.empty()) {
            if (!Strutil::starts_with(modifiers, "ch="))
                fail(format("{}: unknown modifier '{}' (only :ch= is known)",
                            opt, modifiers),
                     kExitUsage);
            channels = modifiers.substr(3);
        }
        const bool action = option
                            && (option->kind == job::Kind::Help
                                || option->kind == job::Kind::Version);
        if (!input && !action && !modifiers.empty())
            fail(format("option {} takes no modifiers", opt), kExitUsage);
        if (!option)
            fail(format("unknown option '{}' (see zdenoise --help)", arg),
                 kExitUsage);
        parse_value(*option, opt, channels, [&]() -> std::string {
            if (i + 1 >= av.size())
                fail(format("{} needs a value", opt), kExitUsage);
            return av[++i];
        }, a);
        if (opt == "--print-chunks" && a.print_chunks < 1)
            fail("--print-chunks needs a chunk size >= 1", kExitUsage);
    }
    // What to do is checked once there is an input (so that a bare
    // `zdenoise` says what to give first), then the job.
    if (a.job.in.given && a.output.empty() && a.recipe.empty()
        && !a.print_chunks)
        fail("no output: give -o FILE (see zdenoise --help)", kExitUsage);
    if (a.job.in.given && !a.output.empty() && !a.recipe.empty())
        fail("give either -o FILE (denoise) or --write-recipe FILE (write a "
             "recipe to denoise later), not both",
             kExitUsage);
    const std::string invalid = job::validate(a.job,
                                              job::Spelling::CommandLine);
    if (!invalid.empty())
        fail(invalid, kExitUsage);
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
    job::Command a = parse_args(argc, argv);
    remove_temporary_files_on_interrupt();
    std::string err;
    cli::SequenceOptions batch;
    batch.frames        = a.frames;
    batch.report        = a.report;
    batch.fail_fast     = a.fail_fast;
    batch.skip_existing = a.skip_existing;
    batch.print_chunks  = a.print_chunks;
    batch.verbose       = a.verbose;
    batch.force         = a.force;
    if (!a.recipe.empty()) {
        // A recipe is one image: at most one frame (--frames N) of
        // patterned inputs, which it keeps with the frame's number.
        const bool patterned = job::job_has_frame_pattern(a.job);
        std::vector<int> frames;
        std::string why;
        if (job::has_frame_pattern(a.recipe))
            why = "its name has no frame pattern";
        else if (!a.report.empty() || a.fail_fast || a.skip_existing
                 || a.print_chunks > 0)
            why = "no batch options (--report, --fail-fast, --skip-existing, "
                  "--print-chunks)";
        else if (patterned
                 && (!job::parse_frame_list(a.frames, frames)
                     || frames.size() != 1))
            why = "inputs with a frame pattern need --frames of one frame";
        else if (!patterned && (!a.frames.empty() || !a.job.shot_range.empty()))
            why = "--frames and --shot-range need inputs with a frame "
                  "pattern (shot.#.exr)";
        else if (a.job.temporal > 0 && a.job.shot_range.empty())
            why = "--temporal needs --shot-range, the shot's frames that the "
                  "neighbours lie within";
        if (!why.empty())
            fail("--write-recipe writes the recipe of one image: " + why,
                 kExitUsage);
        a.job.frame = a.frames;
        if (!job::write_recipe(a.job, a.preset, a.recipe, err))
            fail(err);
        if (a.verbose)
            printf("zdenoise: wrote recipe '%s'\n", a.recipe.c_str());
        return 0;
    }
    if (a.job.threads > 0)
        OIIO::attribute("threads", a.job.threads);
    if (cli::is_batch(a.job, a.output, batch)) {
        const int status = cli::run_batch(a.job, a.output, batch, err);
        if (status != 0)
            fail(err, status);
        return 0;
    }
    if (a.job.temporal > 0)
        fail("--temporal needs a frame sequence, e.g. --in shot.#.exr "
             "--frames 1001-1100 -o clean.#.exr",
             kExitUsage);
    Timer total;

    // Never overwrite an input unless asked.
    const std::string refused = job::output_is_input(
        a.job, a.output, a.force, job::Spelling::CommandLine);
    if (!refused.empty())
        fail(refused);

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
        if (stats.kept_pixels)
            printf("zdenoise: direct light: the significance filter kept "
                   "structure at %lld pixels\n",
                   (long long)stats.kept_pixels);
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
#ifdef __GLIBC__
    // Each strip allocates and frees the filter's planes (tens of MB).
    // glibc would serve them by mmap and give them back at once, so that
    // every strip faults in and zeroes its pages again: 6 % of a 1080p
    // frame's time (docs/PERFORMANCE.md). Kept in the heap they are reused;
    // the peak, which the memory plan bounds, does not change.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
    try {
        return run(argc, argv);
    } catch (const job::Failure& f) {
        fprintf(stderr, "zdenoise: error: %s\n", f.message.c_str());
        return f.exit_code;
    } catch (const std::exception& e) {
        fprintf(stderr, "zdenoise: error: %s\n", e.what());
        return kExitError;
    }
}
