// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// denoise_alpha() (include/zdenoise/alpha.h, docs/ALPHA.md): the coverage
// filtered as light of albedo 1, clamped to [0, 1], solid pixels kept.

#include <zdenoise/alpha.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <OpenImageIO/imagebufalgo.h>

#include "checks.h"
#include "filter/filter_inputs.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;
using namespace detail;

namespace {

/// The filter's options for a coverage: no energy correction (a coverage
/// is no light; docs/FILTER.md section 7b).
FilterOptions
coverage_options(const FilterOptions& options)
{
    FilterOptions o = options;
    o.energy_radius = 0;
    return o;
}


/// The coverage over `region`, a pixel a float (NaN beyond the image).
struct CoveragePlane {
    ROI region;
    std::vector<float> a;

    float at(int x, int y) const
    {
        return a[size_t(y - region.ybegin) * size_t(region.width())
                 + size_t(x - region.xbegin)];
    }
};

/// Are (x, y)'s coverage and its 8 neighbours' (in the region) each
/// exactly 0 or 1: inside an object, on empty film, or along a silhouette
/// rendered without anti-aliasing?
bool
solid(const CoveragePlane& p, int x, int y)
{
    const float c = p.at(x, y);
    if (c != 0.0f && c != 1.0f)
        return false;
    for (int v = std::max(y - 1, p.region.ybegin);
         v < std::min(y + 2, p.region.yend); ++v)
        for (int u = std::max(x - 1, p.region.xbegin);
             u < std::min(x + 2, p.region.xend); ++u)
            if (p.at(u, v) != 0.0f && p.at(u, v) != 1.0f)
                return false;
    return true;
}

/// The coverage as the light of a grey surface of albedo 1: (a, a, a),
/// and that albedo, over the plane's region.
void
coverage_as_light(const CoveragePlane& p, const ROI& frame, ImageBuf& light,
                  ImageBuf& albedo)
{
    const ImageSpec spec = result_spec(p.region, frame, 3);
    light.reset(spec);
    albedo.reset(spec);
    std::vector<float> rgb(3 * p.a.size());
    for (size_t i = 0; i < p.a.size(); ++i)
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = p.a[i];
    ROI r    = p.region;
    r.chbegin = 0;
    r.chend   = 3;
    light.set_pixels(r, TypeFloat, rgb.data());
    const float one[3] = { 1.0f, 1.0f, 1.0f };
    ImageBufAlgo::fill(albedo, one);
}

}  // namespace


int
alpha_halo(const FilterOptions& options)
{
    // keep_structure() reads the filtered coverage one pixel beyond the
    // output, which the filter computes from its own halo around that.
    return filter_halo(coverage_options(options)) + 1;
}


bool
denoise_alpha(ImageBuf& dst, const ImageBuf& alpha, const Guides& guides,
              const FilterOptions& options, ROI roi, int nthreads)
{
    const char* opname = "denoise_alpha";
    if (!alpha.initialized()) {
        dst.errorfmt("{}: input image is not initialized", opname);
        return false;
    }
    if (!roi.defined())
        roi = alpha.roi();
    const ROI frame = options.frame.defined() ? options.frame : alpha.roi();
    if (!check_input(dst, alpha, opname, "alpha", roi, 1)
        || !check_frame(dst, opname, roi, frame))
        return false;
    CoveragePlane p;
    p.region = halo_region(roi, frame, alpha_halo(options));
    if (!check_input(dst, alpha, opname, "alpha", p.region, 1))
        return false;
    p.a.resize(p.region.npixels());
    ROI one    = p.region;
    one.chbegin = 0;
    one.chend   = 1;
    if (!alpha.get_pixels(one, TypeFloat, p.a.data())) {
        dst.errorfmt("{}: cannot read the alpha: {}", opname, alpha.geterror());
        return false;
    }
    ImageBuf light, albedo, filtered;
    coverage_as_light(p, frame, light, albedo);
    // The noise guides describe the colour. The depth of a partly covered
    // pixel mixes the object's with the background's by the pixel's own
    // samples, so it would keep apart pixels of the same coverage by their
    // noise (a motion-blurred edge's alpha MSE 0.99x the rendered one with
    // it, 0.60x without). Progress and the maps are the whole job's.
    Guides g;
    g.normal    = guides.normal;
    g.object_id = guides.object_id;
    FilterOptions o = coverage_options(options);
    o.frame         = frame;
    o.progress      = nullptr;
    o.diagnostics   = nullptr;
    o.hat_diagonal  = nullptr;
    ImageBuf kept;
    if (!denoise(filtered, light, albedo, g, o, nullptr, halo_region(roi, frame, 1),
                 nthreads)
        || !keep_structure(kept, light, filtered, g, frame, nullptr, roi, nthreads)) {
        dst.errorfmt("{}: {}", opname, filtered.geterror() + kept.geterror());
        return false;
    }
    if (!prepare_result(dst, dst, roi, frame, 1, opname, "dst"))
        return false;
    std::vector<float> rgb(3 * roi.npixels()), out(roi.npixels());
    ROI r3    = roi;
    r3.chbegin = 0;
    r3.chend   = 3;
    kept.get_pixels(r3, TypeFloat, rgb.data());
    const size_t w = size_t(roi.width());
    for_rows(roi, nthreads, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t i = size_t(y - roi.ybegin) * w + size_t(x - roi.xbegin);
            const float f  = rgb[3 * i];
            out[i] = solid(p, x, y) ? p.at(x, y)
                                    : std::isfinite(f) ? std::clamp(f, 0.0f, 1.0f)
                                                       : 0.0f;
        }
    });
    ROI r1    = roi;
    r1.chbegin = 0;
    r1.chend   = 1;
    return dst.set_pixels(r1, TypeFloat, out.data());
}


ImageBuf
denoise_alpha(const ImageBuf& alpha, const Guides& guides,
              const FilterOptions& options, ROI roi, int nthreads)
{
    return returned_image("denoise_alpha", [&](ImageBuf& result) {
        return denoise_alpha(result, alpha, guides, options, roi, nthreads);
    });
}

}  // namespace zdenoise
