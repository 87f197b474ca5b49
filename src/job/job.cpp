// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "job.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <set>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imagebufalgo_util.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include "channel_spec.h"
#include "layer_conventions.h"

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


/// Do two data windows cover the same pixels?
bool
same_pixels(const ROI& a, const ROI& b)
{
    return a.xbegin == b.xbegin && a.xend == b.xend && a.ybegin == b.ybegin
           && a.yend == b.yend;
}

/// A data window as messages show it: 384x384+0+0.
std::string
window_text(const ROI& r)
{
    return format("{}x{}{:+d}{:+d}", r.width(), r.height(), r.xbegin,
                  r.ybegin);
}


/// The format named by a file's extension, "" when no reader claims it.
std::string
format_of_extension(const std::string& path)
{
    std::string ext = Strutil::lower(Filesystem::extension(path, false));
    for (const auto& format_exts : get_extension_map())
        for (const std::string& e : format_exts.second)
            if (e == ext)
                return format_exts.first;
    return "";
}


/// The names a multipart EXR's part k > 0 gives its channels C in the
/// file's channel list: PART.C unless already so named.
std::vector<std::string>
part_channel_names(const ImageSpec& part)
{
    const std::string name = part.get_string_attribute("name");
    std::vector<std::string> names;
    for (const std::string& c : part.channelnames)
        names.push_back(name.empty() || Strutil::starts_with(c, name + ".")
                            ? c
                            : name + "." + c);
    return names;
}


/// An input file's headers, checked: part 0's, and the channel names of
/// all its parts (as InputFile has them).
struct InputHeader {
    ImageSpec spec;
    std::vector<std::string> channelnames;
    int parts = 1;
};

/// One input file: the channels of all its parts (a multipart EXR's part
/// k > 0 contributes its channels as part_channel_names() names them), as
/// float, with each channel's pixel type in the file.
struct InputFile {
    ImageBuf image;
    std::vector<TypeDesc> formats;
};


/// Input files, each read once however many roles it serves. Headers are
/// read first (header()), so that a bad file or a frame too large for
/// memory is refused before any pixel is allocated; pixels on first use
/// (get()).
class InputFiles {
public:
    const InputHeader& header(const std::string& path)
    {
        auto it = m_headers.find(path);
        if (it != m_headers.end())
            return it->second;
        if (!Filesystem::exists(path))
            fail(format("cannot read '{}': no such file", path));
        if (Filesystem::file_size(path) == 0)
            fail(format("cannot read '{}': the file is empty", path));
        const ImageBuf first = checked_part(path, 0);
        // OIIO falls back to reading by content; a file whose contents
        // contradict its name was most likely written wrongly upstream.
        const std::string named = format_of_extension(path);
        const std::string found = std::string(first.file_format_name());
        if (!named.empty() && named != found)
            fail(format("cannot read '{}': it is a {} file, not {} as its "
                        "name says",
                        path, found, named));
        InputHeader h;
        h.spec         = first.spec();
        h.channelnames = h.spec.channelnames;
        h.parts        = first.nsubimages();
        for (int part = 1; part < h.parts; ++part) {
            const ImageBuf buf = checked_part(path, part);
            if (!same_pixels(first.roi(), buf.roi()))
                fail(format("'{}': part {} ('{}') is {}, part 0 is {}: "
                            "zdenoise needs every part to cover the same "
                            "pixels",
                            path, part, buf.spec().get_string_attribute("name"),
                            window_text(buf.roi()), window_text(first.roi())));
            for (const std::string& c : part_channel_names(buf.spec()))
                h.channelnames.push_back(c);
        }
        return m_headers[path] = std::move(h);
    }

    InputFile& get(const std::string& path)
    {
        auto it = m_files.find(path);
        if (it != m_files.end())
            return *it->second;
        const int parts = header(path).parts;
        auto file = std::make_unique<InputFile>();
        file->image = read_part(path, 0, file->formats);
        for (int part = 1; part < parts; ++part)
            append_part(*file, path, part);
        return *(m_files[path] = std::move(file));
    }

    ImageBuf& image(const std::string& path) { return get(path).image; }

private:
    /// Part `part`'s header; a deep part or one without pixels is refused.
    static ImageBuf checked_part(const std::string& path, int part)
    {
        ImageBuf buf(path, part);
        if (!buf.init_spec(path, part, 0))
            fail(format("cannot read '{}': {}", path,
                        one_line(buf.geterror())));
        if (buf.deep())
            fail(format("cannot read '{}': deep images are not supported",
                        path));
        const ImageSpec& s = buf.spec();
        if (s.width < 1 || s.height < 1 || s.depth != 1)
            fail(format("cannot read '{}': its data window is {}x{}x{}; "
                        "zdenoise needs a 2D image of at least one pixel",
                        path, s.width, s.height, s.depth));
        return buf;
    }

    static ImageBuf read_part(const std::string& path, int part,
                              std::vector<TypeDesc>& formats)
    {
        ImageBuf buf(path, part);
        if (!buf.read(part, 0, true, TypeFloat))
            fail(format("cannot read '{}': {}", path,
                        one_line(buf.geterror())));
        const ImageSpec& native = buf.nativespec();
        formats.resize(size_t(native.nchannels), native.format);
        for (size_t c = 0; c < native.channelformats.size(); ++c)
            formats[c] = native.channelformats[c];
        return buf;
    }

    static void append_part(InputFile& file, const std::string& path,
                            int part)
    {
        std::vector<TypeDesc> formats;
        ImageBuf buf = read_part(path, part, formats);
        const ImageSpec& spec = buf.spec();
        std::vector<std::string> names = file.image.spec().channelnames;
        for (const std::string& c : part_channel_names(spec))
            names.push_back(c);
        ImageSpec merged_spec = file.image.spec();
        for (const ParamValue& p : spec.extra_attribs)
            if (!merged_spec.find_attribute(p.name()))
                merged_spec.extra_attribs.push_back(p);
        ImageBuf merged;
        if (!ImageBufAlgo::channel_append(merged, file.image, buf))
            fail(format("cannot read '{}': {}", path,
                        one_line(merged.geterror())));
        merged_spec.nchannels    = merged.spec().nchannels;
        merged_spec.channelnames = names;
        merged_spec.alpha_channel = file.image.spec().alpha_channel;
        merged_spec.z_channel     = file.image.spec().z_channel;
        merged_spec.erase_attribute("name");
        merged_spec.erase_attribute("oiio:subimagename");
        merged_spec.erase_attribute("oiio:subimages");
        merged.specmod() = merged_spec;
        file.image = std::move(merged);
        file.formats.insert(file.formats.end(), formats.begin(),
                            formats.end());
    }

    std::map<std::string, InputHeader> m_headers;
    std::map<std::string, std::unique_ptr<InputFile>> m_files;
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
    ImageBuf& src = files.image(arg.path);
    std::string err;
    if (!select_channels(src.spec().channelnames, arg.channels, role,
                              r.indices, err))
        fail(format("{} '{}': {}", role_name(role), arg.path, err));
    // A file covering more pixels than the noisy input (a guide rendered
    // without the beauty's crop) is cut to them; one covering fewer cannot
    // be used.
    const ROI a = src.roi();
    const ROI b = reference ? reference->roi() : a;
    const ROI have(a.xbegin, a.xend, a.ybegin, a.yend);
    const ROI need(b.xbegin, b.xend, b.ybegin, b.yend);
    if (roi_intersection(have, need) != need)
        fail(format("{} '{}' is {}, but the noisy input '{}' is {}: it must "
                    "cover the same pixels",
                    role_name(role), arg.path, window_text(a), reference_path,
                    window_text(b)));
    std::vector<std::string> names;
    if (role == Role::Radiance || role == Role::LayerRadiance)
        names = { "R", "G", "B", "A" };
    names.resize(r.indices.size());
    if (!ImageBufAlgo::channels(r.image, src, int(r.indices.size()),
                                r.indices, {}, names))
        fail(format("{} '{}': {}", role_name(role), arg.path,
                    one_line(r.image.geterror())));
    if (have != need) {
        ImageBuf cropped;
        if (!ImageBufAlgo::crop(cropped, r.image, need))
            fail(format("{} '{}': {}", role_name(role), arg.path,
                        one_line(cropped.geterror())));
        r.image = std::move(cropped);
    }
    return r;
}


/// Fill in the defaults of the convention the input follows.
void
apply_defaults(Job& j, const Convention& conv, std::vector<std::string>& log)
{
    if (conv.name.empty())
        return;
    log.push_back(format("'{}' is a {}", j.in.path, conv.name));
    if (j.in.channels.empty())
        j.in.channels = conv.beauty;
    auto pick = [&](InputArg& arg, bool disabled, const std::string& sel) {
        if (!arg.given && !disabled && !sel.empty())
            arg = { j.in.path, sel, true };
    };
    pick(j.albedo, false, conv.albedo);
    pick(j.normal, j.no_normal, conv.normal);
    pick(j.depth, j.no_depth, conv.depth);
    pick(j.id, j.no_id, conv.id);
}


/// The job's colour spaces, or none when no config is found and the user
/// asked for nothing (the OIIO plugin outside an installation): then the
/// pixels are filtered as they are.
bool
resolve_colour(const Job& j, InputFiles& files, colour::ColourConfig& config,
               colour::JobSpaces& spaces, std::vector<std::string>& log)
{
    std::string err;
    // Layers may come without an albedo of the beauty: then the input's.
    const InputArg& albedo = j.albedo.given ? j.albedo : j.in;
    if (!j.colour.any_given() && !std::getenv("OCIO")
        && colour::bundled_config_path().empty()) {
        log.push_back("no colour config found: pixels filtered as they are");
        return false;
    }
    if (!config.load(j.colour.config, err)
        || !colour::resolve_job_spaces(config, j.colour, files.image(j.in.path),
                                       files.image(albedo.path),
                                       albedo.path == j.in.path, spaces,
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


/// The sum of the selections of `selections` ('+' between them) of the
/// --in file, each R,G,B.
ImageBuf
load_sum(InputFiles& files, const std::string& path,
         const std::string& selections, const ImageBuf& noisy,
         std::string& shown)
{
    ImageBuf sum;
    for (const std::string& part : Strutil::splits(selections, "+")) {
        RoleImage r = load_role(files, { path, part, true },
                                Role::LayerRadiance, &noisy, path);
        shown += (shown.empty() ? "" : " + ")
                 + channel_list(noisy.spec(), r.indices);
        if (!sum.initialized())
            sum = std::move(r.image);
        else if (!ImageBufAlgo::add(sum, sum, r.image))
            fail(format("'{}': {}", path, one_line(sum.geterror())));
    }
    return sum;
}


/// Where the residual layer is negligible against the beauty in a whole
/// neighbourhood, set its albedo to 0, so that the filter passes it through
/// there. Beauty minus layers leaves a residue of the passes' half-float
/// rounding wherever the residual is really empty; relative to its own
/// (zero) level that residue is pure noise, and the filter would grow every
/// window there to r_max for nothing (it made layered mode 5-10x slower than
/// beauty mode). Pixels within `reach` of a real residual stay: an emitter's
/// anti-aliased edge has pixels whose few coverage samples all missed it,
/// and the filter gives them their share of its light.
void
mask_negligible_residual(ImageBuf& albedo, const ImageBuf& residual,
                         const ImageBuf& beauty, int reach, int nthreads)
{
    // Half floats carry 11 bits: a residue of several rounded passes stays
    // below about 2^-9 of the beauty.
    constexpr float kNegligible = 1.0f / 512.0f;
    ImageSpec spec(albedo.roi(), TypeFloat);
    spec.nchannels = 1;
    spec.channelnames = { "Y" };
    ImageBuf real(spec), near_real;
    ImageBufAlgo::parallel_image(
        albedo.roi(), paropt(nthreads), [&](ROI roi) {
            roi.chbegin = 0;
            roi.chend   = 3;
            ImageBuf::ConstIterator<float> r(residual, roi), b(beauty, roi);
            ImageBuf::Iterator<float> m(real, roi);
            for (; !m.done(); ++m, ++r, ++b) {
                float res = 0.0f, total = 0.0f;
                for (int c = 0; c < 3; ++c) {
                    res   = std::max(res, std::fabs(r[c]));
                    total = std::max(total, std::fabs(b[c]));
                }
                m[0] = res > kNegligible * total ? 1.0f : 0.0f;
            }
        });
    ImageBufAlgo::dilate(near_real, real, 2 * reach + 1, 2 * reach + 1, {},
                         nthreads);
    ImageBufAlgo::parallel_image(
        albedo.roi(), paropt(nthreads), [&](ROI roi) {
            ImageBuf::ConstIterator<float> m(near_real, roi);
            for (ImageBuf::Iterator<float> a(albedo, roi); !a.done(); ++a, ++m)
                if (!(m[0] > 0.0f))
                    for (int c = roi.chbegin; c < roi.chend; ++c)
                        a[c] = 0.0f;
        });
}


/// The layers of a layered denoise, read.
struct LoadedLayers {
    std::vector<ImageBuf> radiance, albedo, denoised;
    std::vector<FilterStats> stats;
    ImageBuf residual;
};

/// Read the layers and the residual; the residual is, unless selected, the
/// beauty minus the sum of the unfiltered layers, so that nothing of the
/// beauty is lost (in Cycles: Emit + Env, and any lobe whose passes were
/// not written). With `residual_albedo`, the residual becomes one more
/// layer, denoised with that albedo (see Convention::residual_albedo).
std::vector<Layer>
load_layers(InputFiles& files, const Job& j,
            const std::vector<LayerArg>& args, const std::string& residual,
            const std::string& residual_albedo,
            const std::string& residual_layer,
            const std::string& residual_unfiltered, const ImageBuf& noisy,
            const ImageBuf& beauty, LoadedLayers& l,
            std::vector<std::string>& log)
{
    const size_t n = args.size() + (residual_albedo.empty() ? 0 : 1);
    l.radiance.resize(n);
    l.albedo.resize(n);
    l.denoised.resize(n);
    l.stats.resize(n);
    std::vector<Layer> layers(n);
    auto add_layer = [&](size_t i, const std::string& name, bool divided,
                         bool reflected) {
        layers[i].name      = name;
        layers[i].radiance  = &l.radiance[i];
        layers[i].albedo    = &l.albedo[i];
        layers[i].divided   = divided;
        layers[i].reflected = reflected;
        layers[i].denoised = &l.denoised[i];
        layers[i].stats    = &l.stats[i];
    };
    for (size_t i = 0; i < args.size(); ++i) {
        const LayerArg& a = args[i];
        std::string shown_radiance, shown_albedo;
        l.radiance[i] = load_sum(files, j.in.path, a.radiance, noisy,
                                 shown_radiance);
        l.albedo[i]   = load_sum(files, j.in.path, a.albedo, noisy,
                                 shown_albedo);
        add_layer(i, a.name, a.divided, a.reflected);
        log.push_back(format("  layer     {}: {} with albedo {}{}{}", a.name,
                             shown_radiance, shown_albedo,
                             a.divided ? " (divided by it)" : "",
                             a.reflected ? " (reflected: stricter edge test)"
                                         : ""));
    }
    std::string shown_residual;
    if (!residual.empty()) {
        l.residual = load_sum(files, j.in.path, residual, noisy,
                              shown_residual);
    } else {
        std::vector<Layer> unfiltered(layers.begin(),
                                      layers.begin() + args.size());
        for (Layer& layer : unfiltered) {
            layer.filter   = false;
            layer.denoised = nullptr;
            layer.stats    = nullptr;
        }
        ImageBuf sum;
        ROI rgb     = beauty.roi();
        rgb.chbegin = 0;
        rgb.chend   = 3;
        // RGB only: the beauty's alpha would mark the residual's pixels
        // "no surface" for the filter.
        l.residual.reset(ImageSpec(rgb, TypeFloat));
        if (!layered_denoise(sum, unfiltered, nullptr, {}, j.filter,
                             nullptr, rgb, j.threads)
            || !ImageBufAlgo::sub(l.residual, beauty, sum, rgb, j.threads))
            fail(format("layers of '{}': {}", j.in.path,
                        one_line(sum.has_error() ? sum.geterror()
                                                 : l.residual.geterror())));
        shown_residual = "the beauty minus the layers";
    }
    if (residual_albedo.empty()) {
        log.push_back("  residual  " + shown_residual + ", not filtered");
        return layers;
    }
    const size_t i = n - 1;
    std::string shown_albedo;
    l.radiance[i].swap(l.residual);  // l.residual: uninitialized again
    l.albedo[i] = load_sum(files, j.in.path, residual_albedo, noisy,
                           shown_albedo);
    add_layer(i, residual_layer, false, false);
    if (!residual_unfiltered.empty()) {
        std::string shown_unfiltered;
        l.residual = load_sum(files, j.in.path, residual_unfiltered, noisy,
                              shown_unfiltered);
        if (!ImageBufAlgo::sub(l.radiance[i], l.radiance[i], l.residual,
                               {}, j.threads))
            fail(format("layers of '{}': {}", j.in.path,
                        one_line(l.radiance[i].geterror())));
        shown_residual += " minus " + shown_unfiltered;
        log.push_back("  residual  " + shown_unfiltered + ", not filtered");
    }
    if (l.albedo[i].spec().format != TypeFloat)
        l.albedo[i] = l.albedo[i].copy(TypeFloat);
    mask_negligible_residual(l.albedo[i], l.radiance[i], beauty,
                             j.filter.r_max, j.threads);
    log.push_back(format("  layer     {}: {} with albedo {}", residual_layer,
                         shown_residual, shown_albedo));
    return layers;
}


/// Write `rgb` (3 channels) into the channels `names` of `out`, appending
/// those that do not exist (in pixel type `type`).
void
put_channels(ImageBuf& out, std::vector<TypeDesc>& formats,
             const ImageBuf& rgb, const std::vector<std::string>& names,
             TypeDesc type)
{
    const ROI roi = out.roi();
    std::vector<float> plane(roi.npixels());
    for (int c = 0; c < 3; ++c) {
        int dc = out.spec().channelindex(names[size_t(c)]);
        if (dc < 0) {
            ImageBuf one, appended;
            if (!ImageBufAlgo::channels(one, rgb, 1, { c }, {},
                                        { names[size_t(c)] })
                || !ImageBufAlgo::channel_append(appended, out, one))
                fail(format("cannot add channel '{}': {}", names[size_t(c)],
                            one_line(appended.geterror())));
            ImageSpec spec    = out.spec();  // keep the metadata
            spec.nchannels    = appended.nchannels();
            spec.channelnames.push_back(names[size_t(c)]);
            appended.specmod() = spec;
            out = std::move(appended);
            formats.push_back(type);
            continue;
        }
        rgb.get_pixels(ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1,
                           c, c + 1),
                       TypeFloat, plane.data());
        out.set_pixels(ROI(roi.xbegin, roi.xend, roi.ybegin, roi.yend, 0, 1,
                           dc, dc + 1),
                       TypeFloat, plane.data());
    }
}


/// Each output channel's pixel type: the input's, or `data_type`;
/// Cryptomatte channels always float (their ids are float bit patterns).
/// Set for writing, and returned.
std::vector<TypeDesc>
set_write_formats(ImageBuf& out, std::vector<TypeDesc> formats,
                  TypeDesc data_type)
{
    std::vector<std::string> crypto_layers;
    for (const ParamValue& p : out.spec().extra_attribs) {
        const std::string name = p.name().string();
        if (Strutil::starts_with(name, "cryptomatte/")
            && Strutil::ends_with(name, "/name"))
            crypto_layers.push_back(out.spec().get_string_attribute(name));
    }
    for (size_t c = 0; c < formats.size(); ++c) {
        if (data_type != TypeUnknown)
            formats[c] = data_type;
        if (is_cryptomatte_channel(out.spec().channelnames[c], crypto_layers))
            formats[c] = TypeFloat;
    }
    out.set_write_format(formats);
    return formats;
}


/// The memory a frame needs besides its input files' pixels (read as
/// float, each file at its own size). Per pixel of the frame: the role
/// images (up to 24 float channels), the demodulated, filtered and denoised
/// radiance (3 x 4 floats) and the output plane. Per pixel of one filter
/// tile with its halo (src/regression_filter.cpp: 1024 x 1024 plus
/// 2 (2 r_max + 4)): the filter's planes and accumulators, ~130 bytes. Per
/// pixel and layer in layers mode (the residual counted as one): the
/// layer's radiance, albedo and denoised radiance (3 x 3 floats; the
/// filter's memory is reused from one layer to the next). Rounded up: the
/// guard must err on the side of refusing. Measured: 1024 x 1024 RGBA half
/// with albedo, normal and depth peaks at 352 MiB, estimated 396 MiB;
/// 1024 x 1024 half with albedo and two Arnold-style layers (18 channels),
/// --rmax 2, peaks at 331 MiB (beauty) and 412 MiB (layers), estimated 424
/// and 544 MiB.
constexpr double kFrameBytesPerPixel = 160;
constexpr double kTileBytesPerPixel  = 192;
constexpr double kLayerBytesPerPixel = 40;
constexpr double kFilterTile         = 1024;

std::string
readable_size(double bytes)
{
    const double mib = bytes / double(1 << 20);
    return mib < 1024.0 ? format("{:.0f} MiB", mib)
                        : format("{:.1f} GiB", mib / 1024.0);
}

/// Refuse, before any pixel is read, a job whose frame would need more
/// memory than allowed: an oversized (or corrupt) header must fail with a
/// message, not get the process killed by the kernel. `layers`: the number
/// of layers of a layered denoise, 0 for the beauty.
void
check_memory(const Job& j, InputFiles& files, size_t layers)
{
    const uint64_t limit = j.mem_limit ? j.mem_limit : default_memory_limit();
    const InputHeader& in  = files.header(j.in.path);
    const ImageSpec& noisy = in.spec;
    // In double: a corrupt header's sizes may overflow 64-bit products.
    const double pixels = double(noisy.width) * double(noisy.height);
    double needed       = 0.0;
    std::set<std::string> seen;
    for (const std::string& path : input_paths(j))
        if (seen.insert(path).second) {
            const InputHeader& h = files.header(path);
            needed += 4.0 * double(h.channelnames.size())
                      * double(h.spec.width) * double(h.spec.height);
        }
    const double per_pixel
        = kFrameBytesPerPixel
          + (layers ? kLayerBytesPerPixel * double(layers + 1) : 0.0);
    const double tile = kFilterTile + 4.0 * j.filter.r_max + 8.0;
    needed += per_pixel * pixels
              + kTileBytesPerPixel * std::min(double(noisy.width), tile)
                    * std::min(double(noisy.height), tile);
    if (needed > double(limit))
        fail(format("'{}' is {}x{} with {} channels: denoising it{} needs "
                    "about {}, more than the memory limit of {}",
                    j.in.path, noisy.width, noisy.height,
                    in.channelnames.size(),
                    layers ? " in layers mode" : "",
                    readable_size(needed), readable_size(double(limit))));
}


void
run(Job j, JobResult& result)
{
    InputFiles files;
    Timer read_timer;
    const Convention conv
        = detect_convention(files.header(j.in.path).channelnames);
    apply_defaults(j, conv, result.log);
    const std::vector<LayerArg>& layer_args = j.layers.empty() ? conv.layers
                                                               : j.layers;
    if (j.mode == Mode::Layers && layer_args.empty())
        fail(format("--mode layers: no layers found in '{}' (see "
                    "docs/LAYERS.md); give them with --layer",
                    j.in.path));
    const bool layered = j.mode == Mode::Layers
                         || (j.mode == Mode::Auto && !j.layers.empty());
    if (!layered && !j.albedo.given)
        fail(format("no albedo: '{}' has no Denoising Albedo pass; give "
                    "--albedo FILE",
                    j.in.path));
    check_memory(j, files, layered ? layer_args.size() : 0);
    InputFile& input = files.get(j.in.path);
    ImageBuf& noisy  = input.image;

    RoleImage radiance = load_role(files, j.in, Role::Radiance, nullptr,
                                   "");
    RoleImage albedo;
    if (!layered)
        albedo = load_role(files, j.albedo, Role::Albedo, &noisy, j.in.path);
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
    // Layers are filtered in the input's own space: a divided layer is a
    // quotient per channel, which a change of primaries does not carry.
    if (managed && layered
        && (spaces.working != spaces.input || spaces.output != spaces.input))
        fail(format("--mode layers filters in the input's colour space "
                    "('{}'): give --working-colorspace and --ocolorspace "
                    "as the input's, or use --mode beauty",
                    spaces.input));
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
                       channel_list(files.image(arg.path).spec(),
                                    r.indices)));
    };
    show("radiance", j.in, radiance);
    show("albedo", j.albedo, albedo);
    for (const Optional& o : optional)
        show(o.label, *o.arg, o.image);

    LoadedLayers loaded;
    std::vector<Layer> layers;
    if (layered) {
        const size_t mode_line = result.log.size();
        // An explicit residual (--residual) or explicit layers (--layer)
        // are the user's decomposition: the residual is then not filtered.
        const bool own = !j.residual.empty() || !j.layers.empty();
        const std::string residual = j.residual.empty() ? conv.residual
                                                        : j.residual;
        layers = load_layers(files, j, layer_args, residual,
                             own ? std::string() : conv.residual_albedo,
                             conv.residual_layer,
                             own ? std::string() : conv.residual_unfiltered,
                             noisy, radiance.image,
                             loaded, result.log);
        result.log.insert(result.log.begin() + long(mode_line),
                          format("mode layers: {} layer(s){}", layers.size(),
                                 j.layers.empty() ? "" : " (--layer)"));
        result.log.push_back(
            guides.variance || guides.half_a
                ? "  noise     estimated per layer (--variance and --halves "
                  "describe the beauty, not a layer)"
                : "  noise     estimated per layer");
    } else {
        std::string found;
        for (const LayerArg& a : layer_args)
            found += (found.empty() ? "" : ", ") + a.name;
        result.log.push_back(found.empty()
                                 ? "mode beauty"
                                 : "mode beauty (layers found: " + found
                                       + "; --mode layers uses them)");
        if (!guides.variance && !guides.half_a)
            result.log.push_back("  noise     estimated from the image");
    }
    result.read_seconds = read_timer();
    result.log.push_back("parameters " + describe(j.filter));

    Timer denoise_timer;
    ImageBuf denoised;
    const bool ok = layered
                        ? layered_denoise(denoised, layers,
                                          loaded.residual.initialized()
                                              ? &loaded.residual
                                              : nullptr,
                                          guides, j.filter, &result.stats,
                                          {}, j.threads)
                        : denoise(denoised, radiance.image, albedo.image,
                                  guides, j.filter, &result.stats, {},
                                  j.threads);
    if (!ok)
        fail(format("denoising '{}' failed: {}", j.in.path,
                    one_line(denoised.geterror())));
    result.denoise_seconds = denoise_timer();
    if (managed)
        convert(denoised, spaces.working, spaces.output, j.in);

    // The output: the input file with its radiance RGB replaced (and the
    // denoised layers added with --aovs), each channel written in its input
    // pixel type unless -d says otherwise.
    ImageBuf& out = noisy;
    std::vector<TypeDesc> formats = input.formats;
    const std::vector<std::string>& names = out.spec().channelnames;
    const std::vector<std::string> beauty
        = { names[size_t(radiance.indices[0])],
            names[size_t(radiance.indices[1])],
            names[size_t(radiance.indices[2])] };
    const TypeDesc beauty_type = formats[size_t(radiance.indices[0])];
    put_channels(out, formats, denoised, beauty, beauty_type);
    if (j.write_layers)
        for (size_t i = 0; i < layers.size(); ++i) {
            const std::string& n = layers[i].name;
            put_channels(out, formats, loaded.denoised[i],
                         { n + ".R", n + ".G", n + ".B" }, beauty_type);
            const FilterStats& st = loaded.stats[i];
            result.log.push_back(format(
                "  layer {} written as {}.R,G,B (mean radius {:.2f})", n, n,
                st.mean_radius));
        }
    result.channel_formats = set_write_formats(out, formats, j.data_type);
    if (managed)
        colour::tag_colour_space(out.specmod(), spaces.output, spaces.input);
    out.specmod().attribute("zdenoise.version", ZDENOISE_VERSION_STRING);
    out.specmod().attribute("zdenoise.parameters",
                            describe(j.filter)
                                + (layered ? " mode=layers" : " mode=beauty"));
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


bool
parse_mode(const std::string& text, Mode& mode)
{
    if (text == "beauty")
        mode = Mode::Beauty;
    else if (text == "layers")
        mode = Mode::Layers;
    else
        return false;
    return true;
}


const char*
mode_name(Mode mode)
{
    return mode == Mode::Beauty ? "beauty" : mode == Mode::Layers ? "layers" : "";
}


bool
parse_data_type(const std::string& text, TypeDesc& type)
{
    if (text != "half" && text != "float")
        return false;
    type = TypeDesc(text);
    return true;
}


bool
parse_layer(const std::string& text, LayerArg& layer)
{
    const size_t eq = text.find('=');
    if (eq == std::string::npos || eq == 0)
        return false;
    const std::vector<std::string> parts = Strutil::splits(text.substr(eq + 1),
                                                           ":");
    if (parts.size() < 2 || parts.size() > 4 || parts[0].empty()
        || parts[1].empty())
        return false;
    layer.name      = text.substr(0, eq);
    layer.radiance  = parts[0];
    layer.albedo    = parts[1];
    layer.divided   = false;
    layer.reflected = false;
    for (size_t k = 2; k < parts.size(); ++k) {
        bool& flag = parts[k] == "divided" ? layer.divided : layer.reflected;
        if ((parts[k] != "divided" && parts[k] != "reflected") || flag)
            return false;  // unknown or repeated
        flag = true;
    }
    return true;
}


std::string
layer_text(const LayerArg& layer)
{
    return layer.name + "=" + layer.radiance + ":" + layer.albedo
           + (layer.divided ? ":divided" : "")
           + (layer.reflected ? ":reflected" : "");
}


uint64_t
default_memory_limit()
{
    // Half of the RAM, or of the cgroup's limit when the job runs in a
    // container or a farm slot with one: what the kernel's OOM killer
    // enforces.
    uint64_t total = 0;
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    uint64_t kib = 0;
    while (meminfo >> key >> kib) {
        if (key == "MemTotal:") {
            total = kib * 1024;
            break;
        }
        meminfo.ignore(256, '\n');
    }
    std::ifstream cgroup("/sys/fs/cgroup/memory.max");
    uint64_t cgroup_max = 0;
    if (cgroup >> cgroup_max && cgroup_max > 0
        && (total == 0 || cgroup_max < total))
        total = cgroup_max;
    if (total == 0)
        total = uint64_t(8) << 30;  // unknown: assume a modest machine
    return total / 2;
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
