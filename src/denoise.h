// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// denoise()'s demodulate, filter, remodulate with the filter of the
// quotient given (denoise.cpp): denoise() passes the regression filter, a
// direct layer of layered_denoise() the filter that keeps its structure.

#pragma once

#include <functional>

#include <zdenoise/zdenoise.h>

namespace zdenoise {
namespace detail {

/// Filters `quotient` into `filtered` with `opt` (its frame defined).
using QuotientFilter = std::function<bool(
    ImageBuf& filtered, const ImageBuf& quotient, const FilterOptions& opt)>;

/// denoise() over roi with `filter` in place of the regression filter: the
/// radiance is demodulated over roi and filter_halo() + `extra_halo` around
/// it (what `filter` reads), filtered, and remodulated by `remodulation`
/// when given, else by `albedo`.
bool
denoise_through(ImageBuf& dst, const ImageBuf& radiance,
                const ImageBuf& albedo, const ImageBuf* remodulation,
                const FilterOptions& options, ROI roi, int nthreads,
                int extra_halo, const QuotientFilter& filter);

}  // namespace detail
}  // namespace zdenoise
