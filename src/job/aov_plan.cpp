// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "aov_plan.h"

#include <algorithm>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>

#include <zdenoise/light_groups.h>

#include "failure.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// The R, G, B channels of layer `layer` in `names`, or an empty list.
std::vector<int>
rgb_of(const std::vector<std::string>& names, const std::string& layer)
{
    std::vector<int> found;
    for (const char* c : { ".R", ".G", ".B" }) {
        const auto at = std::find(names.begin(), names.end(), layer + c);
        if (at == names.end())
            return {};
        found.push_back(int(at - names.begin()));
    }
    return found;
}

/// "ViewLayer." of the beauty channel "ViewLayer.Combined.R"; "" for a
/// beauty with no view layer ("Combined.R", "R").
std::string
view_layer_prefix(const std::string& beauty)
{
    const size_t last = beauty.rfind('.');
    const size_t layer = last == std::string::npos || last == 0
                             ? std::string::npos
                             : beauty.rfind('.', last - 1);
    return layer == std::string::npos ? std::string() : beauty.substr(0, layer + 1);
}

/// Why channel `c` may not be an AOV (the beauty's, a group's), or null.
const char*
taken(int c, const Selection& radiance, const LightGroupPlan& groups)
{
    auto in = [c](const Selection& s) {
        return std::find(s.indices.begin(), s.indices.end(), c) != s.indices.end();
    };
    if (in(radiance))
        return "the beauty";
    for (const Selection& g : groups.channels)
        if (in(g))
            return "a light group (denoised by default)";
    return nullptr;
}

}  // namespace


AovPlan
plan_aovs(const Job& j, const InputHeader& in, const Selection& radiance,
          const LightGroupPlan& groups, std::vector<std::string>& log)
{
    AovPlan plan;
    if (j.aovs.empty())
        return plan;
    if (j.temporal > 0)
        fail("--aov: not available with --temporal (the AOVs are not "
             "combined across frames)");
    const std::vector<std::string>& names = in.channelnames;
    const std::string prefix
        = view_layer_prefix(names[size_t(radiance.indices[0])]);
    for (const std::string& aov : j.aovs) {
        std::string layer = aov;
        std::vector<int> rgb = rgb_of(names, layer);
        if (rgb.empty() && !prefix.empty()) {
            layer = prefix + aov;
            rgb   = rgb_of(names, layer);
        }
        if (rgb.empty())
            fail(format("--aov {}: '{}' has no channels {}.R,G,B{}", aov,
                        j.in.path, aov,
                        prefix.empty() ? "" : " or " + prefix + aov + ".R,G,B"));
        if (const char* why = taken(rgb[0], radiance, groups))
            fail(format("--aov {}: {} is {}", aov, layer, why));
        if (std::find(plan.names.begin(), plan.names.end(), layer)
            != plan.names.end())
            fail(format("--aov {}: {} is given twice", aov, layer));
        Selection s;
        s.path    = j.in.path;
        s.indices = rgb;
        s.names   = { "R", "G", "B" };
        plan.names.push_back(layer);
        plan.channels.push_back(s);
    }
    log.push_back(format("  aovs      {} split from the denoised beauty "
                         "(--aov); other channels copied",
                         Strutil::join(plan.names, ", ")));
    return plan;
}


int
aovs_reach(const AovPlan& aovs)
{
    // keep_structure() reads the split one pixel beyond the strip.
    return aovs.empty() ? 0 : light_groups_halo() + 1;
}


int
split_reach(const LightGroupPlan& groups, const AovPlan& aovs)
{
    return std::max(light_groups_reach(groups), aovs_reach(aovs));
}


std::vector<ImageBuf>
denoise_strip_aovs(const Job& j, const AovPlan& aovs, const Strip& strip,
                   const ROI& frame, const ImageBuf& denoised,
                   const ImageBuf& radiance, const Guides& guides,
                   const std::function<void(ImageBuf&)>& convert)
{
    // Each AOV is light the beauty holds (an emission, a volume, an LPE):
    // split from the denoised beauty as a light group of its own, the rest
    // of the beauty the other part. So it keeps the texture and the edges
    // that the beauty's denoise kept, a clean AOV keeps its window mean,
    // and the denoised beauty minus the AOV is never negative. What the AOV
    // holds beyond the beauty is its pixel's own, as it is. keep_structure()
    // then gives back what the AOV shows beyond its noise, and leaves a
    // noise-free pixel as rendered (a clean emitter's or sky's: the split
    // carried light across their edges, Emit at 64 spp 17x the input's).
    const Guides g = surface_guides(guides);
    std::vector<ImageBuf> out(aovs.names.size());
    for (size_t k = 0; k < out.size(); ++k) {
        ImageBuf light = strip.image(aovs.channels[k], false);
        convert(light);
        const std::vector<ImageBuf> split
            = split_from_beauty(j, frame, denoised, radiance, { &light }, guides,
                                strip.widened(1), "the AOV " + aovs.names[k]);
        if (!keep_structure(out[k], light, split[0], g, frame, nullptr,
                            strip.core, j.threads))
            fail(format("denoising the AOV {} of '{}' failed: {}",
                        aovs.names[k], j.in.path, one_line(out[k].geterror())));
    }
    return out;
}

}  // namespace job
}  // namespace zdenoise
