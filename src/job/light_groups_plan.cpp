// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "light_groups_plan.h"

#include <OpenImageIO/strutil.h>

#include <zdenoise/light_groups.h>

#include "failure.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// The channel called `name` in `names`, or -1.
int
index_of(const std::vector<std::string>& names, const std::string& name)
{
    for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == name)
            return int(i);
    return -1;
}

/// "ViewLayer.Combined" and "R" of "ViewLayer.Combined.R".
bool
split_name(const std::string& channel, std::string& layer, std::string& comp)
{
    const size_t dot = channel.rfind('.');
    if (dot == std::string::npos || dot == 0)
        return false;
    layer = channel.substr(0, dot);
    comp  = channel.substr(dot + 1);
    return true;
}

}  // namespace


LightGroupPlan
plan_light_groups(const Job& j, const InputHeader& in, const Selection& radiance,
                  std::vector<std::string>& log)
{
    LightGroupPlan plan;
    const std::vector<std::string>& names = in.channelnames;
    std::string beauty, comp[3];
    for (int c = 0; c < 3; ++c) {
        const std::string& n = names[size_t(radiance.indices[size_t(c)])];
        std::string layer;
        if (!split_name(n, layer, comp[c])) {
            // A plain R, G, B beauty (Arnold's): its groups are RGBA_<group>.
            layer   = "RGBA";
            comp[c] = n;
        }
        if (c > 0 && layer != beauty)
            return plan;
        beauty = layer;
    }
    const std::string prefix = beauty + "_";
    for (const std::string& n : names) {
        std::string layer, first;
        if (!split_name(n, layer, first) || first != comp[0]
            || !Strutil::starts_with(layer, prefix) || layer.size() == prefix.size())
            continue;
        Selection s;
        s.path = radiance.path;
        for (int c = 0; c < 3; ++c) {
            const int i = index_of(names, layer + "." + comp[c]);
            if (i < 0)
                break;
            s.indices.push_back(i);
            s.names.push_back(std::string(1, "RGB"[c]));
        }
        if (s.indices.size() != 3)
            continue;
        plan.names.push_back(layer.substr(prefix.size()));
        plan.channels.push_back(s);
    }
    if (plan.empty())
        return plan;
    const std::string list = Strutil::join(plan.names, ", ");
    const char* why = j.no_light_groups ? "--no-light-groups"
                      : j.temporal > 0  ? "--temporal"
                                        : nullptr;
    if (why) {
        log.push_back(format("  light groups {} copied as they are ({})", list, why));
        return LightGroupPlan();
    }
    log.push_back(format("  light groups {} split from the denoised beauty "
                         "(--no-light-groups copies them)",
                         list));
    return plan;
}


int
light_groups_reach(const LightGroupPlan& groups)
{
    return groups.empty() ? 0 : light_groups_halo();
}


Guides
surface_guides(const Guides& guides)
{
    Guides g;
    g.normal    = guides.normal;
    g.depth     = guides.depth;
    g.object_id = guides.object_id;
    return g;
}


std::vector<ImageBuf>
split_from_beauty(const Job& j, const ROI& frame, const ImageBuf& denoised,
                  const ImageBuf& radiance,
                  const std::vector<const ImageBuf*>& parts,
                  const Guides& guides, const ROI& roi, const std::string& what)
{
    const Guides g        = surface_guides(guides);
    FilterOptions options = j.filter;
    options.frame         = frame;
    std::vector<ImageBuf> out;
    if (!split_light_groups(out, denoised, radiance, parts, g, options, {}, roi,
                            j.threads))
        fail(format("{} of '{}': {}", what, j.in.path,
                    one_line(out[0].geterror())));
    return out;
}


std::vector<ImageBuf>
denoise_strip_light_groups(const Job& j, const LightGroupPlan& groups,
                           const Strip& strip, const ROI& frame,
                           const ImageBuf& denoised, const ImageBuf& radiance,
                           const Guides& guides,
                           const std::function<void(ImageBuf&)>& convert)
{
    std::vector<ImageBuf> noisy(groups.names.size());
    std::vector<const ImageBuf*> given;
    for (size_t k = 0; k < noisy.size(); ++k) {
        noisy[k] = strip.image(groups.channels[k], false);
        convert(noisy[k]);
        given.push_back(&noisy[k]);
    }
    return split_from_beauty(j, frame, denoised, radiance, given, guides,
                             strip.core, "the light groups");
}

}  // namespace job
}  // namespace zdenoise
