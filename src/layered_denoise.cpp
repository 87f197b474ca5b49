// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// layered_denoise(): every layer denoised on its own, summed with the
// unfiltered residual (docs/FILTER.md section 11).

#include <zdenoise/zdenoise.h>

#include <limits>

#include <OpenImageIO/imagebufalgo.h>

#include "internal.h"

namespace zdenoise {

using namespace OIIO;

namespace {

/// The guides of one layer: the shared geometric guides, replaced by the
/// layer's own where it has them. The noise guides (variance, halves) are
/// the layer's own only: the shared ones describe another image's noise.
Guides
layer_guides(const Guides& shared, const Guides& own)
{
    Guides g;
    g.normal    = own.normal ? own.normal : shared.normal;
    g.depth     = own.depth ? own.depth : shared.depth;
    g.object_id = own.object_id ? own.object_id : shared.object_id;
    g.variance  = own.variance;
    g.half_a    = own.half_a;
    g.half_b    = own.half_b;
    return g;
}


/// A layer's light is never negative, but on a steep convex ramp (the
/// ceiling right next to a light) the filter's planes can extrapolate below
/// 0; in a sum of layers that shows as a dark seam. Clamp it away.
bool
clamp_negative(ImageBuf& img, ROI roi, int nthreads)
{
    return ImageBufAlgo::clamp(img, img, 0.0f,
                               std::numeric_limits<float>::max(), false, roi,
                               nthreads);
}


/// One layer's denoised radiance in roi, into `out`; `contribution` is set
/// to the image holding it (`out`, or the radiance itself when nothing is
/// to be done).
bool
denoise_layer(ImageBuf& dst, const Layer& layer, const Guides& shared,
              const FilterOptions& shared_options, FilterStats* stats, ROI roi,
              int nthreads, ImageBuf& out, const ImageBuf*& contribution)
{
    const Guides guides = layer_guides(shared, layer.guides);
    FilterOptions options = shared_options;
    if (layer.reflected)
        options.edge_k *= kReflectedEdgeScale;
    contribution = &out;
    bool ok             = true;
    if (!layer.divided) {
        if (!layer.filter) {
            contribution = layer.radiance;
            return true;
        }
        ok = denoise(out, *layer.radiance, *layer.albedo,
                     layer.remodulation_albedo, guides, options, stats, roi,
                     nthreads)
             && clamp_negative(out, roi, nthreads);
    } else {
        // Already the quotient: filter it as it is, then compose it as the
        // renderer does, albedo * quotient (no albedo_eps: Cycles divides
        // by the colour itself, and where the colour is 0 so is the pass).
        const ImageBuf* quotient = layer.radiance;
        ImageBuf filtered;
        if (layer.filter) {
            if (!regression_filter(filtered, *layer.radiance, *layer.albedo,
                                   guides, options, stats, roi, nthreads)) {
                dst.errorfmt("layered_denoise: layer '{}': {}", layer.name,
                             filtered.geterror());
                return false;
            }
            quotient = &filtered;
        }
        // A remodulation albedo replaces the colour where both are usable.
        ImageBuf effective;
        const ImageBuf* colour = layer.albedo;
        if (layer.remodulation_albedo) {
            if (!detail::remodulation_albedo(effective, *layer.albedo,
                                             *layer.remodulation_albedo,
                                             options.albedo_eps, roi)) {
                dst.errorfmt("layered_denoise: layer '{}': {}", layer.name,
                             effective.geterror());
                return false;
            }
            colour = &effective;
        }
        ok = ImageBufAlgo::mul(out, *quotient, *colour, roi, nthreads)
             && (!layer.filter || clamp_negative(out, roi, nthreads));
    }
    if (!ok) {
        dst.errorfmt("layered_denoise: layer '{}': {}", layer.name,
                     out.geterror());
        return false;
    }
    return true;
}

}  // namespace


bool
layered_denoise(ImageBuf& dst, const std::vector<Layer>& layers,
                const ImageBuf* residual, const Guides& guides,
                const FilterOptions& options, FilterStats* stats, ROI roi,
                int nthreads)
{
    const char* opname = "layered_denoise";
    if (layers.empty() || !layers[0].radiance
        || !layers[0].radiance->initialized()) {
        dst.errorfmt("{}: no layers (the first layer needs a radiance "
                     "image)",
                     opname);
        return false;
    }
    ROI image = layers[0].radiance->roi();
    image.chbegin = 0;
    image.chend   = 3;
    if (!roi.defined())
        roi = image;
    roi.chbegin = 0;
    roi.chend   = 3;
    // Every layer is filtered in the same frame: the first radiance's data
    // window unless given; the images must then hold roi and its halo.
    FilterOptions opt = options;
    if (!opt.frame.defined())
        opt.frame = image;
    if (!detail::check_frame(dst, opname, roi, opt.frame))
        return false;
    ROI need = options.frame.defined()
                   ? detail::halo_region(roi, opt.frame, filter_halo(opt))
                   : image;
    need.chbegin = 0;
    need.chend   = 3;
    for (const Layer& layer : layers) {
        const std::string radiance = "layer '" + layer.name + "' radiance";
        const std::string albedo   = "layer '" + layer.name + "' albedo";
        if (!layer.radiance || !layer.albedo) {
            dst.errorfmt("{}: layer '{}' has no {} image", opname, layer.name,
                         layer.radiance ? "albedo" : "radiance");
            return false;
        }
        if (!detail::check_input(dst, *layer.radiance, opname,
                                 radiance.c_str(), need, 3)
            || !detail::check_input(dst, *layer.albedo, opname,
                                    albedo.c_str(), need, 3))
            return false;
    }
    if (residual
        && !detail::check_input(dst, *residual, opname, "residual", roi, 3))
        return false;
    if (!dst.initialized()) {
        ImageSpec spec(image, TypeFloat);
        spec.channelnames = { "R", "G", "B" };
        dst.reset(spec);
    } else if (dst.nchannels() < 3) {
        dst.errorfmt("{}: destination has {} channels, needs 3", opname,
                     dst.nchannels());
        return false;
    }

    if (stats)
        *stats = {};
    if (residual ? !ImageBufAlgo::copy(dst, *residual, TypeUnknown, roi,
                                       nthreads)
                 : !ImageBufAlgo::zero(dst, roi, nthreads))
        return false;
    for (const Layer& layer : layers) {
        ImageBuf out;
        const ImageBuf* contribution = nullptr;
        FilterStats layer_stats;
        if (!denoise_layer(dst, layer, guides, opt, &layer_stats, roi,
                           nthreads, out, contribution))
            return false;
        if (!ImageBufAlgo::add(dst, dst, *contribution, roi, nthreads))
            return false;
        if (layer.denoised
            && !ImageBufAlgo::channels(*layer.denoised, *contribution, 3, {},
                                       {}, { "R", "G", "B" })) {
            dst.errorfmt("{}: layer '{}': {}", opname, layer.name,
                         layer.denoised->geterror());
            return false;
        }
        if (layer.stats)
            *layer.stats = layer_stats;
        if (stats && layer.filter)
            stats->merge(layer_stats);
    }
    return true;
}


ImageBuf
layered_denoise(const std::vector<Layer>& layers, const ImageBuf* residual,
                const Guides& guides, const FilterOptions& options,
                FilterStats* stats, ROI roi, int nthreads)
{
    return detail::returned_image("layered_denoise", [&](ImageBuf& result) {
        return layered_denoise(result, layers, residual, guides, options, stats, roi, nthreads);
    });
}

}  // namespace zdenoise
