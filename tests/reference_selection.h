// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Plain reference implementations of the selection stages of
// include/zdenoise/selection.h, written from docs/FILTER.md section 13 and
// independently of the library: every window is fitted again for every
// output pixel it reaches, in double, by Gaussian elimination (the library
// uses a Cholesky factor), one thread, in raster order. Only for the tests.

#pragma once

#include <vector>

#include <zdenoise/selection.h>

#include "reference_filter.h"

namespace zdenoise_ref {

/// Section 13.2: R, G, B of the filtered quotient and D = d out_l / d z_l.
/// `albedo` demodulated z (the clamp's radiance); `pilot` has R, G, B and
/// the variance of its luminance in channel 3.
/// Centres lie on the lattice of options.centre_stride from (0, 0); the
/// whole image is the frame.
RefImage feature_regression(const RefImage& z, const RefImage& albedo,
                            const RefImage& pilot,
                            const RefGuides& guides,
                            const zdenoise::FeatureRegressionOptions& options);

/// Section 13.3: weight * [(out_l - z_l)^2 - var + 2 var D], NaN without
/// an observation (var negative or the value not finite); with
/// clip_sigmas > 0 the squared difference is at most clip_sigmas^2 var.
RefImage sure_risk(const RefImage& candidate, const RefImage& z,
                   const RefImage& variance, const RefImage& weight,
                   double clip_sigmas = 0.0);

/// Section 13.4: the blend of the candidates' R, G, B by the smoothed
/// choice map; `weights`, if not null, receives one channel per candidate.
RefImage select_by_risk(const std::vector<const RefImage*>& candidates,
                        const std::vector<const RefImage*>& risks,
                        const zdenoise::SelectionOptions& options,
                        RefImage* weights = nullptr);

}  // namespace zdenoise_ref
