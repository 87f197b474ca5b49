// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "job.h"

#include <cstdlib>
#include <map>
#include <memory>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include "channel_spec.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// Thrown inside this file only and turned into run_job's error.
struct Failure {
    std::string message;
};

[[noreturn]] void
fail(const std::string& message)
{
    throw Failure { message };
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
    ImageBuf image;            ///< the selected channels, float
    std::vector<int> indices;  ///< their indices in the file
};

/// Extract the channels of `arg` for `role`, checking they exist and that
/// the file covers the noisy input's pixels.
RoleImage
load_role(InputFiles& files, const InputArg& arg, Role role,
          const ImageBuf* reference, const std::string& reference_path)
{
    RoleImage r;
    ImageBuf& src = files.get(arg.path);
    std::string err;
    if (!select_channels(src.spec().channelnames, arg.channels, role,
                              r.indices, err))
        fail(format("{} '{}': {}", role_name(role), arg.path, err));
    const ROI a = src.roi();
    const ROI b = reference ? reference->roi() : a;
    if (a.xbegin != b.xbegin || a.xend != b.xend || a.ybegin != b.ybegin
        || a.yend != b.yend)
        fail(format("{} '{}' is {}x{}{:+d}{:+d}, but the noisy input '{}' is "
                    "{}x{}{:+d}{:+d}: they must cover the same pixels",
                    role_name(role), arg.path, a.width(), a.height(),
                    a.xbegin, a.ybegin, reference_path, b.width(), b.height(),
                    b.xbegin, b.ybegin));
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


/// Fill in the defaults for a Blender Cycles multilayer input.
void
apply_cycles_defaults(Job& j, const ImageSpec& spec,
                      std::vector<std::string>& log)
{
    std::string prefix;
    if (!cycles_prefix(spec.channelnames, prefix))
        return;
    log.push_back(format("'{}' is a Blender Cycles multilayer EXR (layer "
                         "'{}')",
                         j.in.path, prefix));
    auto has = [&](const std::string& layer, const char* comp) {
        for (const std::string& n : spec.channelnames)
            if (n == prefix + layer + "." + comp)
                return true;
        return false;
    };
    if (j.in.channels.empty())
        j.in.channels = prefix + "Combined";
    auto pick = [&](InputArg& arg, bool disabled, const char* layer,
                    const char* comp) {
        if (!arg.given && !disabled && has(layer, comp))
            arg = { j.in.path, prefix + layer, true };
    };
    pick(j.albedo, false, "Denoising Albedo", "R");
    pick(j.normal, j.no_normal, "Denoising Normal", "X");
    pick(j.depth, j.no_depth, "Denoising Depth", "Z");
    pick(j.id, j.no_id, "IndexOB", "X");
}


/// The job's colour spaces, or none when no config is found and the user
/// asked for nothing (the OIIO plugin outside an installation): then the
/// pixels are filtered as they are.
bool
resolve_colour(const Job& j, InputFiles& files, colour::ColourConfig& config,
               colour::JobSpaces& spaces, std::vector<std::string>& log)
{
    std::string err;
    if (!j.colour.any_given() && !std::getenv("OCIO")
        && colour::bundled_config_path().empty()) {
        log.push_back("no colour config found: pixels filtered as they are");
        return false;
    }
    if (!config.load(j.colour.config, err)
        || !colour::resolve_job_spaces(config, j.colour, files.get(j.in.path),
                                       files.get(j.albedo.path),
                                       j.albedo.path == j.in.path, spaces,
                                       log, err))
        fail(err);
    return true;
}


std::string
channel_list(const ImageSpec& spec, const std::vector<int>& idx)
{
    std::string s;
    for (int i : idx)
        s += (s.empty() ? "" : ",") + spec.channelnames[size_t(i)];
    return s;
}


void
run(Job j, JobResult& result)
{
    InputFiles files;
    Timer read_timer;
    ImageBuf& noisy = files.get(j.in.path);
    apply_cycles_defaults(j, noisy.spec(), result.log);
    if (!j.albedo.given)
        fail(format("no albedo: '{}' has no Denoising Albedo pass; give "
                    "--albedo FILE",
                    j.in.path));

    RoleImage radiance = load_role(files, j.in, Role::Radiance, nullptr,
                                   "");
    RoleImage albedo   = load_role(files, j.albedo, Role::Albedo, &noisy,
                                   j.in.path);
    struct Optional {
        const InputArg* arg;
        Role role;
        bool disabled;
        const char* label;
        RoleImage image;
    } optional[] = {
        { &j.normal, Role::Normal, j.no_normal, "normal", {} },
        { &j.depth, Role::Depth, j.no_depth, "depth", {} },
        { &j.id, Role::ObjectId, j.no_id, "id", {} },
        { &j.variance, Role::Variance, false, "variance", {} },
        { &j.half_a, Role::Radiance, false, "half A", {} },
        { &j.half_b, Role::Radiance, false, "half B", {} },
    };
    for (Optional& o : optional)
        if (o.arg->given && !o.disabled)
            o.image = load_role(files, *o.arg, o.role, &noisy, j.in.path);

    // Radiance and albedo RGB into the working space (ocio/colour.h).
    colour::ColourConfig config;
    colour::JobSpaces spaces;
    const bool managed = resolve_colour(j, files, config, spaces, result.log);
    auto convert = [&](ImageBuf& image, const std::string& from,
                       const std::string& to, const InputArg& arg) {
        std::string err;
        if (image.initialized() && !config.convert_rgb(image, from, to, err))
            fail(format("'{}': {}", arg.path, one_line(err)));
    };
    if (managed) {
        convert(radiance.image, spaces.input, spaces.working, j.in);
        convert(albedo.image, spaces.albedo, spaces.working, j.albedo);
        convert(optional[4].image.image, spaces.input, spaces.working,
                j.half_a);
        convert(optional[5].image.image, spaces.input, spaces.working,
                j.half_b);
        if (optional[3].image.image.initialized()
            && spaces.input != spaces.working)
            result.log.push_back("  variance  used as given (not converted "
                                 "to the working space)");
    }
    result.read_seconds = read_timer();

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

    const ImageSpec& s = noisy.spec();
    result.log.push_back(format("{}x{}, {} channels in '{}'", s.width,
                                s.height, s.nchannels, j.in.path));
    auto show = [&](const char* what, const InputArg& arg,
                    const RoleImage& r) {
        if (r.image.initialized())
            result.log.push_back(
                format("  {:<9} '{}' channels {}", what, arg.path,
                       channel_list(files.get(arg.path).spec(), r.indices)));
    };
    show("radiance", j.in, radiance);
    show("albedo", j.albedo, albedo);
    for (const Optional& o : optional)
        show(o.label, *o.arg, o.image);
    if (!guides.variance && !guides.half_a)
        result.log.push_back("  noise     estimated from the image");
    result.log.push_back("parameters " + describe(j.filter));

    Timer denoise_timer;
    ImageBuf denoised;
    if (!denoise(denoised, radiance.image, albedo.image, guides, j.filter,
                 &result.stats, {}, j.threads))
        fail(format("denoising '{}' failed: {}", j.in.path,
                    one_line(denoised.geterror())));
    result.denoise_seconds = denoise_timer();
    if (managed)
        convert(denoised, spaces.working, spaces.output, j.in);

    // The output: the input file with its radiance RGB replaced, each
    // channel written in its input pixel type.
    ImageBuf& out = noisy;
    const ROI roi = out.roi();
    std::vector<float> plane(roi.npixels());
    for (int c = 0; c < 3; ++c) {
        denoised.get_pixels(ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0,
                                1, c, c + 1),
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
    if (managed)
        colour::tag_colour_space(out.specmod(), spaces.output, spaces.input);
    out.specmod().attribute("zdenoise.version", ZDENOISE_VERSION_STRING);
    out.specmod().attribute("zdenoise.parameters", describe(j.filter));
    result.image = std::move(out);
}

}  // namespace


std::string
one_line(std::string s)
{
    s = Strutil::strip(s);
    for (char& c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    return s;
}


std::vector<std::string>
input_paths(const Job& j)
{
    std::vector<std::string> paths;
    for (const InputArg* a : { &j.in, &j.albedo, &j.normal, &j.depth, &j.id,
                               &j.variance, &j.half_a, &j.half_b })
        if (a->given)
            paths.push_back(a->path);
    return paths;
}


bool
run_job(const Job& job, JobResult& result, std::string& error)
{
    try {
        run(job, result);
        return true;
    } catch (const Failure& f) {
        error = f.message;
    } catch (const std::exception& e) {
        error = e.what();
    }
    return false;
}

}  // namespace job
}  // namespace zdenoise
