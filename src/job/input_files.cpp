// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "input_files.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagecache.h>
#include <OpenImageIO/strutil.h>

#include "failure.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {


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


/// Part `part`'s header; a deep part or one without pixels is refused.
ImageBuf
checked_part(const std::string& path, int part)
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

}  // namespace


const InputHeader&
InputFiles::header(const std::string& path)
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


RowReader&
InputFiles::rows(const std::string& path)
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


void
InputFiles::want(const std::string& path, const std::vector<int>& indices)
{
    std::vector<bool>& w = m_wanted[path];
    w.resize(header(path).channelnames.size(), false);
    for (int c : indices)
        w[size_t(c)] = true;
}


std::vector<std::string>
InputFiles::paths() const
{
    std::vector<std::string> p;
    for (const auto& w : m_wanted)
        p.push_back(w.first);
    return p;
}


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


namespace {

/// Attribute `name` of `s` as text ("" when absent): strings as they are,
/// numbers and matrices as OIIO prints them.
std::string
attribute_text(const ImageSpec& s, const char* name)
{
    const ParamValue* p = s.find_attribute(name);
    return p ? p->get_string() : std::string();
}


/// Do two float attributes (matrices, vectors) agree to `rel` of their
/// size? Renderers write the same camera with rounding of their own.
bool
same_floats(const ParamValue& a, const ParamValue& b, float rel)
{
    if (a.type().basetype != TypeDesc::FLOAT
        || b.type().basetype != TypeDesc::FLOAT
        || a.type().numelements() * a.type().aggregate
               != b.type().numelements() * b.type().aggregate)
        return a.get_string() == b.get_string();
    const size_t n = a.type().numelements() * a.type().aggregate;
    const float* x = static_cast<const float*>(a.data());
    const float* y = static_cast<const float*>(b.data());
    for (size_t i = 0; i < n; ++i)
        if (std::abs(x[i] - y[i])
            > rel * std::max(1.0f, std::max(std::abs(x[i]), std::abs(y[i]))))
            return false;
    return true;
}

}  // namespace


void
check_same_shot(InputFiles& files, const std::string& aux,
                const std::string& in)
{
    const ImageSpec& a = files.header(aux).spec;
    const ImageSpec& r = files.header(in).spec;
    auto refuse = [&](const std::string& what, const std::string& va,
                      const std::string& vr) {
        fail(format("aux '{}' is {} {}, but the render '{}' is {}: render "
                    "the aux from the render's shot",
                    aux, what, va, in, vr));
    };
    const ROI da(a.full_x, a.full_x + a.full_width, a.full_y,
                 a.full_y + a.full_height);
    const ROI dr(r.full_x, r.full_x + r.full_width, r.full_y,
                 r.full_y + r.full_height);
    if (!same_pixels(da, dr))
        refuse("a frame (display window) of", window_text(da),
               window_text(dr));
    // Blender writes the camera's name and the frame; Arnold, RenderMan
    // and OIIO's convention the camera's matrices; overscan and a lens
    // shift change the screen window.
    for (const char* name : { "Camera", "Frame" }) {
        const std::string va = attribute_text(a, name);
        const std::string vr = attribute_text(r, name);
        if (!va.empty() && !vr.empty() && va != vr)
            refuse(format("of {}", Strutil::lower(name)), "'" + va + "'",
                   "'" + vr + "'");
    }
    for (const char* name : { "worldToCamera", "worldToNDC",
                              "screenWindowCenter", "screenWindowWidth",
                              "PixelAspectRatio" }) {
        const ParamValue* pa = a.find_attribute(name);
        const ParamValue* pr = r.find_attribute(name);
        if (pa && pr && !same_floats(*pa, *pr, 1e-4f))
            refuse(format("of {}", name), pa->get_string(),
                   pr->get_string());
    }
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


RoleSelections
select_roles(InputFiles& files, const Job& j, bool layered)
{
    RoleSelections s;
    const InputHeader& in = files.header(j.in.path);
    const ROI noisy       = in.window();
    s.radiance = select_role(files, j.in, Role::Radiance, nullptr, "");
    if (!layered)
        s.albedo = select_role(files, j.albedo, Role::Albedo, &noisy,
                               j.in.path);
    const struct {
        OptionalRole* role;
        const InputArg* arg;
        bool disabled;
    } optional[] = { { &s.normal, &j.normal, j.no_normal },
                     { &s.depth, &j.depth, j.no_depth },
                     { &s.id, &j.id, j.no_id },
                     { &s.variance, &j.variance, false },
                     { &s.half_a, &j.half_a, false },
                     { &s.half_b, &j.half_b, false },
                     { &s.motion, &j.motion,
                       j.temporal == 0 || j.static_camera } };
    for (const auto& o : optional)
        if (o.arg->given && !o.disabled) {
            o.role->selection = select_role(files, *o.arg, o.role->role,
                                            &noisy, j.in.path);
            o.role->used      = true;
        }
    // The output takes every channel of the --in file.
    std::vector<int> all(in.channelnames.size());
    for (size_t c = 0; c < all.size(); ++c)
        all[c] = int(c);
    files.want(j.in.path, all);
    return s;
}

}  // namespace job
}  // namespace zdenoise
