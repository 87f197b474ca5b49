// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "albedo_plan.h"

#include <algorithm>

#include <OpenImageIO/strutil.h>

#include "failure.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// The samples per pixel a Cycles file records for the layer `sel` is of
/// (cycles.<view layer>.samples), or the only count the file has (a file
/// of one layer, its names unprefixed); 0 when unknown. `name` gets the
/// attribute's name.
int
cycles_samples(InputFiles& files, const Selection& sel, std::string& name)
{
    const InputHeader& h     = files.header(sel.path);
    const std::string& first = h.channelnames[size_t(sel.indices[0])];
    const std::string own    = "cycles." + first.substr(0, first.find('.'))
                            + ".samples";
    std::vector<std::pair<std::string, int>> counts;
    for (const ImageSpec& spec : h.specs)
        for (const ParamValue& v : spec.extra_attribs) {
            const std::string n = v.name().string();
            if (Strutil::starts_with(n, "cycles.")
                && Strutil::ends_with(n, ".samples"))
                counts.emplace_back(n, Strutil::stoi(v.get_string()));
        }
    for (const auto& [n, count] : counts)
        if (count >= 1 && (n == own || counts.size() == 1)) {
            name = n;
            return count;
        }
    return 0;
}

}  // namespace


std::string
AlbedoPlan::describe() const
{
    std::string s;
    if (pool)
        s += format(" aux-pooled={}/{}", pool_options.render_samples,
                    pool_options.aux_samples);
    if (prefilter)
        s += format(" albedo-samples={}{}", prefilter,
                    halves ? " albedo-halves" : "");
    return s;
}


/// With --halves whose files have an albedo of their own (Cycles' Denoising
/// Albedo), the prefilter of the --in file's albedo takes its variance from
/// them as well (prefilter_albedo(), docs/FILTER.md section 12): measured
/// where the model only guesses.
void
use_halves_albedos(const Job& j, InputFiles& files, RoleSelections& roles,
                   const ROI& noisy, AlbedoPlan& a,
                   std::vector<std::string>& log)
{
    if (!a.prefilter || !roles.half_a.used || roles.albedo.path != j.in.path)
        return;
    const std::string named_a
        = detect_convention(files.header(j.half_a.path).channelnames).albedo;
    const std::string named_b
        = detect_convention(files.header(j.half_b.path).channelnames).albedo;
    if (named_a.empty() || named_b.empty())
        return;
    roles.half_a_albedo.selection = select_role(
        files, { j.half_a.path, named_a, true }, Role::Albedo, &noisy, j.in.path);
    roles.half_b_albedo.selection = select_role(
        files, { j.half_b.path, named_b, true }, Role::Albedo, &noisy, j.in.path);
    roles.half_a_albedo.used = roles.half_b_albedo.used = true;
    a.halves = true;
    log.push_back("  albedo    its noise also measured from the halves' albedos "
                  "(" + named_a + ")");
}


AlbedoPlan
plan_albedo(const Job& j, InputFiles& files, const Convention& conv,
            RoleSelections& roles, const ROI& noisy,
            std::vector<std::string>& log)
{
    AlbedoPlan a;
    std::string name;
    const bool from_aux = j.aux.given && j.albedo.path == j.aux.path;
    if (from_aux && !conv.albedo.empty()
        && j.aux_demodulation == AuxDemodulation::Aux) {
        roles.own_albedo.selection
            = select_role(files, { j.in.path, conv.albedo, true },
                          Role::Albedo, &noisy, j.in.path);
        roles.own_albedo.used = true;
        a.pool                = true;
        const int nr = j.albedo_samples > 0
                           ? j.albedo_samples
                           : cycles_samples(files, roles.own_albedo.selection,
                                            name);
        const int na = cycles_samples(files, roles.albedo, name);
        a.pool_options.render_samples = std::max(nr, 1);
        a.pool_options.aux_samples    = na;
        log.push_back(format(
            "  albedo    the aux's ({}) checked against the render's own ({}) "
            "and pooled with it where they agree",
            na ? format("{} samples", na) : std::string("noise-free"),
            nr ? format("{} samples", nr)
               : std::string("samples unknown: taken as 1")));
        // A noise-free aux albedo needs no prefilter; one of N samples
        // pooled with the render's is one of about their sum.
        if (!j.no_albedo_prefilter && na > 0)
            a.prefilter = a.pool_options.render_samples + na;
        if (a.prefilter)
            log.push_back(format("  albedo    prefiltered as {} samples a "
                                 "pixel (the two pooled)",
                                 a.prefilter));
        return a;
    }
    if (j.no_albedo_prefilter) {
        log.push_back("  albedo    not prefiltered (--no-albedo-prefilter)");
        return a;
    }
    if (j.albedo_samples > 0) {
        log.push_back(format("  albedo    prefiltered as {} samples a pixel "
                             "(--albedo-samples)",
                             j.albedo_samples));
        a.prefilter = j.albedo_samples;
        use_halves_albedos(j, files, roles, noisy, a, log);
        return a;
    }
    if (j.aux.given || roles.albedo.path != j.in.path)
        return a;  // a clean image, or one the user chose: as it is
    a.prefilter = cycles_samples(files, roles.albedo, name);
    log.push_back(a.prefilter
                      ? format("  albedo    prefiltered as {} samples a "
                               "pixel ({})",
                               a.prefilter, name)
                      : std::string("  albedo    not prefiltered: its samples "
                                    "per pixel are not in the file (give "
                                    "--albedo-samples N)"));
    use_halves_albedos(j, files, roles, noisy, a, log);
    return a;
}


AlbedoPlan
plan_layer_colours(const Job& j, InputFiles& files, LayersPlan& layers,
                   std::vector<std::string>& log)
{
    AlbedoPlan a;
    std::vector<LayersPlan::One*> own;
    for (LayersPlan::One& one : layers.layers) {
        const bool from_in = !one.albedo.empty()
                             && std::all_of(one.albedo.begin(), one.albedo.end(),
                                            [&](const Selection& s) {
                                                return s.path == j.in.path;
                                            });
        if (from_in && one.remodulation.empty())
            own.push_back(&one);
    }
    if (own.empty())
        return a;
    if (j.no_albedo_prefilter) {
        log.push_back("  colours   not prefiltered (--no-albedo-prefilter)");
        return a;
    }
    std::string name = "--albedo-samples";
    a.prefilter = j.albedo_samples > 0
                      ? j.albedo_samples
                      : cycles_samples(files, own.front()->albedo.front(), name);
    if (!a.prefilter) {
        log.push_back("  colours   not prefiltered: their samples per pixel are "
                      "not in the file (give --albedo-samples N)");
        return a;
    }
    std::string names;
    for (LayersPlan::One* one : own) {
        one->prefilter = a.prefilter;
        names += (names.empty() ? "" : ", ") + one->name;
    }
    log.push_back(format("  colours   prefiltered as {} samples a pixel ({}): {}",
                         a.prefilter, name, names));
    return a;
}


void
make_albedo(const AlbedoPlan& a, ImageBuf& albedo, ImageBuf& own,
            const ImageBuf& half_a, const ImageBuf& half_b,
            const ROI& region, const ROI& core,
            int threads, AuxAlbedoStats& totals, const std::string& path)
{
    auto prefilter = [&](ImageBuf& img, int samples) {
        if (!samples)
            return;
        ImageBuf clean;
        if (!(a.halves ? prefilter_albedo(clean, img, samples, half_a, half_b,
                                          region, threads)
                       : prefilter_albedo(clean, img, samples, region, threads)))
            fail(format("'{}': {}", path, one_line(clean.geterror())));
        img = std::move(clean);
    };
    if (a.pool) {
        // Over what the prefilter reads of it.
        ROI pooled_roi = region;
        if (a.prefilter) {
            const int h = albedo_prefilter_halo();
            pooled_roi  = roi_intersection(ROI(region.xbegin - h,
                                               region.xend + h,
                                               region.ybegin - h,
                                               region.yend + h),
                                           albedo.roi());
        }
        AuxAlbedoOptions o = a.pool_options;
        o.counted          = core;
        ImageBuf pooled;
        AuxAlbedoStats st;
        if (!pool_aux_albedo(pooled, albedo, own, o, &st, pooled_roi,
                             threads))
            fail(format("'{}': {}", path, one_line(pooled.geterror())));
        albedo = std::move(pooled);
        totals.pixels += st.pixels;
        totals.rejected += st.rejected;
    }
    prefilter(albedo, a.prefilter);
    // A swap, not a move: OIIO 2.4 leaves a moved-from ImageBuf without
    // its implementation, and its reset() then crashes.
    ImageBuf().swap(own);
}


std::string
pooled_summary(const AuxAlbedoStats& totals)
{
    const double share = totals.pixels ? 100.0 * double(totals.rejected)
                                             / double(totals.pixels)
                                       : 0.0;
    return format("  albedo    the render's own used at {} pixels ({:.2f} %): "
                  "the aux's disagrees there beyond their noise",
                  totals.rejected, share);
}

}  // namespace job
}  // namespace zdenoise
