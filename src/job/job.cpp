// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "job.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imagebufalgo_util.h>
#include <OpenImageIO/imagecache.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include "atomic_write.h"
#include "channel_spec.h"
#include "layer_conventions.h"
#include "options.h"
#include "row_reader.h"

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

/// Thrown when the OutputSink fails: its message is reported as it is.
struct SinkFailure {
    std::string message;
};


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

/// An input file's headers, checked: each part's spec (as an ImageBuf
/// reading it holds it, and as the file has it), and the channel names of
/// all its parts in one list (part k > 0 as part_channel_names() names
/// them).
struct InputHeader {
    /// Part 0, header only (the colour guess reads it). Held, never
    /// copied: copying an ImageBuf reads its pixels.
    std::shared_ptr<const ImageBuf> first;
    ImageSpec spec;                 ///< part 0's
    std::vector<ImageSpec> specs;   ///< every part's
    std::vector<ImageSpec> native;  ///< every part's, in the file's types
    std::vector<std::string> channelnames;
    int parts = 1;

    ROI window() const
    {
        return ROI(spec.x, spec.x + spec.width, spec.y, spec.y + spec.height);
    }
    /// Channel c's pixel type in the file.
    TypeDesc format(int c) const
    {
        for (const ImageSpec& s : native) {
            if (c < s.nchannels)
                return s.channelformat(c);
            c -= s.nchannels;
        }
        return TypeUnknown;
    }
};


/// Input files, each opened once however many roles it serves. Headers
/// are read first (header()), so that a bad file or a frame too large for
/// memory is refused before any pixel is read.
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
        auto first = std::make_shared<const ImageBuf>(checked_part(path, 0));
        // OIIO falls back to reading by content; a file whose contents
        // contradict its name was most likely written wrongly upstream.
        const std::string named = format_of_extension(path);
        const std::string found = std::string(first->file_format_name());
        if (!named.empty() && named != found)
            fail(format("cannot read '{}': it is a {} file, not {} as its "
                        "name says",
                        path, found, named));
        InputHeader h;
        h.first        = first;
        h.spec         = first->spec();
        h.channelnames = h.spec.channelnames;
        h.parts        = first->nsubimages();
        h.specs.push_back(first->spec());
        h.native.push_back(first->nativespec());
        for (int part = 1; part < h.parts; ++part) {
            const ImageBuf buf = checked_part(path, part);
            if (!same_pixels(first->roi(), buf.roi()))
                fail(format("'{}': part {} ('{}') is {}, part 0 is {}: "
                            "zdenoise needs every part to cover the same "
                            "pixels",
                            path, part, buf.spec().get_string_attribute("name"),
                            window_text(buf.roi()), window_text(first->roi())));
            for (const std::string& c : part_channel_names(buf.spec()))
                h.channelnames.push_back(c);
            h.specs.push_back(buf.spec());
            h.native.push_back(buf.nativespec());
        }
        // The pixels are read by a RowReader: OIIO's ImageCache need not
        // keep the file open (an OpenEXR reader holds its line buffers,
        // tens of MB for a render with many passes). Its entry stays.
        ImageCache::create(true)->close(ustring(path));
        return m_headers[path] = std::move(h);
    }

    /// The file's rows (rows() needs want() first for every channel used).
    RowReader& rows(const std::string& path)
    {
        auto it = m_rows.find(path);
        if (it == m_rows.end()) {
            const InputHeader& h = header(path);
            it = m_rows.emplace(path, std::make_unique<RowReader>(
                                          path, h.native, m_wanted[path]))
                     .first;
        }
        return *it->second;
    }

    /// Channels `indices` of `path` will be read.
    void want(const std::string& path, const std::vector<int>& indices)
    {
        std::vector<bool>& w = m_wanted[path];
        w.resize(header(path).channelnames.size(), false);
        for (int c : indices)
            w[size_t(c)] = true;
    }

    /// Every file with wanted channels.
    std::vector<std::string> paths() const
    {
        std::vector<std::string> p;
        for (const auto& w : m_wanted)
            p.push_back(w.first);
        return p;
    }

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

    std::map<std::string, InputHeader> m_headers;
    std::map<std::string, std::vector<bool>> m_wanted;
    std::map<std::string, std::unique_ptr<RowReader>> m_rows;
};


/// The channels of one role (the radiance, the albedo, a guide, one term
/// of a layer's sum), chosen from a file's header.
struct Selection {
    std::string path;
    std::vector<int> indices;        ///< in the file's channel list
    std::vector<std::string> names;  ///< the role image's channel names
};

/// Choose the channels of `arg` for `role`, checking they exist and that
/// the file covers the noisy input's pixels (`noisy`, from
/// `reference_path`; none for the noisy input itself). A file covering more
/// pixels than the noisy input (a guide rendered without the beauty's crop)
/// is cut to them; one covering fewer cannot be used.
Selection
select_role(InputFiles& files, const InputArg& arg, Role role,
            const ROI* noisy, const std::string& reference_path)
{
    Selection s;
    s.path                 = arg.path;
    const InputHeader& h   = files.header(arg.path);
    std::string err;
    if (!select_channels(h.channelnames, arg.channels, role, s.indices, err))
        fail(format("{} '{}': {}", role_name(role), arg.path, err));
    const ROI have = h.window();
    if (noisy && roi_intersection(have, *noisy) != *noisy)
        fail(format("{} '{}' is {}, but the noisy input '{}' is {}: it must "
                    "cover the same pixels",
                    role_name(role), arg.path, window_text(have),
                    reference_path, window_text(*noisy)));
    // Radiance channels are called R,G,B,A (A marks the filter's "no
    // surface"); the others keep the file's names.
    if (role == Role::Radiance || role == Role::LayerRadiance)
        s.names = { "R", "G", "B", "A" };
    s.names.resize(s.indices.size());
    for (size_t k = 0; k < s.indices.size(); ++k)
        if (s.names[k].empty())
            s.names[k] = h.channelnames[size_t(s.indices[k])];
    files.want(arg.path, s.indices);
    return s;
}


/// Whether values of `type` can be read or written at `p`, `stride` bytes
/// apart. Packed pixels of mixed types do not always allow it (a float
/// after three halves), and then the values are moved as bytes.
bool
aligned_for(const void* p, stride_t stride, TypeDesc type)
{
    const size_t a = type.basesize();
    return reinterpret_cast<uintptr_t>(p) % a == 0 && size_t(stride) % a == 0;
}


/// Move `n` consecutive channels of one pixel type from one interleaved
/// row to another, converting to `to` (OIIO's conversions, as a read or
/// write converting them would).
void
move_channels(const unsigned char* src, TypeDesc from, stride_t src_stride,
              unsigned char* dst, TypeDesc to, stride_t dst_stride, int n,
              int width)
{
    const size_t in = size_t(n) * from.size(), out = size_t(n) * to.size();
    if (from == to) {
        for (int x = 0; x < width; ++x)
            std::memcpy(dst + x * dst_stride, src + x * src_stride, in);
        return;
    }
    // Misaligned values go through packed (so aligned) rows of their own.
    thread_local std::vector<unsigned char> packed_in, packed_out;
    if (!aligned_for(src, src_stride, from)) {
        packed_in.resize(in * size_t(width));
        for (int x = 0; x < width; ++x)
            std::memcpy(&packed_in[size_t(x) * in], src + x * src_stride, in);
        src        = packed_in.data();
        src_stride = stride_t(in);
    }
    if (!aligned_for(dst, dst_stride, to)) {
        packed_out.resize(out * size_t(width));
        convert_image(n, width, 1, 1, src, from, src_stride, AutoStride,
                      AutoStride, packed_out.data(), to, stride_t(out),
                      AutoStride, AutoStride);
        for (int x = 0; x < width; ++x)
            std::memcpy(dst + x * dst_stride, &packed_out[size_t(x) * out],
                        out);
        return;
    }
    convert_image(n, width, 1, 1, src, from, src_stride, AutoStride,
                  AutoStride, dst, to, dst_stride, AutoStride, AutoStride);
}

/// Runs of the file channels `indices` that lie next to each other in the
/// file with one pixel type: each moves in one call.
struct ChannelRun {
    int first = 0;  ///< position in `indices`
    int count = 0;
};

std::vector<ChannelRun>
channel_runs(const RowReader& rows, const std::vector<int>& indices)
{
    std::vector<ChannelRun> runs;
    for (size_t k = 0; k < indices.size(); ++k) {
        const int c = indices[k];
        if (!runs.empty()) {
            ChannelRun& r  = runs.back();
            const int prev = indices[size_t(r.first + r.count - 1)];
            if (rows.format(c) == rows.format(prev)
                && rows.adjacent(prev, c)) {
                ++r.count;
                continue;
            }
        }
        runs.push_back({ int(k), 1 });
    }
    return runs;
}


/// Whether a role's channels can be handed to the library as the file's
/// rows themselves: next to each other, of one type, where that type may
/// be read.
bool
wraps(const RowReader& rows, const Selection& s,
      const std::vector<ChannelRun>& runs)
{
    return runs.size() == 1 && rows.aligned(s.indices[0]);
}


/// The rows the current strip holds: the strip's own rows (`core`) and the
/// rows around them that they depend on (`held`: the filter's halo, and
/// the residual layer mask's reach), x over the noisy input's columns.
struct Strip {
    ROI core, held;
    InputFiles* files = nullptr;
    int threads       = 0;

    /// A role's channels over the held rows: a float image of its own, or
    /// for an image only read (`read_only`) and whose channels lie next to
    /// each other in the file in one pixel type, the file's rows themselves
    /// (no copy; the operations take any pixel type and convert exactly as
    /// the copy would). Valid until the rows move on.
    ImageBuf image(const Selection& s, bool read_only = false) const
    {
        const RowReader& rows = files->rows(s.path);
        const int nch         = int(s.indices.size());
        const std::vector<ChannelRun> runs = channel_runs(rows, s.indices);
        const int c0    = s.indices[0];
        const bool wrap = read_only && wraps(rows, s, runs);
        ImageSpec spec(held.width(), held.height(), nch,
                       wrap ? rows.format(c0) : TypeFloat);
        spec.x = spec.full_x = held.xbegin;
        spec.y = spec.full_y = held.ybegin;
        spec.channelnames    = s.names;
        spec.alpha_channel   = -1;
        for (int c = 0; c < nch; ++c)
            if (Strutil::iequals(s.names[size_t(c)], "A")
                || Strutil::iequals(s.names[size_t(c)], "alpha"))
                spec.alpha_channel = c;
        if (wrap)
            return ImageBuf(spec,
                            const_cast<unsigned char*>(
                                rows.at(c0, held.xbegin, held.ybegin)),
                            rows.stride(c0), rows.row_stride(c0));
        ImageBuf img(spec, InitializePixels::No);
        auto* px = static_cast<unsigned char*>(img.localpixels());
        const stride_t pixel = stride_t(nch) * 4;
        parallel_for(int64_t(held.ybegin), int64_t(held.yend), [&](int64_t y) {
            unsigned char* dst = px
                                 + size_t(y - held.ybegin) * size_t(pixel)
                                       * size_t(held.width());
            for (const ChannelRun& r : runs) {
                const int c = s.indices[size_t(r.first)];
                move_channels(rows.at(c, held.xbegin, int(y)), rows.format(c),
                              rows.stride(c), dst + 4 * r.first, TypeFloat,
                              pixel, r.count, held.width());
            }
        }, paropt(threads));
        return img;
    }

    /// The sum of the images of `terms`, a float image of its own unless
    /// only read (`read_only`).
    ImageBuf sum(const std::vector<Selection>& terms,
                 bool read_only = true) const
    {
        ImageBuf total;
        for (const Selection& t : terms) {
            ImageBuf img = image(t, total.initialized()
                                        || (read_only && terms.size() == 1));
            if (!total.initialized())
                total = std::move(img);
            else if (!ImageBufAlgo::add(total, total, img, {}, threads))
                fail(format("'{}': {}", t.path, one_line(total.geterror())));
        }
        return total;
    }
};


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
        || !colour::resolve_job_spaces(config, j.colour,
                                       *files.header(j.in.path).first,
                                       *files.header(albedo.path).first,
                                       albedo.path == j.in.path, spaces,
                                       log, err))
        fail(err);
    return true;
}


std::string
channel_list(const std::vector<std::string>& names,
             const std::vector<int>& idx)
{
    std::string s;
    for (int i : idx)
        s += (s.empty() ? "" : ",") + names[size_t(i)];
    return s;
}


/// The selections of `selections` ('+' between them) of the --in file,
/// each R,G,B: the terms of a sum.
std::vector<Selection>
select_sum(InputFiles& files, const std::string& path,
           const std::string& selections, const ROI& noisy,
           std::string& shown)
{
    std::vector<Selection> terms;
    for (const std::string& part : Strutil::splits(selections, "+")) {
        terms.push_back(select_role(files, { path, part, true },
                                    Role::LayerRadiance, &noisy, path));
        shown += (shown.empty() ? "" : " + ")
                 + channel_list(files.header(path).channelnames,
                                terms.back().indices);
    }
    return terms;
}


/// Where the residual layer is negligible against the beauty in a whole
/// neighbourhood, set its albedo to 0, so that the filter passes it through
/// there. Beauty minus layers leaves a residue of the passes' half-float
/// rounding wherever the residual is really empty; relative to its own
/// (zero) level that residue is pure noise, and the filter would grow every
/// window there to r_max for nothing (it made layered mode 5-10x slower than
/// beauty mode). Pixels within `reach` of a real residual stay: an emitter's
/// anti-aliased edge has pixels whose few coverage samples all missed it,
/// and the filter gives them their share of its light. All three images
/// are float.
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


/// The layers of a layered denoise as channel selections: each layer's
/// radiance and albedo sums, and the residual.
struct LayersPlan {
    struct One {
        std::string name;
        std::vector<Selection> radiance, albedo;
        bool divided = false, reflected = false;
    };
    std::vector<One> layers;  ///< the given ones, then the residual's
    /// The residual's terms; none: the beauty minus the given layers.
    std::vector<Selection> residual;
    /// The residual is denoised as the last layer (residual_albedo), but for
    /// these terms, added as they are (residual_unfiltered).
    bool residual_is_layer = false;
    std::vector<Selection> residual_unfiltered;
    /// How far mask_negligible_residual() looks: rows a strip reads beyond
    /// the filter's halo (0 without a residual layer).
    int reach = 0;
};

/// Choose the layers and the residual; the residual is, unless selected,
/// the beauty minus the sum of the unfiltered layers, so that nothing of
/// the beauty is lost (in Cycles: Emit + Env, and any lobe whose passes
/// were not written). With `residual_albedo`, the residual becomes one
/// more layer, denoised with that albedo (see Convention::residual_albedo).
LayersPlan
plan_layers(InputFiles& files, const Job& j,
            const std::vector<LayerArg>& args, const std::string& residual,
            const std::string& residual_albedo,
            const std::string& residual_layer,
            const std::string& residual_unfiltered, const ROI& noisy,
            std::vector<std::string>& log)
{
    LayersPlan plan;
    for (const LayerArg& a : args) {
        std::string shown_radiance, shown_albedo;
        LayersPlan::One one;
        one.name      = a.name;
        one.divided   = a.divided;
        one.reflected = a.reflected;
        one.radiance = select_sum(files, j.in.path, a.radiance, noisy,
                                  shown_radiance);
        one.albedo   = select_sum(files, j.in.path, a.albedo, noisy,
                                  shown_albedo);
        plan.layers.push_back(std::move(one));
        log.push_back(format("  layer     {}: {} with albedo {}{}{}", a.name,
                             shown_radiance, shown_albedo,
                             a.divided ? " (divided by it)" : "",
                             a.reflected ? " (reflected: stricter edge test)"
                                         : ""));
    }
    std::string shown_residual = "the beauty minus the layers";
    if (!residual.empty()) {
        shown_residual.clear();
        plan.residual = select_sum(files, j.in.path, residual, noisy,
                                   shown_residual);
    }
    if (residual_albedo.empty()) {
        log.push_back("  residual  " + shown_residual + ", not filtered");
        return plan;
    }
    std::string shown_albedo;
    LayersPlan::One one;
    one.name   = residual_layer;
    one.albedo = select_sum(files, j.in.path, residual_albedo, noisy,
                            shown_albedo);
    plan.layers.push_back(std::move(one));
    plan.residual_is_layer = true;
    plan.reach             = std::max(j.filter.r_max, 0);
    if (!residual_unfiltered.empty()) {
        std::string shown_unfiltered;
        plan.residual_unfiltered = select_sum(files, j.in.path,
                                              residual_unfiltered, noisy,
                                              shown_unfiltered);
        shown_residual += " minus " + shown_unfiltered;
        log.push_back("  residual  " + shown_unfiltered + ", not filtered");
    }
    log.push_back(format("  layer     {}: {} with albedo {}", residual_layer,
                         shown_residual, shown_albedo));
    return plan;
}


/// The layers of one strip, read.
struct LoadedLayers {
    std::vector<ImageBuf> radiance, albedo, denoised;
    std::vector<FilterStats> stats;
    ImageBuf residual;
};

/// Read the strip's layers and residual as `plan` says.
std::vector<Layer>
load_layers(const Strip& strip, const LayersPlan& plan, const Job& j,
            const ImageBuf& beauty, LoadedLayers& l)
{
    const size_t n = plan.layers.size();
    l.radiance.assign(n, ImageBuf());
    l.albedo.assign(n, ImageBuf());
    l.denoised.assign(n, ImageBuf());
    l.stats.assign(n, FilterStats());
    l.residual.reset();
    std::vector<Layer> layers(n);
    const size_t given = plan.residual_is_layer ? n - 1 : n;
    for (size_t i = 0; i < n; ++i) {
        const LayersPlan::One& one = plan.layers[i];
        if (i < given)
            l.radiance[i] = strip.sum(one.radiance);
        // The residual layer's albedo is masked below: a copy of its own.
        l.albedo[i]         = strip.sum(one.albedo, i < given);
        layers[i].name      = one.name;
        layers[i].radiance  = &l.radiance[i];
        layers[i].albedo    = &l.albedo[i];
        layers[i].divided   = one.divided;
        layers[i].reflected = one.reflected;
        layers[i].denoised  = &l.denoised[i];
        layers[i].stats     = &l.stats[i];
    }
    if (!plan.residual.empty()) {
        l.residual = strip.sum(plan.residual, !plan.residual_is_layer);
    } else {
        std::vector<Layer> unfiltered(layers.begin(),
                                      layers.begin() + long(given));
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
        FilterOptions sum_options = j.filter;
        sum_options.progress      = nullptr;
        if (!layered_denoise(sum, unfiltered, nullptr, {}, sum_options,
                             nullptr, rgb, j.threads)
            || !ImageBufAlgo::sub(l.residual, beauty, sum, rgb, j.threads))
            fail(format("layers of '{}': {}", j.in.path,
                        one_line(sum.has_error() ? sum.geterror()
                                                 : l.residual.geterror())));
    }
    if (!plan.residual_is_layer)
        return layers;
    const size_t i = n - 1;
    l.radiance[i].swap(l.residual);  // l.residual: uninitialized again
    if (!plan.residual_unfiltered.empty()) {
        l.residual = strip.sum(plan.residual_unfiltered);
        if (!ImageBufAlgo::sub(l.radiance[i], l.radiance[i], l.residual, {},
                               j.threads))
            fail(format("layers of '{}': {}", j.in.path,
                        one_line(l.radiance[i].geterror())));
    }
    // The mask reads float images; the beauty may be the file's half rows.
    const ImageBuf beauty_float = beauty.spec().format == TypeFloat
                                      ? ImageBuf()
                                      : beauty.copy(TypeFloat);
    mask_negligible_residual(l.albedo[i], l.radiance[i],
                             beauty_float.initialized() ? beauty_float
                                                        : beauty,
                             plan.reach, j.threads);
    return layers;
}


/// One channel of the output and where its pixels come from: a channel of
/// the --in file, or a channel of a denoised image of the strip.
struct OutputChannel {
    int file = -1;  ///< channel of the --in file, or -1
    int image = -1, image_channel = 0;  ///< else: denoised image, channel
    TypeDesc type;  ///< pixel type in the output
};

/// Write `rgb` (3 channels, the denoised image `image`) into the output
/// channels `names`, appending those that do not exist (in pixel type
/// `type`) with the output spec's metadata kept.
void
put_channels(ImageSpec& spec, std::vector<OutputChannel>& channels,
             int image, const std::vector<std::string>& names, TypeDesc type)
{
    for (int c = 0; c < 3; ++c) {
        int dc = spec.channelindex(names[size_t(c)]);
        if (dc < 0) {
            spec.channelnames.push_back(names[size_t(c)]);
            spec.nchannels = int(spec.channelnames.size());
            channels.push_back({ -1, image, c, type });
            continue;
        }
        channels[size_t(dc)].file          = -1;
        channels[size_t(dc)].image         = image;
        channels[size_t(dc)].image_channel = c;
    }
}


/// Each output channel's pixel type: the input's, or `data_type`;
/// Cryptomatte channels always float (their ids are float bit patterns).
std::vector<TypeDesc>
write_formats(const ImageSpec& spec, std::vector<OutputChannel>& channels,
              TypeDesc data_type)
{
    std::vector<std::string> crypto_layers;
    for (const ParamValue& p : spec.extra_attribs) {
        const std::string name = p.name().string();
        if (Strutil::starts_with(name, "cryptomatte/")
            && Strutil::ends_with(name, "/name"))
            crypto_layers.push_back(spec.get_string_attribute(name));
    }
    std::vector<TypeDesc> formats;
    for (size_t c = 0; c < channels.size(); ++c) {
        TypeDesc& t = channels[c].type;
        if (data_type != TypeUnknown)
            t = data_type;
        if (is_cryptomatte_channel(spec.channelnames[c], crypto_layers))
            t = TypeFloat;
        formats.push_back(t);
    }
    return formats;
}


/// The output spec as the --in file's pixels read into one ImageBuf have
/// it: part 0's spec, with the channels of every part, each part's
/// metadata that part 0 lacks (the ImageBuf of the whole frame zdenoise
/// used to read held exactly this).
ImageSpec
output_spec(const InputHeader& in)
{
    ImageSpec spec = in.spec;
    spec.set_format(TypeFloat);
    if (in.parts == 1)
        return spec;
    for (size_t p = 1; p < in.specs.size(); ++p)
        for (const ParamValue& v : in.specs[p].extra_attribs)
            if (!spec.find_attribute(v.name()))
                spec.extra_attribs.push_back(v);
    spec.nchannels    = int(in.channelnames.size());
    spec.channelnames = in.channelnames;
    spec.erase_attribute("name");
    spec.erase_attribute("oiio:subimagename");
    spec.erase_attribute("oiio:subimages");
    return spec;
}


std::string
readable_size(double bytes)
{
    const double mib = bytes / double(1 << 20);
    return mib < 1024.0 ? format("{:.0f} MiB", mib)
                        : format("{:.1f} GiB", mib / 1024.0);
}


/// The memory a strip needs. Measured peaks of the heap (docs/PERFORMANCE.md,
/// "Memory") sit at or below these estimates, which leave out what does
/// not depend on the job (the program and its libraries); the guard must
/// err on the side of refusing.
struct StripCost {
    double held_pixel = 0;  ///< per pixel of the held rows (strip + halo)
    double core_pixel = 0;  ///< per pixel of the strip's own rows
    double file_row   = 0;  ///< the input files' held rows, per row
    double out_row    = 0;  ///< one output row as the sink takes it
    double fixed      = 0;  ///< decoders, encoder, an output held whole
    int width = 0, height = 0;
    int halo   = 0;  ///< the filter's (filter_halo())
    int around = 0;  ///< rows read above and below a strip (>= halo)

    /// Filter: per pixel of one internal tile of regression_filter()
    /// (1024 x 1024) with its halo, its decoded planes and accumulators.
    static constexpr double kTileBytesPerPixel = 192;
    static constexpr int kFilterTile           = 1024;
    /// Output rows are assembled and written this many at a time.
    static constexpr int kBandRows = 32;

    double bytes(int rows) const
    {
        const double held = std::min(double(height),
                                     double(rows) + 2.0 * around);
        const double tile_w = std::min(double(width),
                                       double(kFilterTile) + 2.0 * halo);
        const double tile_h = std::min(held,
                                       double(kFilterTile) + 2.0 * halo);
        return fixed + file_row * held + held_pixel * width * held
               + core_pixel * width * double(rows)
               + out_row * std::min(rows, kBandRows)
               + kTileBytesPerPixel * tile_w * tile_h;
    }
};


/// What an OpenEXR reader or writer of a file with these pixels keeps
/// besides them: per thread of OpenEXR's pool, two blocks (tiles, or rows:
/// 16 for zip, 32 for piz, ...) in flight, each with its compressor's
/// buffers (measured: three times the block for zip).
double
codec_bytes(const ImageSpec& spec, size_t pixel_bytes)
{
    const std::string c = Strutil::lower(spec.get_string_attribute("compression"));
    int threads = 0;
    OIIO::getattribute("exr_threads", threads);
    threads = std::max(threads, 1);
    if (spec.tile_width)
        return 3.0 * 2.0 * threads * double(spec.tile_width)
               * double(spec.tile_height) * double(pixel_bytes);
    int rows = 16;
    if (c.empty() || c == "none" || c == "rle" || c == "zips")
        rows = 1;
    else if (Strutil::starts_with(c, "dwab"))
        rows = 256;
    else if (!Strutil::starts_with(c, "zip"))
        rows = 32;
    return 3.0 * 2.0 * threads * rows * double(pixel_bytes)
           * double(spec.width);
}


/// How many rows a strip has: --tile, or else as many as keep a strip's
/// memory within a comfortable size (or the memory limit, when that is
/// lower), in strips of equal height. Strips are at most as tall as the
/// filter's internal tile: up to that, cutting the frame costs the filter
/// nothing a whole-frame run does not pay too (a strip boundary, like a
/// tile boundary, makes the centres within r_max of it be fitted twice).
/// Below 256 rows that cost grows quickly (2 r_max of S rows), so strips
/// are thinner than that only when the memory limit demands it. Refuses,
/// before any pixel is read, a job whose strip would need more memory than
/// allowed: an oversized (or corrupt) header must fail with a message, not
/// get the process killed.
void
plan_strips(const Job& j, const InputHeader& in, const StripCost& cost,
            JobResult& result)
{
    const uint64_t limit = j.mem_limit ? j.mem_limit : default_memory_limit();
    // Leaves room for the rest of a render node's work; a 1080p frame with
    // 54 passes takes four strips of 270 rows.
    constexpr double kComfortable = 256.0 * (1 << 20);
    constexpr int kEfficient      = 256;
    constexpr int kThinnest       = 16;
    const int height = cost.height;
    int rows         = 0;
    double needed    = 0.0;
    if (j.tile_rows > 0) {
        rows   = std::min(j.tile_rows, height);
        needed = cost.bytes(rows);
    } else {
        const double budget = std::min(double(limit), kComfortable);
        int n  = (height + StripCost::kFilterTile - 1) / StripCost::kFilterTile;
        rows   = (height + n - 1) / n;
        needed = cost.bytes(rows);
        while (needed > budget && rows > kThinnest) {
            const int next = (height + n) / (n + 1);
            if (next < kEfficient && needed <= double(limit))
                break;
            ++n;
            rows   = next;
            needed = cost.bytes(rows);
        }
    }
    if (needed > double(limit)) {
        const std::string how
            = j.tile_rows > 0 ? format(" in strips of {} rows (--tile)", rows)
              : rows < height ? format(" even in strips of {} rows", rows)
                              : std::string();
        fail(format("'{}' is {}x{} with {} channels: denoising it needs "
                    "about {}{}, more than the memory limit of {}",
                    j.in.path, cost.width, height, in.channelnames.size(),
                    readable_size(needed), how,
                    readable_size(double(limit))));
    }
    result.strip_rows      = rows;
    result.strips          = (height + rows - 1) / rows;
    result.estimated_bytes = needed;
}


/// Where the output of one strip comes from and goes to.
struct Output {
    OutputSink* sink = nullptr;
    ImageSpec spec;
    std::vector<OutputChannel> channels;
    std::vector<TypeDesc> row_types;  ///< as the sink takes them
    std::vector<size_t> offset;       ///< of each channel in a pixel
    size_t pixel_bytes = 0;
    std::vector<unsigned char> band, plane;

    void set_row_types(bool float_rows)
    {
        pixel_bytes = 0;
        for (const OutputChannel& c : channels) {
            row_types.push_back(float_rows ? TypeFloat : c.type);
            offset.push_back(pixel_bytes);
            pixel_bytes += row_types.back().size();
        }
    }

    /// Assemble the output rows of `strip` band by band and give them to
    /// the sink: channels of the --in file moved from its rows (in runs of
    /// neighbours of one type), the others from the denoised `images`.
    void write(const Strip& strip, const RowReader& in,
               const std::vector<const ImageBuf*>& images, int threads)
    {
        const ROI& core = strip.core;
        const int width = core.width();
        // Runs of output channels taken from neighbouring file channels of
        // one type into neighbouring output channels of one type.
        struct Run {
            int first, count, file;
        };
        std::vector<Run> runs;
        for (size_t c = 0; c < channels.size(); ++c) {
            const OutputChannel& oc = channels[c];
            if (oc.file < 0)
                continue;
            if (!runs.empty()) {
                Run& r        = runs.back();
                const int pc  = r.first + r.count - 1;
                const int pf  = r.file + r.count - 1;
                if (int(c) == pc + 1 && oc.file == pf + 1
                    && in.format(oc.file) == in.format(pf)
                    && row_types[c] == row_types[size_t(pc)]
                    && in.adjacent(pf, oc.file)) {
                    ++r.count;
                    continue;
                }
            }
            runs.push_back({ int(c), 1, oc.file });
        }
        const size_t row_bytes = pixel_bytes * size_t(width);
        for (int y0 = core.ybegin; y0 < core.yend;
             y0 += StripCost::kBandRows) {
            const int y1 = std::min(y0 + StripCost::kBandRows, core.yend);
            band.resize(row_bytes * size_t(y1 - y0));
            parallel_for(int64_t(y0), int64_t(y1), [&](int64_t y) {
                unsigned char* row = band.data() + size_t(y - y0) * row_bytes;
                for (const Run& r : runs)
                    move_channels(in.at(r.file, core.xbegin, int(y)),
                                  in.format(r.file), in.stride(r.file),
                                  row + offset[size_t(r.first)],
                                  row_types[size_t(r.first)],
                                  stride_t(pixel_bytes), r.count, width);
            }, paropt(threads));
            for (size_t c = 0; c < channels.size(); ++c) {
                const OutputChannel& oc = channels[c];
                if (oc.file >= 0)
                    continue;
                // Through a plane of its own: the channel's place in the
                // packed pixels may not suit its type (aligned_for()).
                const ImageBuf& img = *images[size_t(oc.image)];
                const size_t size   = row_types[c].size();
                plane.resize(size * size_t(width) * size_t(y1 - y0));
                if (!img.get_pixels(ROI(core.xbegin, core.xend, y0, y1, 0, 1,
                                        oc.image_channel,
                                        oc.image_channel + 1),
                                    row_types[c], plane.data()))
                    fail(format("cannot assemble the output: {}",
                                one_line(img.geterror())));
                for (size_t p = 0, n = size_t(width) * size_t(y1 - y0); p < n;
                     ++p)
                    std::memcpy(band.data() + p * pixel_bytes + offset[c],
                                &plane[p * size], size);
            }
            std::string err;
            if (!sink->rows(y0, y1, band.data(), err))
                throw SinkFailure { err };
        }
    }
};


void
run(Job j, OutputSink& sink, JobResult& result)
{
    const std::string invalid = validate(j, Spelling::CommandLine);
    if (!invalid.empty())
        fail(invalid);
    InputFiles files;
    Timer read_timer;
    const InputHeader& in = files.header(j.in.path);
    const Convention conv = detect_convention(in.channelnames);
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
    const ROI noisy = in.window();

    // Every channel the job reads, chosen from the headers: a missing
    // channel or a file of other pixels fails before any pixel is read.
    const Selection radiance = select_role(files, j.in, Role::Radiance,
                                           nullptr, "");
    Selection albedo;
    if (!layered)
        albedo = select_role(files, j.albedo, Role::Albedo, &noisy,
                             j.in.path);
    struct Optional {
        const InputArg* arg;
        Role role;
        bool disabled;
        const char* label;
        bool used = false;
        Selection selection;
        ImageBuf image;  ///< the current strip's
    } optional[] = {
        { &j.normal, Role::Normal, j.no_normal, "normal", false, {}, {} },
        { &j.depth, Role::Depth, j.no_depth, "depth", false, {}, {} },
        { &j.id, Role::ObjectId, j.no_id, "id", false, {}, {} },
        { &j.variance, Role::Variance, false, "variance", false, {}, {} },
        { &j.half_a, Role::Radiance, false, "half A", false, {}, {} },
        { &j.half_b, Role::Radiance, false, "half B", false, {}, {} },
    };
    for (Optional& o : optional)
        if (o.arg->given && !o.disabled) {
            o.selection = select_role(files, *o.arg, o.role, &noisy,
                                      j.in.path);
            o.used      = true;
        }
    // The output takes every channel of the --in file.
    {
        std::vector<int> all(in.channelnames.size());
        for (size_t c = 0; c < all.size(); ++c)
            all[c] = int(c);
        files.want(j.in.path, all);
    }

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
    if (managed && optional[3].used && spaces.input != spaces.working)
        result.log.push_back("  variance  used as given (not converted "
                             "to the working space)");

    result.log.push_back(format("{}x{}, {} channels in '{}'", noisy.width(),
                                noisy.height(), in.channelnames.size(),
                                j.in.path));
    auto show = [&](const char* what, const Selection& s) {
        result.log.push_back(format(
            "  {:<9} '{}' channels {}", what, s.path,
            channel_list(files.header(s.path).channelnames, s.indices)));
    };
    show("radiance", radiance);
    if (!layered)
        show("albedo", albedo);
    for (const Optional& o : optional)
        if (o.used)
            show(o.label, o.selection);

    LayersPlan layers_plan;
    if (layered) {
        const size_t mode_line = result.log.size();
        // An explicit residual (--residual) or explicit layers (--layer)
        // are the user's decomposition: the residual is then not filtered.
        const bool own = !j.residual.empty() || !j.layers.empty();
        const std::string residual = j.residual.empty() ? conv.residual
                                                        : j.residual;
        layers_plan = plan_layers(
            files, j, layer_args, residual,
            own ? std::string() : conv.residual_albedo, conv.residual_layer,
            own ? std::string() : conv.residual_unfiltered, noisy,
            result.log);
        result.log.insert(result.log.begin() + long(mode_line),
                          format("mode layers: {} layer(s){}",
                                 layers_plan.layers.size(),
                                 j.layers.empty() ? "" : " (--layer)"));
        result.log.push_back(
            optional[3].used || optional[4].used
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
        if (!optional[3].used && !optional[4].used)
            result.log.push_back("  noise     estimated from the image");
    }

    // The output: the input file with its radiance RGB replaced (and the
    // denoised layers added with --aovs), each channel in its input pixel
    // type unless -d says otherwise. Images: 0 the denoised beauty, 1 + i
    // layer i.
    ImageSpec spec = output_spec(in);
    std::vector<OutputChannel> channels(in.channelnames.size());
    for (size_t c = 0; c < channels.size(); ++c)
        channels[c] = { int(c), -1, 0, in.format(int(c)) };
    const std::vector<std::string>& names = in.channelnames;
    const TypeDesc beauty_type = in.format(radiance.indices[0]);
    put_channels(spec, channels, 0,
                 { names[size_t(radiance.indices[0])],
                   names[size_t(radiance.indices[1])],
                   names[size_t(radiance.indices[2])] },
                 beauty_type);
    if (j.write_layers)
        for (size_t i = 0; i < layers_plan.layers.size(); ++i) {
            const std::string& n = layers_plan.layers[i].name;
            put_channels(spec, channels, int(i) + 1,
                         { n + ".R", n + ".G", n + ".B" }, beauty_type);
        }
    result.channel_formats = write_formats(spec, channels, j.data_type);
    if (managed)
        colour::tag_colour_space(spec, spaces.output, spaces.input);
    spec.attribute("zdenoise.version", ZDENOISE_VERSION_STRING);
    spec.attribute("zdenoise.parameters",
                   describe(j.filter)
                       + (layered ? " mode=layers" : " mode=beauty"));

    // Strips: their height from the memory each needs.
    StripCost cost;
    cost.width  = noisy.width();
    cost.height = noisy.height();
    cost.halo   = filter_halo(j.filter);
    // The residual layer's mask looks further than the filter.
    cost.around = cost.halo + layers_plan.reach;
    for (const std::string& path : files.paths()) {
        const InputHeader& h = files.header(path);
        cost.file_row += double(files.rows(path).pixel_bytes())
                         * double(h.spec.width);
        cost.fixed += double(files.rows(path).fixed_bytes());
        for (const ImageSpec& part : h.native)
            cost.fixed += codec_bytes(part, part.pixel_bytes(true));
    }
    // Role images: copies when converted or not lying together in the
    // file, else the file's rows themselves (Strip::image()).
    const bool radiance_as_is = !managed || spaces.input == spaces.working;
    auto role_bytes = [&](const Selection& s, bool read_only) {
        const RowReader& rows = files.rows(s.path);
        return read_only && wraps(rows, s, channel_runs(rows, s.indices))
                   ? 0.0
                   : 4.0 * double(s.indices.size());
    };
    // The quotient (demodulate()), the filtered and the denoised radiance.
    cost.held_pixel = role_bytes(radiance, radiance_as_is) + 16.0;
    cost.core_pixel = 32.0;
    if (!layered)
        cost.held_pixel += role_bytes(albedo, !managed
                                                  || spaces.albedo
                                                         == spaces.working);
    for (const Optional& o : optional)
        if (o.used)
            cost.held_pixel += role_bytes(o.selection,
                                          o.role != Role::Radiance
                                              || radiance_as_is);
    if (layered) {
        // Each layer's radiance and albedo sums, the residual and the sum
        // (over the held rows), each denoised layer (over the strip).
        cost.held_pixel += 24.0 * double(layers_plan.layers.size()) + 24.0
                           + (layers_plan.residual_is_layer ? 8.0 : 0.0);
        cost.core_pixel += 12.0 * double(layers_plan.layers.size());
    }
    Output output;
    output.sink     = &sink;
    output.channels = channels;
    output.set_row_types(sink.float_rows());
    cost.out_row = double(output.pixel_bytes) * cost.width;
    if (sink.holds_image())
        cost.fixed += cost.out_row * cost.height;
    else {
        ImageSpec scanlines = spec;  // written as scanlines (FileSink)
        scanlines.tile_width = scanlines.tile_height = 0;
        cost.fixed += codec_bytes(scanlines, output.pixel_bytes);
    }
    plan_strips(j, in, cost, result);
    result.log.push_back(
        result.strips == 1
            ? format("whole frame at once (about {})",
                     readable_size(result.estimated_bytes))
            : format("{} strips of {} rows, each read with {} rows of halo "
                     "around it (about {} each)",
                     result.strips, result.strip_rows, cost.around,
                     readable_size(result.estimated_bytes)));
    result.log.push_back("parameters " + describe(j.filter));

    for (const std::string& path : files.paths())
        files.rows(path).reserve(std::min(result.strip_rows + 2 * cost.around,
                                          cost.height));
    {
        std::string err;
        if (!sink.begin(spec, result.channel_formats, err))
            throw SinkFailure { err };
    }
    result.read_seconds += read_timer();

    // Statistics summed over the strips; the mean radius from the exact
    // sum of radii, so that it does not depend on the strips.
    std::vector<FilterStats> layer_stats;
    Strip strip;
    strip.files   = &files;
    strip.threads = j.threads;
    FilterOptions options = j.filter;
    options.frame         = noisy;
    const int around      = cost.around;
    for (int s = 0; s < result.strips; ++s) {
        Timer strip_read;
        strip.core        = noisy;
        strip.core.ybegin = noisy.ybegin + s * result.strip_rows;
        strip.core.yend   = std::min(strip.core.ybegin + result.strip_rows,
                                     noisy.yend);
        strip.held        = strip.core;
        strip.held.ybegin = std::max(strip.core.ybegin - around,
                                     noisy.ybegin);
        strip.held.yend   = std::min(strip.core.yend + around, noisy.yend);
        for (const std::string& path : files.paths()) {
            std::string err;
            if (!files.rows(path).hold(strip.held.ybegin, strip.held.yend,
                                       j.threads, err))
                fail(format("cannot read '{}': {}", path, one_line(err)));
        }
        // Images converted to the working space are copies; the others
        // are the files' rows.
        ImageBuf radiance_image = strip.image(radiance, radiance_as_is);
        ImageBuf albedo_image;
        if (!layered)
            albedo_image = strip.image(albedo, !managed
                                                   || spaces.albedo
                                                          == spaces.working);
        for (Optional& o : optional)
            o.image = o.used ? strip.image(o.selection,
                                           o.role != Role::Radiance
                                               || radiance_as_is)
                             : ImageBuf();
        if (managed) {
            convert(radiance_image, spaces.input, spaces.working, j.in);
            convert(albedo_image, spaces.albedo, spaces.working, j.albedo);
            convert(optional[4].image, spaces.input, spaces.working,
                    j.half_a);
            convert(optional[5].image, spaces.input, spaces.working,
                    j.half_b);
        }
        Guides guides;
        auto guide = [](const Optional& o) {
            return o.used ? &o.image : nullptr;
        };
        guides.normal    = guide(optional[0]);
        guides.depth     = guide(optional[1]);
        guides.object_id = guide(optional[2]);
        guides.variance  = guide(optional[3]);
        guides.half_a    = guide(optional[4]);
        guides.half_b    = guide(optional[5]);
        LoadedLayers loaded;
        std::vector<Layer> layers;
        if (layered)
            layers = load_layers(strip, layers_plan, j, radiance_image,
                                 loaded);
        result.read_seconds += strip_read();

        Timer denoise_timer;
        if (j.filter.progress)
            options.progress = [&](float f) {
                j.filter.progress((float(s) + f) / float(result.strips));
            };
        ImageBuf denoised;
        FilterStats st;
        const bool ok
            = layered ? layered_denoise(denoised, layers,
                                        loaded.residual.initialized()
                                            ? &loaded.residual
                                            : nullptr,
                                        guides, options, &st, strip.core,
                                        j.threads)
                      : denoise(denoised, radiance_image, albedo_image,
                                guides, options, &st, strip.core, j.threads);
        if (!ok)
            fail(format("denoising '{}' failed: {}", j.in.path,
                        one_line(denoised.geterror())));
        result.denoise_seconds += denoise_timer();
        result.stats.merge(st);
        layer_stats.resize(loaded.stats.size());
        for (size_t i = 0; i < loaded.stats.size(); ++i)
            layer_stats[i].merge(loaded.stats[i]);

        Timer write_timer;
        if (managed)
            convert(denoised, spaces.working, spaces.output, j.in);
        std::vector<const ImageBuf*> images = { &denoised };
        for (const ImageBuf& l : loaded.denoised)
            images.push_back(&l);
        output.write(strip, files.rows(j.in.path), images, j.threads);
        result.write_seconds += write_timer();
    }
    if (j.write_layers)
        for (size_t i = 0; i < layer_stats.size(); ++i) {
            const std::string& n = layers_plan.layers[i].name;
            const double mean    = layer_stats[i].mean_radius;
            result.log.push_back(format(
                "  layer {} written as {}.R,G,B (mean radius {:.2f})", n, n,
                mean));
        }
    Timer end_timer;
    std::string err;
    if (!sink.end(err))
        throw SinkFailure { err };
    result.write_seconds += end_timer();
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
run_job(const Job& job, OutputSink& sink, JobResult& result,
        std::string& error)
{
    try {
        run(job, sink, result);
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


namespace {

/// The output image in memory, float, with its write formats set.
class ImageSink final : public OutputSink {
public:
    explicit ImageSink(ImageBuf& image)
        : m_image(image)
    {
    }
    bool begin(const ImageSpec& spec, const std::vector<TypeDesc>& formats,
               std::string& error) override
    {
        m_image.reset(spec);
        m_image.set_write_format(formats);
        return true;
    }
    bool float_rows() const override { return true; }
    bool holds_image() const override { return true; }
    bool rows(int ybegin, int yend, const void* data,
              std::string& error) override
    {
        const ImageSpec& s = m_image.spec();
        if (m_image.set_pixels(ROI(s.x, s.x + s.width, ybegin, yend, s.z,
                                   s.z + 1, 0, s.nchannels),
                               TypeFloat, data))
            return true;
        error = m_image.geterror();
        return false;
    }

private:
    ImageBuf& m_image;
};


/// The output file, written as ImageBuf::write would write the image in
/// memory: scanlines, each channel in its output type, the pixel type of
/// the spec the widest.
class FileSink final : public OutputSink {
public:
    explicit FileSink(const std::string& path)
        : m_path(path)
    {
    }
    bool begin(const ImageSpec& spec, const std::vector<TypeDesc>& formats,
               std::string& error) override
    {
        ImageSpec s   = spec;
        s.tile_width  = 0;
        s.tile_height = 0;
        s.tile_depth  = 0;
        TypeDesc widest;
        for (TypeDesc f : formats)
            widest = TypeDesc::basetype_merge(widest, f);
        s.set_format(widest);
        s.channelformats = formats;
        if (std::all_of(formats.begin(), formats.end(),
                        [&](TypeDesc f) { return f == widest; }))
            s.channelformats.clear();
        m_out = ImageOutput::create(m_path);
        if (!m_out)
            return failed(OIIO::geterror(), error);
        if (!m_out->open(m_path, s))
            return failed(m_out->geterror(), error);
        m_z = s.z;
        return true;
    }
    bool rows(int ybegin, int yend, const void* data,
              std::string& error) override
    {
        return m_out->write_scanlines(ybegin, yend, m_z, TypeUnknown, data)
               || failed(m_out->geterror(), error);
    }
    bool end(std::string& error) override
    {
        return m_out->close() || failed(m_out->geterror(), error);
    }
    /// Whether the failure, if any, was writing.
    bool write_failed() const { return m_failed; }

private:
    bool failed(std::string why, std::string& error)
    {
        m_failed = true;
        error    = why.empty() ? std::string("unknown error") : why;
        return false;
    }

    std::string m_path;
    std::unique_ptr<ImageOutput> m_out;
    int m_z       = 0;
    bool m_failed = false;
};

}  // namespace


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
