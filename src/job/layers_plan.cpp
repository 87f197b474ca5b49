// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "layers_plan.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imagebufalgo_util.h>
#include <OpenImageIO/parallel.h>
#include <OpenImageIO/strutil.h>

#include "internal.h"
#include "failure.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// route_direct_light()'s pools: the 17x17 around each pixel.
constexpr int kPool = 8;

/// How far route_direct_light() looks: the noise estimate, the pooled
/// decision, and the share pooled again.
int
route_reach()
{
    return noise_variance_halo() + 2 * kPool;
}

/// Whether any of the n elements within r of each element (the window
/// clipped at both ends, `stride` apart) is set: a running count, so that
/// its cost does not grow with r.
void
any_within(const uint8_t* in, uint8_t* out, int n, size_t stride, int r)
{
    int count = 0;  // set elements in [i - r, i + r]
    for (int i = 0; i < std::min(r, n); ++i)
        count += in[size_t(i) * stride];
    for (int i = 0; i < n; ++i) {
        if (i + r < n)
            count += in[size_t(i + r) * stride];
        if (i - r - 1 >= 0)
            count -= in[size_t(i - r - 1) * stride];
        out[size_t(i) * stride] = count > 0;
    }
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
    const ROI all = albedo.roi();
    const int w = all.width(), h = all.height();
    std::vector<uint8_t> real(size_t(w) * size_t(h)), rows(real.size()),
        near_real(real.size());
    ImageBufAlgo::parallel_image(
        all, paropt(nthreads), [&](ROI roi) {
            roi.chbegin = 0;
            roi.chend   = 3;
            ImageBuf::ConstIterator<float> r(residual, roi), b(beauty, roi);
            for (; !r.done(); ++r, ++b) {
                float res = 0.0f, total = 0.0f;
                for (int c = 0; c < 3; ++c) {
                    res   = std::max(res, std::fabs(r[c]));
                    total = std::max(total, std::fabs(b[c]));
                }
                real[size_t(r.y() - all.ybegin) * size_t(w) + size_t(r.x() - all.xbegin)]
                    = res > kNegligible * total;
            }
        });
    // Near a real residual: within `reach` in x and in y (a square),
    // rows then columns.
    parallel_for(int64_t(0), int64_t(h), [&](int64_t y) {
        const size_t row = size_t(y) * size_t(w);
        any_within(&real[row], &rows[row], w, 1, reach);
    }, detail::paropt_any_length(nthreads));
    parallel_for(int64_t(0), int64_t(w), [&](int64_t x) {
        any_within(&rows[size_t(x)], &near_real[size_t(x)], h, size_t(w), reach);
    }, detail::paropt_any_length(nthreads));
    ImageBufAlgo::parallel_image(
        all, paropt(nthreads), [&](ROI roi) {
            for (ImageBuf::Iterator<float> a(albedo, roi); !a.done(); ++a)
                if (!near_real[size_t(a.y() - all.ybegin) * size_t(w)
                               + size_t(a.x() - all.xbegin)])
                    for (int c = roi.chbegin; c < roi.chend; ++c)
                        a[c] = 0.0f;
        });
}


}  // namespace


std::string
auto_path_blocker(const Job& j)
{
    const struct {
        bool given;
        const char* option;
    } beauty_options[] = {
        { !j.layers.empty(), "--layer" },
        { j.albedo.given, "--albedo" },
        { j.aux.given, "--aux" },
        { j.variance.given, "--variance" },
        { j.half_a.given || j.half_b.given, "--halves" },
        { j.temporal > 0, "--temporal" },
        // Layers are filtered in the input's colour space (plan_colour()).
        { j.colour.any_given(), "a colour space or config" },
    };
    for (const auto& o : beauty_options)
        if (o.given)
            return o.option;
    return "";
}


const std::vector<LayerArg>&
choose_layers(const Job& j, const Convention& conv,
              const std::string& auto_path_blocker, bool& path, bool& layered)
{
    if (j.mode == Mode::Path && conv.direct_layers.empty())
        fail(format("--mode path: '{}' has no direct light pass apart (Cycles' "
                    "DiffDir with DiffCol and Denoising Albedo, or Arnold's "
                    "diffuse_direct with diffuse_albedo and albedo; "
                    "docs/LAYERS.md)",
                    j.in.path));
    path = j.mode == Mode::Path
           || (j.mode == Mode::Auto && auto_path_blocker.empty()
               && !conv.direct_layers.empty());
    const std::vector<LayerArg>& layer_args
        = path ? conv.direct_layers : (j.layers.empty() ? conv.layers : j.layers);
    if (j.mode == Mode::Layers && layer_args.empty())
        fail(format("--mode layers: no layers found in '{}' (see "
                    "docs/LAYERS.md); give them with --layer",
                    j.in.path));
    layered = path || j.mode == Mode::Layers
              || (j.mode == Mode::Auto && !j.layers.empty());
    return layer_args;
}


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
        one.direct    = a.direct;
        one.radiance = select_sum(files, j.in.path, a.radiance, noisy,
                                  shown_radiance);
        one.albedo   = select_sum(files, j.in.path, a.albedo, noisy,
                                  shown_albedo);
        plan.layers.push_back(std::move(one));
        log.push_back(format("  layer     {}: {} with albedo {}{}{}{}", a.name,
                             shown_radiance, shown_albedo,
                             a.divided ? " (divided by it)" : "",
                             a.reflected ? " (reflected: stricter edge test)"
                                         : "",
                             a.direct ? " (direct: structure beyond its noise "
                                        "kept)"
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
    plan.mask_reach        = std::max(j.filter.r_max, 0);
    plan.reach             = plan.mask_reach;
    // The residual's mask reads the residual, which the direct light's
    // routing wrote from pixels further out.
    if (std::any_of(args.begin(), args.end(), [](const LayerArg& a) { return a.direct; }))
        plan.reach += route_reach();
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
    // Only a convention's lobes (Cycles: Diff, Gloss, Trans), which name
    // their lobe; --layer gives none.
    const auto diffuse = std::find_if(args.begin(), args.end(),
                                      [](const LayerArg& a) {
                                          return a.lobe == "Diff";
                                      });
    for (size_t i = 0; diffuse != args.end() && i < args.size(); ++i)
        if (args[i].divided && (args[i].lobe == "Gloss" || args[i].lobe == "Trans")) {
            plan.layers[i].diffuse = int(diffuse - args.begin());
            log.push_back(format("  layer     {}: over {} where {} is 0 (mirrors, "
                                 "clear glass)", args[i].name, shown_albedo,
                                 diffuse->albedo));
        }
    return plan;
}


void
use_aux_colours(LayersPlan& plan, InputFiles& files, const Job& j,
                const std::vector<LayerArg>& args, const AuxConvention& aux,
                const ROI& noisy, std::vector<std::string>& log)
{
    auto use = [&](LayersPlan::One& one, const std::string& colour) {
        std::string shown;
        std::vector<Selection> sel = select_sum(files, j.aux.path, colour,
                                                noisy, shown);
        const bool divides = !one.divided
                             && j.aux_demodulation == AuxDemodulation::Aux;
        (divides ? one.albedo : one.remodulation) = std::move(sel);
        log.push_back(format("  layer     {}: {} by the aux {}", one.name,
                             divides ? "demodulated and remodulated"
                                     : "remodulated",
                             shown));
    };
    for (size_t i = 0; i < args.size() && i < plan.layers.size(); ++i)
        for (const auto& lobe : aux.lobe_colours)
            if (lobe.first == args[i].lobe)
                use(plan.layers[i], lobe.second);
    if (plan.residual_is_layer)
        use(plan.layers.back(), aux.albedo);
}


namespace {

/// The layer's own colour prefiltered (docs/LAYERS.md, "Colours"), over
/// the strip's rows (the strip reads the prefilter's halo beyond what the
/// filter and the residual's mask read): a colour the radiance came divided
/// by stays as the renderer divided by it and the clean one remodulates
/// (`remodulation`); a colour the filter divides by is replaced.
void
prefilter_colour(const LayersPlan::One& one, const Job& j, ImageBuf& colour,
                 ImageBuf& remodulation)
{
    ImageBuf clean;
    if (!prefilter_albedo(clean, colour, one.prefilter, {}, j.threads))
        fail(format("layer '{}' of '{}': {}", one.name, j.in.path,
                    one_line(clean.geterror())));
    // A swap, not a move: OIIO 2.4 leaves a moved-from ImageBuf without
    // its implementation.
    clean.swap(one.divided ? remodulation : colour);
}


/// Mirrors and clear glass (docs/LAYERS.md, "Mirrors and glass"). Cycles
/// divides a lobe's light by the lobe's colour, which at a mirror or clear
/// glass is flat: the texture seen in it stays in the quotient, and the
/// filter blurs it. Its Denoising Albedo passes through such a hit to the
/// surface seen, as beauty mode's albedo does. So where a pixel has no
/// diffuse colour (`diffuse_colour` 0 in every channel: no sample met a
/// rough surface) and the lobe's `colour` is not 0, the lobe's light is
/// divided by `through` instead: `radiance` (Cycles' quotient by `colour`)
/// becomes `colour * radiance / through`, and `colour` (and the colour
/// that remodulates, if any) `through`, channel by channel where `through`
/// is above `eps`; not where a channel of `through` is above 1, an emitter
/// seen through the glass (Cycles writes its emission as its albedo),
/// whose samples would be taken for texture. Nothing else changes:
/// remodulated, the light is the renderer's.
void
divide_through_specular(ImageBuf& radiance, ImageBuf& colour,
                        ImageBuf& remodulation, const ImageBuf& diffuse_colour,
                        const ImageBuf& through, float eps, int threads)
{
    const bool remodulates = remodulation.initialized();
    // The float iterators need float pixels; an image may be the file's
    // half rows (the diffuse colour, an --aux colour).
    auto make_float = [](ImageBuf& img) {
        if (img.initialized() && img.spec().format != TypeFloat) {
            ImageBuf copy = img.copy(TypeFloat);
            img.swap(copy);  // not a move: see prefilter_colour()
        }
    };
    make_float(radiance);
    make_float(colour);
    make_float(remodulation);
    ImageBuf diffuse = diffuse_colour.spec().format == TypeFloat
                           ? ImageBuf()
                           : diffuse_colour.copy(TypeFloat);
    ImageBuf through_float = through.spec().format == TypeFloat
                                 ? ImageBuf()
                                 : through.copy(TypeFloat);
    const ImageBuf& d_img = diffuse.initialized() ? diffuse : diffuse_colour;
    const ImageBuf& t_img = through_float.initialized() ? through_float : through;
    ImageBufAlgo::parallel_image(radiance.roi(), threads, [&](ROI roi) {
        ImageBuf::ConstIterator<float> d(d_img, roi), t(t_img, roi);
        ImageBuf::Iterator<float> q(radiance, roi), c(colour, roi);
        ImageBuf::Iterator<float> m(remodulates ? remodulation : colour, roi);
        for (; !q.done(); ++q, ++c, ++m, ++d, ++t) {
            if (!d.exists() || !t.exists() || !c.exists()
                || d[0] != 0.0f || d[1] != 0.0f || d[2] != 0.0f
                || !(c[0] > 0.0f || c[1] > 0.0f || c[2] > 0.0f)
                || t[0] > 1.0f || t[1] > 1.0f || t[2] > 1.0f)
                continue;
            for (int ch = 0; ch < 3; ++ch) {
                const float through_c = t[ch];
                if (!(through_c > eps && std::isfinite(through_c)))
                    continue;
                q[ch] = c[ch] * q[ch] / through_c;
                c[ch] = through_c;
                if (remodulates)
                    m[ch] = through_c;
            }
        }
    });
}


/// The mean of `v` over the (2 r + 1)^2 box around each pixel (over what
/// lies in the image and is finite), rows then columns.
std::vector<float>
box_mean(const std::vector<float>& v, int w, int h, int r)
{
    std::vector<float> rows(v.size()), out(v.size()), nrows(v.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float s = 0.0f, n = 0.0f;
            for (int u = std::max(x - r, 0); u <= std::min(x + r, w - 1); ++u) {
                const float e = v[size_t(y) * size_t(w) + size_t(u)];
                if (std::isfinite(e)) {
                    s += e;
                    n += 1.0f;
                }
            }
            rows[size_t(y) * size_t(w) + size_t(x)]  = s;
            nrows[size_t(y) * size_t(w) + size_t(x)] = n;
        }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float s = 0.0f, n = 0.0f;
            for (int t = std::max(y - r, 0); t <= std::min(y + r, h - 1); ++t) {
                s += rows[size_t(t) * size_t(w) + size_t(x)];
                n += nrows[size_t(t) * size_t(w) + size_t(x)];
            }
            out[size_t(y) * size_t(w) + size_t(x)] = n > 0.0f ? s / n : 0.0f;
        }
    return out;
}


std::vector<float>
luminance_plane(const std::vector<float>& rgb)
{
    std::vector<float> y(rgb.size() / 3);
    for (size_t i = 0; i < y.size(); ++i)
        y[i] = 0.2126f * rgb[3 * i] + 0.7152f * rgb[3 * i + 1] + 0.0722f * rgb[3 * i + 2];
    return y;
}


/// Light by path keeps the direct light apart only where it is cleaner
/// than the rest of the light (the residual): its relative noise, sqrt(V)
/// over its level, both pooled over the 17x17 (V from noise_variance()),
/// below the residual's. Elsewhere (a sky's light through a window, found
/// by few samples) splitting leaves two noisier images to filter instead
/// of one, and the direct light goes to the residual. The share kept apart
/// is that decision's 17x17 mean, so that neither image takes a seam where
/// it changes: the direct quotient is scaled by it, and what it loses is
/// added to the residual as light.
void
route_direct_light(ImageBuf& quotient, const ImageBuf& colour, bool divided,
                   ImageBuf& residual, const Job& j, const std::string& name)
{
    ImageBuf product, v_direct, v_rest;
    const ROI all = quotient.roi();
    // A layer of radiance (not divided, Arnold's) is its light already.
    const ImageBuf& direct = divided ? product : quotient;
    if ((divided && !ImageBufAlgo::mul(product, quotient, colour, {}, j.threads))
        || !noise_variance(v_direct, direct, {}, all, all, j.threads)
        || !noise_variance(v_rest, residual, {}, all, all, j.threads))
        fail(format("layer '{}' of '{}': {}", name, j.in.path,
                    one_line(product.geterror() + v_direct.geterror()
                             + v_rest.geterror())));
    const int w = all.width(), h = all.height();
    const size_t n = size_t(w) * size_t(h);
    ROI rgb    = all;
    rgb.chbegin = 0;
    rgb.chend   = 3;
    ROI one    = all;
    one.chbegin = 0;
    one.chend   = 1;
    std::vector<float> d(3 * n), o(3 * n), q(3 * n), vd(n), vo(n);
    direct.get_pixels(rgb, TypeFloat, d.data());
    residual.get_pixels(rgb, TypeFloat, o.data());
    quotient.get_pixels(rgb, TypeFloat, q.data());
    v_direct.get_pixels(one, TypeFloat, vd.data());
    v_rest.get_pixels(one, TypeFloat, vo.data());
    const std::vector<float> yd = box_mean(luminance_plane(d), w, h, kPool);
    const std::vector<float> yo = box_mean(luminance_plane(o), w, h, kPool);
    const std::vector<float> pd = box_mean(vd, w, h, kPool);
    const std::vector<float> po = box_mean(vo, w, h, kPool);
    std::vector<float> cleaner(n);
    for (size_t i = 0; i < n; ++i)
        cleaner[i] = pd[i] * yo[i] * yo[i] < po[i] * yd[i] * yd[i] ? 1.0f : 0.0f;
    const std::vector<float> share = box_mean(cleaner, w, h, kPool);
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            o[3 * i + size_t(c)] += (1.0f - share[i]) * d[3 * i + size_t(c)];
            q[3 * i + size_t(c)] *= share[i];
        }
    quotient.set_pixels(rgb, TypeFloat, q.data());
    residual.set_pixels(rgb, TypeFloat, o.data());
}

}  // namespace


/// Zero the unfiltered residual `unfiltered` where the beauty's alpha (its
/// fourth channel, when it has one) is below 1. Under transparent film,
/// Cycles' Env pass holds the background that the beauty leaves out (its
/// alpha says where): added back it would paint the sky into the holes
/// (light_groups_motion at 16 spp, layers mode: relMSE 770x the input's).
/// Where the film is opaque the alpha is 1 and nothing changes.
static void
drop_where_transparent(ImageBuf& unfiltered, const ImageBuf& beauty)
{
    if (beauty.nchannels() < 4)
        return;
    // Through get/set_pixels: the beauty may be the file's half rows.
    ROI roi = unfiltered.roi(), a = roi;
    a.chbegin = 3;
    a.chend   = 4;
    std::vector<float> alpha(a.npixels());
    beauty.get_pixels(a, TypeFloat, alpha.data());
    if (std::all_of(alpha.begin(), alpha.end(), [](float v) { return v >= 1.0f; }))
        return;
    // `unfiltered` may be the file's rows, which the output copies: the
    // change goes to a copy of its own.
    const size_t nch = size_t(roi.nchannels());
    std::vector<float> light(roi.npixels() * nch);
    unfiltered.get_pixels(roi, TypeFloat, light.data());
    for (size_t i = 0; i < alpha.size(); ++i)
        if (!(alpha[i] >= 1.0f))
            std::fill_n(light.begin() + long(i * nch), nch, 0.0f);
    unfiltered.reset(ImageSpec(roi, TypeFloat));
    unfiltered.set_pixels(roi, TypeFloat, light.data());
}


/// The beauty's alpha into `residual`'s fourth channel, when it has one.
/// Through get/set_pixels: the beauty may be the file's half rows.
static bool
copy_alpha(ImageBuf& residual, const ImageBuf& beauty)
{
    if (residual.nchannels() < 4)
        return true;
    ROI a    = residual.roi();
    a.chbegin = 3;
    a.chend   = 4;
    std::vector<float> alpha(a.npixels());
    return beauty.get_pixels(a, TypeFloat, alpha.data())
           && residual.set_pixels(a, TypeFloat, alpha.data());
}


/// The residual's image over `rgb`: RGB, and the beauty's alpha when the
/// residual is a layer to filter and the beauty has one. The filter reads
/// an alpha of 0 as no surface, as it does the beauty's in beauty mode, so
/// that under transparent film the holes are left as they are, not filled
/// with their neighbours' light. (An unfiltered residual stays RGB.)
static ImageSpec
residual_spec(const ROI& rgb, const ImageBuf& beauty, bool filtered)
{
    ROI kept = rgb;
    if (filtered && beauty.nchannels() >= 4)
        kept.chend = 4;
    ImageSpec spec(kept, TypeFloat);
    if (kept.chend == 4)
        spec.alpha_channel = 3;
    return spec;
}


/// Read the strip's layers and residual as `plan` says.
std::vector<Layer>
load_layers(const Strip& strip, const LayersPlan& plan, const Job& j,
            const ImageBuf& beauty, LoadedLayers& l)
{
    const size_t n = plan.layers.size();
    l.radiance.assign(n, ImageBuf());
    l.albedo.assign(n, ImageBuf());
    l.remodulation.assign(n, ImageBuf());
    l.denoised.assign(n, ImageBuf());
    l.stats.assign(n, FilterStats());
    l.residual.reset();
    std::vector<Layer> layers(n);
    const size_t given = plan.residual_is_layer ? n - 1 : n;
    for (size_t i = 0; i < n; ++i) {
        const LayersPlan::One& one = plan.layers[i];
        // divide_through_specular() writes a lobe's light and colour,
        // route_direct_light() a direct layer's light and the residual's,
        // and the mask below the residual layer's albedo: copies of their
        // own.
        const bool read_only = one.diffuse < 0 && !one.direct;
        if (i < given)
            l.radiance[i] = strip.sum(one.radiance, read_only);
        l.albedo[i]         = strip.sum(one.albedo, i < given && read_only);
        if (one.prefilter)
            prefilter_colour(one, j, l.albedo[i], l.remodulation[i]);
        layers[i].name      = one.name;
        layers[i].radiance  = &l.radiance[i];
        layers[i].albedo    = &l.albedo[i];
        if (!one.remodulation.empty())
            l.remodulation[i] = strip.sum(one.remodulation, true);
        if (l.remodulation[i].initialized())
            layers[i].remodulation_albedo = &l.remodulation[i];
        layers[i].divided   = one.divided;
        layers[i].reflected = one.reflected;
        layers[i].direct    = one.direct;
        layers[i].denoised  = &l.denoised[i];
        layers[i].stats     = &l.stats[i];
    }
    if (!plan.residual.empty()) {
        l.residual = strip.sum(plan.residual, !plan.residual_is_layer);
    } else {
        std::vector<Layer> unfiltered(layers.begin(),
                                      layers.begin() + long(given));
        // The beauty is the layers as the renderer composed them: with
        // their own colours, not the aux image's.
        for (Layer& layer : unfiltered) {
            layer.remodulation_albedo = nullptr;
            layer.filter   = false;
            layer.denoised = nullptr;
            layer.stats    = nullptr;
        }
        ImageBuf sum;
        ROI rgb     = beauty.roi();
        rgb.chbegin = 0;
        rgb.chend   = 3;
        l.residual.reset(residual_spec(rgb, beauty, plan.residual_is_layer));
        FilterOptions sum_options = j.filter;
        sum_options.progress      = nullptr;
        if (!layered_denoise(sum, unfiltered, nullptr, {}, sum_options,
                             nullptr, rgb, j.threads)
            || !ImageBufAlgo::sub(l.residual, beauty, sum, rgb, j.threads)
            || !copy_alpha(l.residual, beauty))
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
        drop_where_transparent(l.residual, beauty);
        ROI rgb    = l.residual.roi();
        rgb.chend  = 3;
        if (!ImageBufAlgo::sub(l.radiance[i], l.radiance[i], l.residual, rgb,
                               j.threads))
            fail(format("layers of '{}': {}", j.in.path,
                        one_line(l.radiance[i].geterror())));
    }
    for (size_t k = 0; k < given; ++k)
        if (plan.layers[k].diffuse >= 0)
            divide_through_specular(l.radiance[k], l.albedo[k],
                                    l.remodulation[k],
                                    l.albedo[size_t(plan.layers[k].diffuse)],
                                    l.albedo[i], j.filter.albedo_eps,
                                    j.threads);
    for (size_t k = 0; k < given; ++k)
        if (plan.layers[k].direct)
            route_direct_light(l.radiance[k], l.albedo[k],
                               plan.layers[k].divided, l.radiance[i], j,
                               plan.layers[k].name);
    // The mask reads float images; the beauty may be the file's half rows.
    const ImageBuf beauty_float = beauty.spec().format == TypeFloat
                                      ? ImageBuf()
                                      : beauty.copy(TypeFloat);
    mask_negligible_residual(l.albedo[i], l.radiance[i],
                             beauty_float.initialized() ? beauty_float
                                                        : beauty,
                             plan.mask_reach, j.threads);
    return layers;
}

}  // namespace job
}  // namespace zdenoise
