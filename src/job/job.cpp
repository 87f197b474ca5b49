// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The job's orchestration: plan() reads the headers and decides everything
// before any pixel is read (the channels of each role, the colour spaces,
// the layers, the output's layout, the strips), then run_strip()
// (strip_run.cpp) reads, denoises and writes one strip at a time. Each
// step's work is in a file of its own: role_defaults (what the files'
// conventions give each role),
// colour_plan (the colour spaces),
// input_files (headers, channel selection), layers_plan, memory_plan
// (strips), strips (a strip's images), output (layout, rows, sinks).

#include "job.h"

#include <zdenoise/simd.h>
#include <zdenoise/temporal.h>

#include <algorithm>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include "alpha_plan.h"
#include "atomic_write.h"
#include "colour_plan.h"
#include "diagnostics_picture.h"
#include "failure.h"
#include "input_files.h"
#include "layer_conventions.h"
#include "layers_plan.h"
#include "light_groups_plan.h"
#include "memory_plan.h"
#include "neighbour_frames.h"
#include "options.h"
#include "validate.h"
#include "role_defaults.h"
#include "output.h"
#include "output_sinks.h"
#include "strip_plan.h"
#include "strip_run.h"
#include "strips.h"
#include "temporal_strip.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// What -v says of the layers (or of their absence) and of the noise.
void
log_mode(const Job& j, const Convention& conv, const Plan& p,
         const std::vector<LayerArg>& layer_args, size_t mode_line,
         std::vector<std::string>& log)
{
    const bool noise_given = p.roles.variance.used || p.roles.half_a.used;
    if (p.layered) {
        log.insert(log.begin() + long(mode_line),
                   p.path ? format("mode path: the direct light apart from "
                                   "the rest, {} layer(s){}",
                                   p.layers.layers.size(),
                                   j.mode == Mode::Auto
                                       ? " (the default where the render "
                                         "has its direct light apart; "
                                         "--mode beauty filters the "
                                         "beauty as one)"
                                       : "")
                          : format("mode layers: {} layer(s){}",
                                   p.layers.layers.size(),
                                   j.layers.empty() ? "" : " (--layer)"));
        log.push_back(noise_given
                          ? "  noise     estimated per layer (--variance and "
                            "--halves describe the beauty, not a layer)"
                          : "  noise     estimated per layer");
        return;
    }
    std::string found;
    for (const LayerArg& a : layer_args)
        found += (found.empty() ? "" : ", ") + a.name;
    log.push_back(found.empty() ? "mode beauty"
                                : "mode beauty (layers found: " + found
                                      + "; --mode layers uses them)");
    if (j.mode == Mode::Auto && !conv.direct_layers.empty())
        log.push_back("  not by path: " + p.path_blocker
                      + " describes the beauty (--mode path filters the "
                        "direct light apart all the same)");
    if (!noise_given)
        log.push_back("  noise     estimated from the image");
}


/// --temporal's conditions, and what -v says of its frames.
void
check_temporal(const Job& j, const Plan& p, JobResult& result)
{
    if (p.layered)
        fail("--temporal works in --mode beauty (the layers' light is "
             "not combined across frames yet; docs/TEMPORAL.md)");
    if (!j.static_camera && !p.roles.motion.used)
        fail(format("--temporal {}: '{}' has no motion vectors (a Cycles "
                    "Vector pass, Arnold's motionvector); give --motion "
                    "FILE[:ch=X,Y] or, when nothing moves, "
                    "--static-camera",
                    j.temporal, j.in.path));
    std::string offsets;
    for (int o : j.neighbour_offsets)
        offsets += format("{}{:+d}", offsets.empty() ? "" : ",", o);
    result.log.push_back(format(
        "temporal  frames {} around this one, {}", 
        offsets.empty() ? std::string("none") : offsets,
        j.static_camera ? "a static camera (no motion vectors)"
                        : "reprojected through the motion vectors"));
}


/// Stage 1 of plan(): job `j` checked, its convention's and files'
/// defaults applied, the layers chosen and the roles' channels selected.
/// Returns the --in file's convention.
Convention
plan_roles(Job& j, InputFiles& files, Plan& p, AuxConvention& aux,
           std::vector<LayerArg>& layer_args, JobResult& result)
{
    for (const std::string& invalid : { validate(j, Spelling::CommandLine),
                                        filter_options_problem(j.filter) })
        if (!invalid.empty())
            fail(invalid);
    const InputHeader& in = files.header(j.in.path);
    const Convention conv = detect_convention(in.channelnames);
    p.path_blocker = auto_path_blocker(j);
    std::string remodulation;
    if (j.aux.given)
        apply_aux(j, files, aux, remodulation, result.log);
    apply_defaults(j, conv, result.log);
    apply_file_defaults(j, files);
    layer_args = choose_layers(j, conv, p.path_blocker, p.path, p.layered);
    if (!p.layered && !j.albedo.given)
        fail(format("no albedo: '{}' has no Denoising Albedo pass; give "
                    "--albedo FILE or --aux FILE",
                    j.in.path));
    p.noisy = in.window();
    const uint64_t pixels = uint64_t(p.noisy.width()) * uint64_t(p.noisy.height());
    if (j.max_pixels && pixels > j.max_pixels)
        fail(format("'{}' is {}x{}, {} pixels: more than the {} a recipe may "
                    "denoise (ZDENOISE_RECIPE_LIMITS=pixels=N allows more)",
                    j.in.path, p.noisy.width(), p.noisy.height(), pixels,
                    j.max_pixels));
    p.roles = select_roles(files, j, p.layered);
    if (j.temporal > 0)
        check_temporal(j, p, result);
    if (!p.layered && !remodulation.empty()) {
        p.roles.remodulation.selection
            = select_role(files, { j.aux.path, remodulation, true },
                          Role::Albedo, &p.noisy, j.in.path);
        p.roles.remodulation.used = true;
    }
    return conv;
}


/// Stage 2 of plan(): the colour spaces of the roles.
void
plan_colour(const Job& j, InputFiles& files, Plan& p, JobResult& result)
{
    // Radiance and albedo RGB into the working space (ocio/colour.h).
    p.managed = resolve_colour(j, files, p.config, p.spaces, result.log);
    // Layers are filtered in the input's own space: a divided layer is a
    // quotient per channel, which a change of primaries does not carry.
    if (p.managed && p.layered
        && (p.spaces.working != p.spaces.input
            || p.spaces.output != p.spaces.input))
        fail(format("--mode layers filters in the input's colour space "
                    "('{}'): give --working-colorspace and --ocolorspace "
                    "as the input's, or use --mode beauty",
                    p.spaces.input));
    if (p.managed && p.roles.variance.used
        && p.spaces.input != p.spaces.working)
        result.log.push_back("  variance  used as given (not converted "
                             "to the working space)");
    p.radiance_as_is = !p.managed || p.spaces.input == p.spaces.working;
    p.albedo_as_is   = !p.managed || p.spaces.albedo == p.spaces.working;
}


/// What -v says of the files and of each role's channels.
void
log_roles(const Job& j, InputFiles& files, const Plan& p, JobResult& result)
{
    const InputHeader& in = files.header(j.in.path);
    result.log.push_back(format("{}x{}, {} channels in '{}'",
                                p.noisy.width(), p.noisy.height(),
                                in.channelnames.size(), j.in.path));
    auto show = [&](const char* what, const Selection& s) {
        result.log.push_back(format(
            "  {:<9} '{}' channels {}", what, s.path,
            channel_list(files.header(s.path).channelnames, s.indices)));
    };
    show("radiance", p.roles.radiance);
    const int alpha = denoised_alpha_channel(j, p.roles.radiance);
    if (alpha >= 0)
        result.log.push_back(format(
            "  alpha     '{}' channel {} denoised where fractional "
            "(--no-alpha copies it)",
            j.in.path, in.channelnames[size_t(alpha)]));
    if (!p.layered)
        show("albedo", p.roles.albedo);
    for (const OptionalRole* o : p.roles.optional())
        if (o->used)
            show(o->label, o->selection);
}


/// Stage 3 of plan(): the light to filter: the albedo (beauty mode) or
/// the layers and their colours.
void
plan_light(const Job& j, InputFiles& files, const Convention& conv,
           const AuxConvention& aux, const std::vector<LayerArg>& layer_args,
           Plan& p, JobResult& result)
{
    if (!p.layered)
        p.albedo = plan_albedo(j, files, conv, p.roles, p.noisy, result.log);

    const size_t mode_line = result.log.size();
    if (p.layered) {
        // An explicit residual (--residual) or explicit layers (--layer)
        // are the user's decomposition: the residual is then not filtered.
        const bool own = !j.residual.empty() || !j.layers.empty();
        const std::string residual = j.residual.empty() ? conv.residual
                                                        : j.residual;
        // By path the residual is the beauty minus the direct light, over
        // the beauty's albedo (Cycles' residual albedo is that too).
        p.layers = plan_layers(
            files, j, layer_args, p.path && !own ? std::string() : residual,
            own        ? std::string()
            : p.path   ? conv.albedo
                       : conv.residual_albedo,
            conv.residual_layer,
            // Path mode keeps the environment in the residual, as beauty
            // mode does: at a silhouette against the sky the residual's
            // albedo holds the sky's, and without the sky's light the
            // quotient there is neither's (glass_emitter 64 spp: its Env
            // pixels' error 10x beauty mode's when added as it is).
            own || p.path ? std::string() : conv.residual_unfiltered, p.noisy,
            result.log);
        if (j.aux.given)
            use_aux_colours(p.layers, files, j, layer_args, aux, p.noisy,
                            result.log);
        p.albedo = plan_layer_colours(j, files, p.layers, result.log);
    }
    log_mode(j, conv, p, layer_args, mode_line, result.log);
    p.groups = plan_light_groups(j, files.header(j.in.path), p.roles.radiance,
                                 result.log);
    p.aovs = plan_aovs(j, files.header(j.in.path), p.roles.radiance, p.groups,
                       result.log);
}


/// Stage 4 of plan(): the output's layout, colour space and metadata.
ImageSpec
plan_output(const Job& j, InputFiles& files, Plan& p, JobResult& result)
{
    const InputHeader& in = files.header(j.in.path);
    ImageSpec spec;
    layout_output(j, in, p.roles.radiance, p.layers, p.groups, p.aovs, spec,
                  p.output.channels,
                  result.channel_formats);
    if (p.managed)
        colour::tag_colour_space(spec, p.spaces.output, p.spaces.input);
    spec.attribute("zdenoise.version", ZDENOISE_VERSION_STRING);
    std::string parameters = describe(j.filter)
                             + (p.path      ? " mode=path"
                                : p.layered ? " mode=layers"
                                            : " mode=beauty");
    parameters += p.albedo.describe();
    spec.attribute("zdenoise.parameters", parameters);
    return spec;
}


/// Stage 5 of plan(): the strips, from the memory each needs
/// (memory_plan.cpp) with the output's rows as `sink` takes them.
void
plan_strips(const Job& j, InputFiles& files, const OutputSink& sink,
            const ImageSpec& spec, Plan& p, JobResult& result)
{
    const InputHeader& in = files.header(j.in.path);
    p.maps = j.diagnostics || !j.diagnostics_png.empty();
    p.output.set_row_types(sink.float_rows());
    const StripCost cost = strip_cost(j, p, files, sink, spec);
    plan_strips(j, in, cost, result);
    p.around = cost.around;
    result.log.push_back(
        result.strips == 1
            ? format("whole frame at once (about {})",
                     readable_size(result.estimated_bytes))
            : format("{} strips of {} rows, each read with {} rows of halo "
                     "around it (about {} each)",
                     result.strips, result.strip_rows, cost.around,
                     readable_size(result.estimated_bytes)));
    result.log.push_back("parameters " + describe(j.filter));
    result.log.push_back("vector kernels " + simd_target() + " (this CPU runs "
                         + Strutil::join(simd_targets(), ", ") + ")");
}


/// Stages 1-5 of plan(), which read the headers of job `j` (its
/// convention's defaults applied) and no pixel: roles, colour, layers,
/// output, strips. Returns the output's spec as the sink is begun with
/// (`result.channel_formats` its pixel types).
ImageSpec
plan_from_headers(Job& j, InputFiles& files, const OutputSink& sink, Plan& p,
                  JobResult& result)
{
    AuxConvention aux;
    std::vector<LayerArg> layer_args;
    const Convention conv = plan_roles(j, files, p, aux, layer_args, result);
    plan_colour(j, files, p, result);
    log_roles(j, files, p, result);
    plan_light(j, files, conv, aux, layer_args, p, result);
    const ImageSpec spec = plan_output(j, files, p, result);
    plan_strips(j, files, sink, spec, p, result);
    return spec;
}


/// Decide everything from the headers (plan_from_headers()), then make
/// ready for the pixels: the files' rows reserved, the sink begun.
void
plan(Job& j, InputFiles& files, OutputSink& sink, Plan& p, JobResult& result)
{
    const ImageSpec spec = plan_from_headers(j, files, sink, p, result);
    if (!j.diagnostics_png.empty())
        p.picture = ErrorPicture(p.noisy);
    p.output.sink = &sink;
    const int held = std::min(result.strip_rows + 2 * p.around,
                              p.noisy.height());
    for (const std::string& path : files.paths())
        files.rows(path).reserve(held);
    std::string err;
    if (!sink.begin(spec, result.channel_formats, err))
        throw SinkFailure { err };
}


void
run(Job j, OutputSink& sink, JobResult& result)
{
    InputFiles files;
    Plan p;
    Timer read_timer;
    plan(j, files, sink, p, result);
    result.read_seconds += read_timer();

    std::vector<FilterStats> layer_stats;
    for (int s = 0; s < result.strips; ++s)
        run_strip(j, p, files, s, result, layer_stats);
    if (p.albedo.pool)
        result.log.push_back(pooled_summary(p.pooled));
    if (j.write_layers)
        for (size_t i = 0; i < layer_stats.size(); ++i) {
            const std::string& n = p.layers.layers[i].name;
            result.log.push_back(format(
                "  layer {} written as {}.R,G,B (mean radius {:.2f})", n, n,
                layer_stats[i].mean_radius));
        }
    Timer end_timer;
    std::string err;
    if (!j.diagnostics_png.empty()
        && !write_atomically(p.picture.picture(), j.diagnostics_png, err))
        fail(format("--diagnostics-png '{}': {}", j.diagnostics_png,
                    one_line(err)));
    if (!sink.end(err))
        throw SinkFailure { err };
    result.write_seconds += end_timer();
}

/// Run `step`, its failures caught as the one-line `error` the job's
/// functions give (job.h). Returns whether it succeeded.
template<class Step>
bool
reporting_failures(Step&& step, std::string& error)
{
    try {
        step();
        return true;
    } catch (const Failure& f) {
        error = f.message;
    } catch (const SinkFailure& f) {
        error = one_line(f.message);
    } catch (const std::exception& e) {
        error = one_line(e.what());
    }
    return false;
}

}  // namespace


bool
run_job(const Job& job, OutputSink& sink, JobResult& result,
        std::string& error)
{
    return reporting_failures([&] { run(job, sink, result); }, error);
}


bool
output_spec(const Job& job, const OutputSink& sink, ImageSpec& spec,
            std::string& error)
{
    return reporting_failures(
        [&] {
            Job j = job;
            InputFiles files;
            Plan p;
            JobResult result;
            const ImageSpec planned = plan_from_headers(j, files, sink, p,
                                                        result);
            spec = native_spec(planned, result.channel_formats);
        },
        error);
}

bool
run_job(const Job& job, JobResult& result, std::string& error)
{
    ImageSink sink(result.image);
    return run_job(job, sink, result, error);
}


bool
run_job_to_file(const Job& job, const std::string& path, JobResult& result,
                std::string& error)
{
    // A failure of the job itself is reported as it is; only a failure to
    // write is "cannot write PATH".
    std::string job_error;
    bool job_failed = false;
    const bool ok   = write_atomically(
        path,
        [&](const std::string& tmp, std::string& why) {
            FileSink sink(tmp);
            if (run_job(job, sink, result, why))
                return true;
            if (!sink.write_failed()) {
                job_failed = true;
                job_error  = why;
            }
            return false;
        },
        error);
    if (!ok && job_failed)
        error = job_error;
    return ok;
}

}  // namespace job
}  // namespace zdenoise
