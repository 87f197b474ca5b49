// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// What modulate.cpp gives the library beyond zdenoise.h's demodulate() and
// remodulate().

#pragma once

#include <zdenoise/zdenoise.h>

namespace zdenoise {
namespace detail {

/// The albedo that remodulates a quotient demodulated by `albedo` when a
/// cleaner `remodulation_albedo` is given (zdenoise.h's remodulate() with
/// two albedos), over roi into `dst` (float, R,G,B): the clean one where
/// both are demodulated (albedo_demodulated()), else the demodulating one,
/// so that channels not demodulated still pass through.
bool
remodulation_albedo(ImageBuf& dst, const ImageBuf& albedo,
                    const ImageBuf& remodulation_albedo, float albedo_eps,
                    ROI roi);

}  // namespace detail
}  // namespace zdenoise
