// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// decode_filter_inputs(): the filter's input planes over one region, stage
// by stage (docs/FILTER.md sections 2-4).

#include "decode_inputs.h"

#include <cmath>

#include "guide_weight.h"
#include "noise_estimate.h"
#include "outliers.h"
#include "pixel_classes.h"

namespace zdenoise {
namespace detail {

using namespace OIIO;

namespace {

/// The planes the fit and the splat read, padded for the row kernels
/// (kPlanePadding): z and the radiance of the fit points per channel, the
/// receivers' 1 / (La + eps), the fit prior exp(-sigma) where sigma <=
/// sigma_good, and zl, vs, sigma, cls padded likewise.
void
prepare_fit_planes(FilterInputs& in, const std::vector<float>& z,
                   const std::vector<float>& albedo, float albedo_eps,
                   float sigma_good, int nthreads)
{
    const size_t npix = in.region.npixels();
    auto fit = [&](size_t i) { return (in.cls[i] & kFitPoint) != 0; };
    for (int c = 0; c < 3; ++c) {
        in.zfit[c].assign(npix + kPlanePadding, 0.0f);
        in.lfit[c].assign(npix + kPlanePadding, 0.0f);
        in.inv_albedo[c].assign(npix + kPlanePadding, 0.0f);
    }
    in.fit_prior.assign(npix + kPlanePadding, 0.0f);
    for_rows(in.region, nthreads, [&](int y) {
        for (size_t i = in.index(in.region.xbegin, y), e = i + in.width; i < e;
             ++i) {
            for (int c = 0; c < 3; ++c)
                if (in.cls[i] & (kReceiveR << c))
                    in.inv_albedo[c][i] = 1.0f / (albedo[3 * i + c] + albedo_eps);
            if (!fit(i))
                continue;
            for (int c = 0; c < 3; ++c) {
                in.zfit[c][i] = z[3 * i + c];
                in.lfit[c][i] = z[3 * i + c] * (albedo[3 * i + c] + albedo_eps);
            }
            if (in.sigma[i] <= sigma_good)
                in.fit_prior[i] = std::exp(-in.sigma[i]);
        }
    });
    in.zl.resize(npix + kPlanePadding, 0.0f);
    in.vs.resize(npix + kPlanePadding, 0.0f);
    in.sigma.resize(npix + kPlanePadding, 0.0f);
    in.cls.resize(npix + kPlanePadding, 0);
    if (!in.invdepth.empty())
        in.invdepth.resize(npix + kPlanePadding, 0.0f);
}

}  // namespace


bool
decode_filter_inputs(FilterInputs& in, ImageBuf& dst, const ImageBuf& quotient,
                     const ImageBuf& albedo, const Guides& guides,
                     const FilterOptions& opt, ROI region, int nthreads)
{
    in.region = region;
    in.image  = opt.frame;  // regression_filter() always sets it
    in.width  = region.width();
    in.height = region.height();

    // The RGB quotient, 3 per pixel: kept as zfit for the fit points.
    std::vector<float> z = read_channels(quotient, region, 0, 3);
    const std::vector<float> alb = read_channels(albedo, region, 0, 3);
    std::vector<float> alpha;
    const int alpha_ch = quotient.spec().alpha_channel;
    if (alpha_ch >= 3)
        alpha = read_channels(quotient, region, alpha_ch, alpha_ch + 1);
    std::vector<float> depth;
    if (guides.depth)
        depth = read_channels(*guides.depth, region, 0, 1);

    if (guides.normal)
        decode_normals(in, *guides.normal);
    if (guides.object_id && !decode_object_ids(in, dst, *guides.object_id))
        return false;
    // Cancelled (FilterOptions::cancel): false between stages, with no
    // message (the operation gives it).
    if (cancel_requested(opt))
        return false;
    classify_pixels(in, z, alb, alpha, depth, opt.albedo_eps, nthreads);
    const RawVariance var = raw_variance(in, guides, alb, opt.albedo_eps,
                                         opt.directional_noise != 0, nthreads);
    if (cancel_requested(opt))
        return false;
    if (opt.outlier_spread)
        in.outliers = split_outliers(in, z, alb, var, opt, nthreads);
    smooth_noise(in, var, nthreads);
    if (cancel_requested(opt))
        return false;
    prepare_fit_planes(in, z, alb, opt.albedo_eps, opt.sigma_good, nthreads);
    return !cancel_requested(opt);
}

}  // namespace detail
}  // namespace zdenoise
