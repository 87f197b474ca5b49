// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// zdenoise: the command-line tool. Conventions follow oiiotool: options
// take their values as the following arguments, input options take an
// optional `:ch=` modifier selecting channels (`--albedo:ch=R,G,B a.exr`).

#include <cerrno>
#include <cmath>
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

#include "atomic_write.h"
#include "channel_spec.h"

using namespace OIIO;
using OIIO::Strutil::fmt::format;
using namespace zdenoise;
using namespace zdenoise::cli;

namespace {

constexpr int kExitError = 1;
constexpr int kExitUsage = 2;

const char* kUsage = R"(zdenoise )" ZDENOISE_VERSION_STRING R"( -- denoise Monte Carlo renders (Zhdanov, Ershov & Voloboy 2018)

Usage: zdenoise --in NOISY -o OUTPUT [options]

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
  and IndexOB are taken from it.

Output:
  -o FILE              Output image: the --in file with its radiance channels
                       denoised; every other channel and the metadata kept,
                       each channel in its input pixel type. Written to a
                       temporary file, then renamed.
  --force              Allow the output to replace one of the inputs.

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

General:
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

/// OIIO error texts can span lines; the tool reports one.
std::string
one_line(std::string s)
{
    s = Strutil::strip(s);
    for (char& c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    return s;
}

struct InputArg {
    std::string path;
    std::string channels;  ///< the :ch= selection; empty = default
    bool given = false;
};

struct Args {
    InputArg in, albedo, normal, depth, id, variance, half_a, half_b;
    bool no_normal = false, no_depth = false, no_id = false;
    std::string output;
    bool force   = false;
    bool verbose = false;
    int threads  = 0;
    FilterOptions filter;
};

double
parse_number(const std::string& opt, const std::string& value)
{
    const char* s = value.c_str();
    char* end     = nullptr;
    errno         = 0;
    double v      = std::strtod(s, &end);
    if (value.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
        fail(format("{} needs a number, got '{}'", opt, value), kExitUsage);
    return v;
}

int
parse_int(const std::string& opt, const std::string& value)
{
    double v = parse_number(opt, value);
    if (v != std::floor(v) || std::fabs(v) > 1e6)
        fail(format("{} needs a whole number, got '{}'", opt, value),
             kExitUsage);
    return int(v);
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
            if (av[k + 1] == "spec")
                a.filter = FilterOptions::algorithm_defaults();
            else if (av[k + 1] != "tuned")
                fail(format("--preset: unknown preset '{}' (known: tuned, "
                            "spec)",
                            av[k + 1]),
                     kExitUsage);
        }
    size_t i   = 0;
    auto value = [&](const std::string& opt) -> std::string {
        if (i + 1 >= av.size())
            fail(format("{} needs a value", opt), kExitUsage);
        return av[++i];
    };
    std::map<std::string, InputArg*> inputs
        = { { "--in", &a.in },       { "--albedo", &a.albedo },
            { "--normal", &a.normal }, { "--depth", &a.depth },
            { "--id", &a.id },       { "--variance", &a.variance } };
    std::map<std::string, float*> floats
        = { { "--eta", &a.filter.eta_target },
            { "--edge-k", &a.filter.edge_k },
            { "--tau-min", &a.filter.tau_min },
            { "--value-k", &a.filter.value_k },
            { "--sigma-good", &a.filter.sigma_good },
            { "--albedo-eps", &a.filter.albedo_eps },
            { "--depth-tol", &a.filter.depth_tolerance },
            { "--normal-cut", &a.filter.normal_cut },
            { "--normal-power", &a.filter.normal_power },
            { "--quadrant-power", &a.filter.quadrant_power } };
    std::map<std::string, int*> ints = { { "--rmin", &a.filter.r_min },
                                         { "--rmax", &a.filter.r_max },
                                         { "--threads", &a.threads } };
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
                a.half_a = { value(opt), channels, true };
                a.half_b = { value(opt), channels, true };
            } else {
                *inputs[opt] = { value(opt), channels, true };
            }
        } else if (!modifiers.empty()) {
            fail(format("option {} takes no modifiers", opt), kExitUsage);
        } else if (opt == "-o") {
            a.output = value(opt);
        } else if (opt == "--preset") {
            value(opt);  // applied above
        } else if (floats.count(opt)) {
            *floats[opt] = float(parse_number(opt, value(opt)));
        } else if (ints.count(opt)) {
            *ints[opt] = parse_int(opt, value(opt));
        } else if (opt == "--no-normal") {
            a.no_normal = true;
        } else if (opt == "--no-depth") {
            a.no_depth = true;
        } else if (opt == "--no-id") {
            a.no_id = true;
        } else if (opt == "--force") {
            a.force = true;
        } else if (opt == "-v") {
            a.verbose = true;
        } else {
            fail(format("unknown option '{}' (see zdenoise --help)", arg),
                 kExitUsage);
        }
    }
    if (!a.in.given)
        fail("no input: give --in FILE (see zdenoise --help)", kExitUsage);
    if (a.output.empty())
        fail("no output: give -o FILE (see zdenoise --help)", kExitUsage);
    if (a.threads < 0)
        fail(format("--threads needs a number >= 0, got {}", a.threads),
             kExitUsage);
    return a;
}


/// Input files, each read once however many roles it serves.
class InputFiles {
public:
    ImageBuf& get(const std::string& path)
    {
        auto it = m_files.find(path);
        if (it != m_files.end())
            return *it->second;
        if (!Filesystem::exists(path))
            fail(format("cannot read '{}': no such file", path));
        auto buf = std::make_unique<ImageBuf>(path);
        if (!buf->init_spec(path, 0, 0))
            fail(format("cannot read '{}': {}", path,
                        one_line(buf->geterror())));
        if (buf->deep())
            fail(format("cannot read '{}': deep images are not supported",
                        path));
        if (!buf->read(0, 0, true, TypeFloat))
            fail(format("cannot read '{}': {}", path,
                        one_line(buf->geterror())));
        return *(m_files[path] = std::move(buf));
    }

private:
    std::map<std::string, std::unique_ptr<ImageBuf>> m_files;
};


struct RoleImage {
    ImageBuf image;                 ///< the selected channels, float
    std::vector<int> indices;       ///< their indices in the file
    std::string path;
};

/// Extract the channels of `arg` for `role`, checking they exist and that
/// the file matches the noisy input's data window.
RoleImage
load_role(InputFiles& files, const InputArg& arg, Role role,
          const ImageBuf* reference, const std::string& reference_path)
{
    RoleImage r;
    r.path        = arg.path;
    ImageBuf& src = files.get(arg.path);
    const ImageSpec& spec = src.spec();
    std::string err;
    if (!select_channels(spec.channelnames, arg.channels, role, r.indices,
                         err))
        fail(format("{} '{}': {}", role_name(role), arg.path, err));
    const ROI a = src.roi();
    const ROI b = reference ? reference->roi() : a;
    if (a.xbegin != b.xbegin || a.xend != b.xend || a.ybegin != b.ybegin
        || a.yend != b.yend) {
        fail(format("{} '{}' is {}x{}{:+d}{:+d}, but the noisy input '{}' is "
                    "{}x{}{:+d}{:+d}: they must cover the same pixels",
                    role_name(role), arg.path, a.width(), a.height(),
                    a.xbegin, a.ybegin, reference_path, b.width(), b.height(),
                    b.xbegin, b.ybegin));
    }
    std::vector<std::string> names;
    if (role == Role::Radiance)
        names = { "R", "G", "B", "A" };
    names.resize(r.indices.size());
    if (!ImageBufAlgo::channels(r.image, src, int(r.indices.size()),
                                r.indices, {}, names))
        fail(format("{} '{}': {}", role_name(role), arg.path,
                    one_line(r.image.geterror())));
    return r;
}

std::string
channel_list(const ImageSpec& spec, const std::vector<int>& idx)
{
    std::string s;
    for (int i : idx)
        s += (s.empty() ? "" : ",") + spec.channelnames[size_t(i)];
    return s;
}


/// Fill in the defaults for a Blender Cycles multilayer input.
void
apply_cycles_defaults(Args& a, InputFiles& files, bool verbose)
{
    const ImageSpec& spec = files.get(a.in.path).spec();
    std::string prefix;
    if (!cycles_prefix(spec.channelnames, prefix))
        return;
    if (verbose)
        printf("zdenoise: '%s' is a Blender Cycles multilayer EXR (layer "
               "'%s')\n",
               a.in.path.c_str(), prefix.c_str());
    auto has = [&](const std::string& layer, const char* comp) {
        for (const std::string& n : spec.channelnames)
            if (n == prefix + layer + "." + comp)
                return true;
        return false;
    };
    if (a.in.channels.empty())
        a.in.channels = prefix + "Combined";
    auto pick = [&](InputArg& arg, bool disabled, const char* layer,
                    const char* comp) {
        if (!arg.given && !disabled && has(layer, comp))
            arg = { a.in.path, prefix + layer, true };
    };
    pick(a.albedo, false, "Denoising Albedo", "R");
    pick(a.normal, a.no_normal, "Denoising Normal", "X");
    pick(a.depth, a.no_depth, "Denoising Depth", "Z");
    pick(a.id, a.no_id, "IndexOB", "X");
}


bool
same_file(const std::string& a, const std::string& b)
{
    char ra[PATH_MAX], rb[PATH_MAX];
    if (!realpath(a.c_str(), ra) || !realpath(b.c_str(), rb))
        return false;
    return std::strcmp(ra, rb) == 0;
}


int
run(int argc, char* argv[])
{
    Args a = parse_args(argc, argv);
    if (a.threads > 0)
        OIIO::attribute("threads", a.threads);
    Timer total;

    // Never overwrite an input unless asked.
    if (!a.force)
        for (const InputArg* in : { &a.in, &a.albedo, &a.normal, &a.depth,
                                    &a.id, &a.variance, &a.half_a, &a.half_b })
            if (in->given && same_file(in->path, a.output))
                fail(format("the output '{}' is also an input; use --force "
                            "to replace it",
                            a.output));

    InputFiles files;
    Timer read_timer;
    files.get(a.in.path);
    apply_cycles_defaults(a, files, a.verbose);
    if (!a.albedo.given)
        fail(format("no albedo: '{}' has no Denoising Albedo pass; give "
                    "--albedo FILE",
                    a.in.path),
             kExitUsage);

    RoleImage radiance = load_role(files, a.in, Role::Radiance, nullptr, "");
    const ImageBuf& ref = files.get(a.in.path);
    RoleImage albedo    = load_role(files, a.albedo, Role::Albedo, &ref,
                                    a.in.path);
    struct Optional {
        InputArg* arg;
        Role role;
        bool disabled;
        RoleImage image;
    } optional[] = { { &a.normal, Role::Normal, a.no_normal, {} },
                     { &a.depth, Role::Depth, a.no_depth, {} },
                     { &a.id, Role::ObjectId, a.no_id, {} },
                     { &a.variance, Role::Variance, false, {} },
                     { &a.half_a, Role::Radiance, false, {} },
                     { &a.half_b, Role::Radiance, false, {} } };
    for (Optional& o : optional)
        if (o.arg->given && !o.disabled)
            o.image = load_role(files, *o.arg, o.role, &ref, a.in.path);
    const double read_time = read_timer();

    Guides guides;
    auto guide = [](const Optional& o) {
        return o.image.image.initialized() ? &o.image.image : nullptr;
    };
    guides.normal    = guide(optional[0]);
    guides.depth     = guide(optional[1]);
    guides.object_id = guide(optional[2]);
    guides.variance  = guide(optional[3]);
    guides.half_a    = guide(optional[4]);
    guides.half_b    = guide(optional[5]);

    if (a.verbose) {
        const ImageSpec& s = ref.spec();
        printf("zdenoise: %dx%d, %d channels in '%s'\n", s.width, s.height,
               s.nchannels, a.in.path.c_str());
        auto show = [&](const char* what, const RoleImage& r) {
            if (r.image.initialized())
                printf("  %-9s '%s' channels %s\n", what, r.path.c_str(),
                       channel_list(files.get(r.path).spec(), r.indices)
                           .c_str());
        };
        show("radiance", radiance);
        show("albedo", albedo);
        const char* labels[] = { "normal", "depth", "id", "variance",
                                 "half A", "half B" };
        for (int k = 0; k < 6; ++k)
            show(labels[k], optional[k].image);
        if (!guides.variance && !guides.half_a)
            printf("  noise     estimated from the image\n");
        printf("zdenoise: parameters %s\n", describe(a.filter).c_str());
    }

    // Denoise.
    int last_tenth = -1;
    if (a.verbose) {
        const bool tty    = isatty(fileno(stderr));
        a.filter.progress = [&](float f) {
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
    Timer filter_timer;
    FilterStats stats;
    ImageBuf result;
    if (!denoise(result, radiance.image, albedo.image, guides, a.filter,
                 &stats, {}, a.threads))
        fail(format("denoising '{}' failed: {}", a.in.path,
                    one_line(result.geterror())));
    const double filter_time = filter_timer();

    // The output: the input file with its radiance RGB replaced.
    Timer write_timer;
    ImageBuf& out = files.get(a.in.path);
    const ROI roi = out.roi();
    std::vector<float> plane(roi.npixels());
    for (int c = 0; c < 3; ++c) {
        result.get_pixels(ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1,
                              c, c + 1),
                          TypeFloat, plane.data());
        const int dc = radiance.indices[size_t(c)];
        out.set_pixels(ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1,
                           dc, dc + 1),
                       TypeFloat, plane.data());
    }
    const ImageSpec& native = out.nativespec();
    if (!native.channelformats.empty())
        out.set_write_format(native.channelformats);
    else
        out.set_write_format(native.format);
    out.specmod().attribute("zdenoise:version", ZDENOISE_VERSION_STRING);
    out.specmod().attribute("zdenoise:parameters", describe(a.filter));
    std::string err;
    if (!write_atomically(out, a.output, err))
        fail(err);
    const double write_time = write_timer();

    if (a.verbose) {
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
               read_time, filter_time, write_time, total(), a.output.c_str());
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
