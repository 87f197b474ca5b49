// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// simd_targets(), simd_target(), set_simd_target(): Highway's run-time
// dispatch, named. HWY_TARGETS here is the kernels' (the same compile
// definitions, src/CMakeLists.txt).

#include <zdenoise/simd.h>

#include <hwy/highway.h>
#include <hwy/targets.h>

namespace zdenoise {

namespace {

/// The compiled targets the CPU runs, best first (lower bits are better).
std::vector<int64_t>
runnable_targets()
{
    std::vector<int64_t> out;
    for (int64_t t = hwy::SupportedTargets() & HWY_TARGETS; t != 0; t &= t - 1)
        out.push_back(t & ~(t - 1));
    return out;
}

/// The targets without a test mock: what the CPU itself runs.
std::vector<int64_t>
cpu_targets()
{
    const std::vector<int64_t> now = runnable_targets();
    hwy::SetSupportedTargetsForTest(0);
    std::vector<int64_t> all = runnable_targets();
    if (now != all) {
        int64_t mask = 0;
        for (int64_t t : now)
            mask |= t;
        hwy::SetSupportedTargetsForTest(mask);
    }
    return all;
}

}  // namespace


std::vector<std::string>
simd_targets()
{
    std::vector<std::string> names;
    for (int64_t t : cpu_targets())
        names.push_back(hwy::TargetName(t));
    return names;
}


std::string
simd_target()
{
    const std::vector<int64_t> now = runnable_targets();
    return now.empty() ? std::string() : hwy::TargetName(now.front());
}


bool
set_simd_target(const std::string& name)
{
    if (name.empty()) {
        hwy::SetSupportedTargetsForTest(0);
        return true;
    }
    for (int64_t t : cpu_targets())
        if (name == hwy::TargetName(t)) {
            hwy::SetSupportedTargetsForTest(t);
            return true;
        }
    return false;
}

}  // namespace zdenoise
