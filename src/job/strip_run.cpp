// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "strip_run.h"

#include <functional>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/strutil.h>
#include <OpenImageIO/timer.h>

#include "alpha_plan.h"
#include "failure.h"
#include "layers_plan.h"
#include "light_groups_plan.h"
#include "output.h"
#include "strips.h"
#include "temporal_strip.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// The filter's run on strip `s` (of `strips`) into `denoised` (and the
/// maps, with their statistics into `st`): over the strip's rows, and,
/// when light groups or AOVs are split, over split_reach() rows above and
/// below it too (each a run of its own, so that the statistics stay the
/// strip's and the result is what one run over all the rows gives).
void
filter_strip(const Job& j, const Plan& p, int s, int strips, const Strip& strip,
             RoleImages& img, const Guides& guides, std::vector<Layer>& layers,
             LoadedLayers& loaded, ImageBuf& denoised, ImageBuf& maps,
             FilterStats& st)
{
    FilterOptions options = j.filter;
    options.frame         = p.noisy;
    if (j.filter.progress)
        options.progress = [&](float f) {
            j.filter.progress((float(s) + f) / float(strips));
        };
    if (p.maps)
        options.diagnostics = &maps;
    const ROI wide = strip.widened(split_reach(p.groups, p.aovs));
    if (wide != strip.core) {
        // One image over all the rows, which the runs below fill in parts.
        ImageSpec spec(ROI(wide.xbegin, wide.xend, wide.ybegin, wide.yend, 0, 1, 0,
                           img.radiance.nchannels()),
                       TypeFloat);
        spec.full_x      = p.noisy.xbegin;
        spec.full_y      = p.noisy.ybegin;
        spec.full_width  = p.noisy.width();
        spec.full_height = p.noisy.height();
        denoised.reset(spec);
    }
    auto run = [&](const ROI& roi, FilterStats* stats) {
        return p.layered
                   ? layered_denoise(denoised, layers,
                                     loaded.residual.initialized() ? &loaded.residual
                                                                   : nullptr,
                                     guides, options, stats, roi, j.threads)
                   : denoise(denoised, img.radiance, img.albedo,
                             p.roles.remodulation.used ? &img.remodulation : nullptr,
                             guides, options, stats, roi, j.threads);
    };
    bool ok = run(strip.core, &st);
    options.progress    = nullptr;
    options.diagnostics = nullptr;
    const ROI above(wide.xbegin, wide.xend, wide.ybegin, strip.core.ybegin);
    const ROI below(wide.xbegin, wide.xend, strip.core.yend, wide.yend);
    for (const ROI& band : { above, below })
        if (ok && band.height() > 0)
            ok = run(band, nullptr);
    if (!ok)
        fail(format("denoising '{}' failed: {}", j.in.path,
                    one_line(denoised.geterror())));
}


}  // namespace


void
run_strip(const Job& j, Plan& p, InputFiles& files, int s,
          JobResult& result, std::vector<FilterStats>& layer_stats)
{
    Timer strip_read;
    Strip strip;
    strip.files   = &files;
    strip.threads = j.threads;
    strip.place(p.noisy, s, result.strip_rows, p.around);
    for (const std::string& path : files.paths()) {
        std::string err;
        if (!files.rows(path).hold(strip.held.ybegin, strip.held.yend,
                                   j.threads, err))
            fail(format("cannot read '{}': {}", path, one_line(err)));
    }
    const RoleSelections& roles = p.roles;
    RoleImages img = read_role_images(j, p, strip);
    const bool alpha = denoised_alpha_channel(j, roles.radiance) >= 0;
    const ImageBuf held_alpha = alpha ? strip_alpha(j, img.radiance) : ImageBuf();
    // Over what the filter reads: the strip and its halo (and with
    // --temporal, the light test's box around it; with light groups, the
    // rows beyond the strip that their split reads).
    if (!p.layered)  // the layers' colours: load_layers()
        make_albedo(p.albedo, img.albedo, img.own_albedo, img.half_a_albedo,
                    img.half_b_albedo,
                    strip.widened(filter_halo(j.filter) + temporal_reach(j)
                                  + split_reach(p.groups, p.aovs)),
                    strip.core, j.threads, p.pooled, j.albedo.path);
    if (j.temporal > 0)
        combine_neighbours(j, p, files, strip, img, result);
    auto guide = [](const OptionalRole& o, const ImageBuf& image) {
        return o.used ? &image : nullptr;
    };
    Guides guides;
    guides.normal    = guide(roles.normal, img.normal);
    guides.depth     = guide(roles.depth, img.depth);
    guides.object_id = guide(roles.id, img.id);
    guides.variance  = guide(roles.variance, img.variance);
    guides.half_a    = guide(roles.half_a, img.half_a);
    guides.half_b    = guide(roles.half_b, img.half_b);
    LoadedLayers loaded;
    std::vector<Layer> layers;
    if (p.layered)
        layers = load_layers(strip, p.layers, j, img.radiance, loaded);
    result.read_seconds += strip_read();

    Timer denoise_timer;
    ImageBuf denoised, maps;
    FilterStats st;
    filter_strip(j, p, s, result.strips, strip, img, guides, layers, loaded,
                 denoised, maps, st);
    ImageBuf denoised_alpha;
    if (alpha)
        denoise_strip_alpha(j, strip, p.noisy, held_alpha, guides,
                            denoised_alpha);
    std::vector<ImageBuf> groups;
    if (!p.groups.empty())
        groups = denoise_strip_light_groups(
            j, p.groups, strip, p.noisy, denoised, img.radiance, guides,
            [&](ImageBuf& g) {
                convert_role(p, g, p.spaces.input, p.spaces.working, j.in);
            });
    std::vector<ImageBuf> aovs;
    if (!p.aovs.empty())
        aovs = denoise_strip_aovs(j, p.aovs, strip, p.noisy, denoised,
                                  img.radiance, guides,
                                  [&](ImageBuf& a) {
                                      convert_role(p, a, p.spaces.input,
                                                   p.spaces.working, j.in);
                                  });
    result.denoise_seconds += denoise_timer();
    // Statistics summed over the strips (exact sums: they do not depend
    // on the strips).
    result.stats.merge(st);
    layer_stats.resize(loaded.stats.size());
    for (size_t i = 0; i < loaded.stats.size(); ++i)
        layer_stats[i].merge(loaded.stats[i]);

    Timer write_timer;
    convert_role(p, denoised, p.spaces.working, p.spaces.output, j.in);
    std::vector<const ImageBuf*> images = { &denoised };
    for (const ImageBuf& l : loaded.denoised)
        images.push_back(&l);
    if (j.diagnostics)
        images.push_back(&maps);  // at diagnostics_image(p.layers)
    if (alpha)
        images.push_back(&denoised_alpha);  // at alpha_image(j, p.layers)
    for (ImageBuf& g : groups) {  // at light_group_image()
        convert_role(p, g, p.spaces.working, p.spaces.output, j.in);
        images.push_back(&g);
    }
    for (ImageBuf& a : aovs) {  // after the groups: layout_output()
        convert_role(p, a, p.spaces.working, p.spaces.output, j.in);
        images.push_back(&a);
    }
    if (!j.diagnostics_png.empty() && !p.picture.keep(maps, strip.core))
        fail(format("--diagnostics-png: {}", one_line(maps.geterror())));
    p.output.write(strip, files.rows(j.in.path), images, j.threads);
    result.write_seconds += write_timer();
}

}  // namespace job
}  // namespace zdenoise
