// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The noise estimate of docs/FILTER.md section 3: the variance V of the
// quotient's luminance at each fit point, from the first source there is
// (a variance guide, two half buffers, or the image itself), and its 3x3
// smoothing into the fit's Vs and relative noise sigma.

#pragma once

#include <vector>

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// Per-pixel variance of zl over in.region, NaN where undefined (and at
/// every pixel that is no fit point).
using RawVariance = std::vector<float>;

/// Section 3, source 1: the variance guide `variance` (1 or RGB channels)
/// divided by the squared albedo (3 floats a pixel).
RawVariance
variance_from_guide(const FilterInputs& in, const ImageBuf& variance,
                    const std::vector<float>& albedo, float albedo_eps);

/// Section 3, source 2: (A - B)^2 / 4 of two half buffers, divided by the
/// squared albedo as source 1, then the robust 5x5 estimate of source 3.
RawVariance
variance_from_halves(const FilterInputs& in, const ImageBuf& half_a,
                     const ImageBuf& half_b, const std::vector<float>& albedo,
                     float albedo_eps, int nthreads);

/// Section 3, source 3: estimated from z itself, the 5x5 median of the
/// squared residuals against the 8-neighbour mean on the same surface.
RawVariance
variance_from_image(const FilterInputs& in, int nthreads);

/// Section 14's estimate (the smallest of four directions' 5x5 pools of
/// squared second differences, directional_variance.h) on the fit points'
/// zl; NaN where no direction has three.
RawVariance
variance_directional(const FilterInputs& in, int nthreads);

/// The 3x3 smoothing of section 3: in.vs and in.sigma from `var`.
void
smooth_noise(FilterInputs& in, const RawVariance& var, int nthreads);

/// Section 3: V from the first source `guides` has (with halves, never
/// below the image's own estimate); the image's own estimate is source 3,
/// or, when `directional`, the smaller of it and variance_directional().
RawVariance
raw_variance(const FilterInputs& in, const Guides& guides,
             const std::vector<float>& albedo, float albedo_eps,
             bool directional, int nthreads);

/// The median of the n > 0 values at v (the mean of the middle two for an
/// even n); reorders them. The noise estimate's and the outlier test's.
float
median(float* v, int n);

/// Are pixels a and b on the same surface for the noise estimate: the same
/// (plain or primary Cryptomatte) id, and close normals (cosine > 0.9) when
/// normals are given.
bool
same_surface(const FilterInputs& in, size_t a, size_t b);

}  // namespace detail
}  // namespace zdenoise
