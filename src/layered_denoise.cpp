// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// layered_denoise(): every layer denoised on its own, summed with the
// unfiltered residual (docs/FILTER.md section 11).

#include <zdenoise/zdenoise.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <OpenImageIO/imagebufalgo.h>

#include "checks.h"
#include "denoise.h"
#include "modulate.h"
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


/// A direct layer's quotient filtered: the regression filter over roi
/// widened by 1 (keep_structure()'s test at roi's border reads it), then
/// keep_structure() in roi. The filter's window statistics would count that
/// ring, which depends on how the frame is cut: only the kept pixels are
/// counted.
bool
filter_direct(ImageBuf& filtered, const ImageBuf& quotient,
              const ImageBuf& albedo, const Guides& guides,
              const FilterOptions& options, FilterStats* stats, ROI roi,
              int nthreads)
{
    int64_t kept = 0;
    if (!regression_filter(filtered, quotient, albedo, guides, options,
                           nullptr,
                           detail::halo_region(roi, options.frame, 1),
                           nthreads)
        || !keep_structure(filtered, quotient, filtered, guides, options.frame,
                           &kept, roi, nthreads))
        return false;
    if (stats)
        stats->kept_pixels += kept;
    return true;
}


/// A layer's quotient filtered in roi into `filtered`: filter_direct() for
/// a direct layer, else the regression filter.
bool
filter_quotient(ImageBuf& filtered, const Layer& layer,
                const ImageBuf& quotient, const Guides& guides,
                const FilterOptions& options, FilterStats* stats, ROI roi,
                int nthreads)
{
    return layer.direct
               ? filter_direct(filtered, quotient, *layer.albedo, guides,
                               options, stats, roi, nthreads)
               : regression_filter(filtered, quotient, *layer.albedo, guides,
                                   options, stats, roi, nthreads);
}


/// A direct layer of radiance (not divided): demodulated, filtered as its
/// quotient (filter_direct(), which reads one pixel beyond roi), and
/// remodulated as denoise() does, so that the test and the significance
/// filter see its light and not its texture.
bool
denoise_direct_radiance(ImageBuf& out, const Layer& layer,
                        const Guides& guides, const FilterOptions& options,
                        FilterStats* stats, ROI roi, int nthreads)
{
    return detail::denoise_through(
        out, *layer.radiance, *layer.albedo, layer.remodulation_albedo,
        options, roi, nthreads, 1,
        [&](ImageBuf& filtered, const ImageBuf& quotient,
            const FilterOptions& opt) {
            return filter_direct(filtered, quotient, *layer.albedo, guides,
                                 opt, stats, roi, nthreads);
        });
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
    // Direct light's thin shadows are structure, not noise (FILTER.md 14).
    if (layer.direct)
        options.directional_noise = 1;
    contribution = &out;
    bool ok             = true;
    if (!layer.divided) {
        if (!layer.filter) {
            contribution = layer.radiance;
            return true;
        }
        ok = (layer.direct
                  ? denoise_direct_radiance(out, layer, guides, options,
                                            stats, roi, nthreads)
                  : denoise(out, *layer.radiance, *layer.albedo,
                            layer.remodulation_albedo, guides, options,
                            stats, roi, nthreads))
             && clamp_negative(out, roi, nthreads);
    } else {
        // Already the quotient: filter it as it is, then compose it as the
        // renderer does, albedo * quotient (no albedo_eps: Cycles divides
        // by the colour itself, and where the colour is 0 so is the pass).
        const ImageBuf* quotient = layer.radiance;
        ImageBuf filtered;
        if (layer.filter) {
            if (!filter_quotient(filtered, layer, *layer.radiance, guides,
                                 options, stats, roi, nthreads)) {
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


/// Every layer has its radiance and albedo, holding `need`.
bool
check_layers(ImageBuf& dst, const std::vector<Layer>& layers, const ROI& need,
             const char* opname)
{
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
    return true;
}


/// The diagnostics of a layered denoise (FilterOptions::diagnostics): each
/// filtered layer's maps combined with weight w = its light (luminance of
/// its contribution, at least 1e-20 so that layers without light still
/// count): radius a weighted mean, noise and error the relative deviation
/// of a sum of independent parts, sqrt(sum (w e)^2) / sum w, stop the
/// reason of the layer with the most light.
class CombinedDiagnostics {
public:
    explicit CombinedDiagnostics(const ROI& roi)
        : m_roi(roi)
        , m_sums(kSums * size_t(roi.width()) * size_t(roi.height()), 0.0)
    {
    }

    bool add(const ImageBuf& maps, const ImageBuf& contribution)
    {
        const size_t npix = size_t(m_roi.width()) * size_t(m_roi.height());
        std::vector<float> m(4 * npix), rgb(3 * npix);
        ROI r4 = m_roi, r3 = m_roi;
        r4.chbegin = r3.chbegin = 0;
        r4.chend = 4;
        r3.chend = 3;
        if (!maps.get_pixels(r4, TypeFloat, m.data())
            || !contribution.get_pixels(r3, TypeFloat, rgb.data()))
            return false;
        for (size_t p = 0; p < npix; ++p) {
            const float* c = &rgb[3 * p];
            const double light = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
            const double w = std::max(std::isfinite(light) ? light : 0.0, 1e-20);
            double* s      = &m_sums[kSums * p];
            s[0] += w;
            s[1] += w * double(m[4 * p]);
            s[2] += (w * double(m[4 * p + 2])) * (w * double(m[4 * p + 2]));
            s[3] += (w * double(m[4 * p + 3])) * (w * double(m[4 * p + 3]));
            if (w > s[4]) {
                s[4] = w;
                s[5] = double(m[4 * p + 1]);
            }
        }
        return true;
    }

    bool write(ImageBuf& maps) const
    {
        const size_t npix = size_t(m_roi.width()) * size_t(m_roi.height());
        std::vector<float> m(4 * npix, 0.0f);
        for (size_t p = 0; p < npix; ++p) {
            const double* s = &m_sums[kSums * p];
            if (!(s[0] > 0.0))
                continue;
            m[4 * p]     = float(s[1] / s[0]);
            m[4 * p + 1] = float(s[5]);
            m[4 * p + 2] = float(std::sqrt(s[2]) / s[0]);
            m[4 * p + 3] = float(std::sqrt(s[3]) / s[0]);
        }
        ROI r4    = m_roi;
        r4.chbegin = 0;
        r4.chend   = 4;
        return maps.set_pixels(r4, TypeFloat, m.data());
    }

private:
    /// Per pixel: sum w, sum w radius, sum (w noise)^2, sum (w error)^2,
    /// the largest w and its layer's stop code.
    static constexpr size_t kSums = 6;
    ROI m_roi;
    std::vector<double> m_sums;
};

}  // namespace


bool
layered_denoise(ImageBuf& dst, const std::vector<Layer>& layers,
                const ImageBuf* residual, const Guides& guides,
                const FilterOptions& options, FilterStats* stats, ROI roi,
                int nthreads)
{
    const char* opname = "layered_denoise";
    const bool dst_was_given = dst.initialized();
    if (detail::cancel_requested(options))
        return detail::cancelled(dst, dst_was_given, roi, nthreads);
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
    const bool any_direct = std::any_of(layers.begin(), layers.end(),
                                        [](const Layer& l) {
                                            return l.direct && l.filter;
                                        });
    ROI need = options.frame.defined()
                   ? detail::halo_region(roi, opt.frame,
                                         filter_halo(opt) + (any_direct ? 1 : 0))
                   : image;
    need.chbegin = 0;
    need.chend   = 3;
    if (!check_layers(dst, layers, need, opname))
        return false;
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
    // Each layer's maps go to an image of its own, combined at the end.
    if (options.diagnostics
        && !detail::prepare_diagnostics(dst, *options.diagnostics, roi,
                                        opt.frame, opname))
        return false;
    CombinedDiagnostics combined(options.diagnostics ? roi : ROI(0, 0, 0, 0));
    for (size_t k = 0; k < layers.size(); ++k) {
        const Layer& layer = layers[k];
        ImageBuf out, layer_maps;
        const ImageBuf* contribution = nullptr;
        FilterStats layer_stats;
        FilterOptions layer_opt = opt;
        // Each layer's filter reports 0 to 1: its share of the whole, so
        // that the progress never goes back.
        if (options.progress)
            layer_opt.progress = [&options, k, n = layers.size()](float f) {
                options.progress((float(k) + f) / float(n));
            };
        layer_opt.diagnostics   = options.diagnostics && layer.filter
                                      ? &layer_maps
                                      : nullptr;
        layer_opt.hat_diagonal  = nullptr;  // one per layer: not combined
        // Each layer's filter stops within when cancelled; the rest of the
        // layers are not begun.
        const bool layer_done = denoise_layer(dst, layer, guides, layer_opt,
                                              &layer_stats, roi, nthreads, out,
                                              contribution);
        if (detail::cancel_requested(options))
            return detail::cancelled(dst, dst_was_given, roi, nthreads);
        if (!layer_done)
            return false;
        if (layer_opt.diagnostics
            && !combined.add(layer_maps, *contribution)) {
            dst.errorfmt("{}: layer '{}': diagnostics: {}", opname,
                         layer.name, layer_maps.geterror());
            return false;
        }
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
    if (options.diagnostics && !combined.write(*options.diagnostics)) {
        dst.errorfmt("{}: diagnostics: {}", opname,
                     options.diagnostics->geterror());
        return false;
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
