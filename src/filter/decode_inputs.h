// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The filter's input planes decoded over one region (decode_inputs.cpp):
// the first stage of every filter that reads the quotient and the guides.

#pragma once

#include "filter_inputs.h"

namespace zdenoise {
namespace detail {

/// Decode the quotient, albedo and guides over `region` and estimate the
/// noise (docs/FILTER.md sections 2-3). Guides must have been checked to
/// cover the region. Returns false (message in dst) on bad guide shapes,
/// and (no message) when opt.cancel is set.
bool
decode_filter_inputs(FilterInputs& in, ImageBuf& dst, const ImageBuf& quotient,
                     const ImageBuf& albedo, const Guides& guides,
                     const FilterOptions& opt, ROI region, int nthreads);

}  // namespace detail
}  // namespace zdenoise
