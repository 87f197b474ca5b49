// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The pixel classes of docs/FILTER.md section 2 (pixel_classes.cpp), which
// decode_filter_inputs() computes for the filter.

#pragma once

#include <vector>

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// The pixel classes of section 2 (in.cls), the luminance zl of the fit
/// points and the inverse depth of the surface pixels, from the RGB
/// quotient z and albedo (3 floats a pixel), the alpha (empty: none) and
/// the depth (empty: none) over in.region.
void
classify_pixels(FilterInputs& in, const std::vector<float>& z,
                const std::vector<float>& albedo,
                const std::vector<float>& alpha,
                const std::vector<float>& depth, float albedo_eps,
                int nthreads);

}  // namespace detail
}  // namespace zdenoise
