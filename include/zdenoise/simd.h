// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The instruction sets of the filter's vector kernels (docs/PERFORMANCE.md
// "Vector kernels"). The kernels are compiled for several (Google Highway)
// and the best one the CPU has runs; these functions tell which, and let a
// test or a benchmark pick another.

#pragma once

#include <string>
#include <vector>

#include <zdenoise/export.h>

namespace zdenoise {

/// The instruction sets the kernels are compiled for that this CPU runs,
/// best first, by Highway's names: "AVX3" (AVX-512 F/BW/DQ/VL), "AVX2"
/// (with FMA), "SSE4", "NEON" on Arm, and last the portable scalar code,
/// always there ("SCALAR", or "EMU128" in newer Highway versions).
ZDENOISE_API std::vector<std::string> simd_targets();

/// The instruction set the kernels run with now.
ZDENOISE_API std::string simd_target();

/// Run the kernels with `name`, one of simd_targets(), or with the best
/// one again for "". Results of two instruction sets differ by float
/// rounding only (their vectors sum in different orders); on one
/// instruction set they do not depend on the thread count. Call it while
/// no filter runs (it is global to the process).
///
/// @return false, changing nothing, for a name not in simd_targets().
ZDENOISE_API bool set_simd_target(const std::string& name);

}  // namespace zdenoise
