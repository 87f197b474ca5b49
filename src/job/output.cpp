// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "output.h"

#include <algorithm>
#include <cstring>
#include <memory>

#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include "alpha_plan.h"
#include "failure.h"
#include "internal.h"
#include "layer_conventions.h"
#include "pixel_moves.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// Write `rgb` (3 channels, the denoised image `image`) into the output
/// channels `names`, appending those that do not exist (in pixel type
/// `type`) with the output spec's metadata kept.
void
put_channels(ImageSpec& spec, std::vector<OutputChannel>& channels,
             int image, const std::vector<std::string>& names, TypeDesc type)
{
    for (int c = 0; c < int(names.size()); ++c) {
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

}  // namespace


void
layout_output(const Job& j, const InputHeader& in, const Selection& radiance,
              const LayersPlan& layers, const LightGroupPlan& groups,
              const AovPlan& aovs, ImageSpec& spec,
              std::vector<OutputChannel>& channels,
              std::vector<TypeDesc>& formats)
{
    spec = output_spec(in);
    channels.resize(in.channelnames.size());
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
        for (size_t i = 0; i < layers.layers.size(); ++i) {
            const std::string& n = layers.layers[i].name;
            put_channels(spec, channels, int(i) + 1,
                         { n + ".R", n + ".G", n + ".B" }, beauty_type);
        }
    if (j.diagnostics) {
        std::vector<std::string> maps;
        for (const std::string& n : diagnostic_channels())
            maps.push_back(std::string(kDiagnosticsLayer) + "." + n);
        put_channels(spec, channels, diagnostics_image(layers), maps,
                     TypeFloat);
    }
    const int alpha = denoised_alpha_channel(j, radiance);
    if (alpha >= 0)
        channels[size_t(alpha)] = { -1, alpha_image(j, layers), 0,
                                    in.format(alpha) };
    for (size_t k = 0; k < groups.channels.size(); ++k)
        for (int c = 0; c < 3; ++c) {
            const int i = groups.channels[k].indices[size_t(c)];
            channels[size_t(i)] = { -1, light_group_image(j, layers, radiance, k),
                                    c, in.format(i) };
        }
    const int first_aov = light_group_image(j, layers, radiance, groups.names.size());
    for (size_t k = 0; k < aovs.channels.size(); ++k)
        for (int c = 0; c < 3; ++c) {
            const int i = aovs.channels[k].indices[size_t(c)];
            channels[size_t(i)] = { -1, first_aov + int(k), c, in.format(i) };
        }
    formats = write_formats(spec, channels, j.data_type);
}


int
diagnostics_image(const LayersPlan& layers)
{
    return 1 + int(layers.layers.size());
}


int
alpha_image(const Job& j, const LayersPlan& layers)
{
    return diagnostics_image(layers) + (j.diagnostics ? 1 : 0);
}


int
light_group_image(const Job& j, const LayersPlan& layers,
                  const Selection& radiance, size_t k)
{
    return alpha_image(j, layers)
           + (denoised_alpha_channel(j, radiance) >= 0 ? 1 : 0) + int(k);
}


ImageSpec
native_spec(const ImageSpec& spec, const std::vector<TypeDesc>& formats)
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
    return s;
}


void
Output::set_row_types(bool float_rows)
{
    pixel_bytes = 0;
    for (const OutputChannel& c : channels) {
        row_types.push_back(float_rows ? TypeFloat : c.type);
        offset.push_back(pixel_bytes);
        pixel_bytes += row_types.back().size();
    }
}


void
Output::write(const Strip& strip, const RowReader& in,
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
         y0 += kBandRows) {
        const int y1 = std::min(y0 + kBandRows, core.yend);
        band.resize(row_bytes * size_t(y1 - y0));
        parallel_for(int64_t(y0), int64_t(y1), [&](int64_t y) {
            unsigned char* row = band.data() + size_t(y - y0) * row_bytes;
            for (const Run& r : runs)
                move_channels(in.at(r.file, core.xbegin, int(y)),
                              in.format(r.file), in.stride(r.file),
                              row + offset[size_t(r.first)],
                              row_types[size_t(r.first)],
                              stride_t(pixel_bytes), r.count, width);
        }, detail::paropt_any_length(threads));
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


}  // namespace job
}  // namespace zdenoise
