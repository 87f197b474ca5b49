// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Outliers (fireflies) split off and spread (docs/FILTER.md section 3a): a
// fit point far above what its neighbourhood and its noise allow keeps only
// the light they allow; the rest of its radiance is taken out of the fit
// and added back, smoothly, over the receivers of its surface around it, so
// that no energy is lost and no window is swamped by it.

#pragma once

#include <vector>

#include "filter_inputs.h"
#include "noise_estimate.h"

namespace zdenoise {
namespace detail {

/// The outlier threshold t of section 3a: a point is an outlier when its
/// luminance is more than t standard deviations above its neighbourhood's
/// median, with t the normal quantile that one point of the largest window
/// ((2 r_max + 1)^2 points) exceeds by chance.
float
outlier_threshold(int r_max);

/// Find the outliers among the fit points of in.region (their test reads
/// the 5x5 around them) from the raw variance `var`, cap each one's z in
/// `z` (3 floats a pixel) and in.zl, and return them in raster order.
std::vector<Outlier>
split_outliers(FilterInputs& in, std::vector<float>& z,
               const std::vector<float>& albedo, const RawVariance& var,
               const FilterOptions& opt, int nthreads);

/// Spread the outliers' radiance over the receivers of their surface within
/// r_max (weights g(q; p) exp(-d^2 / r_max^2) times the receiver's albedo,
/// normalised per outlier and channel so that each outlier's radiance is
/// kept exactly), and add what lands on the output pixels `out` to
/// `spread` (3 doubles a pixel of `out`, in z units), outliers in order.
void
spread_outliers(const FilterInputs& in, const FilterOptions& opt,
                const ROI& out, std::vector<double>& spread, int nthreads);

}  // namespace detail
}  // namespace zdenoise
