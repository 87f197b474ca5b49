// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The 5x5 median (median_kernel.h): Batcher's odd-even merge sort network
// on 32 inputs with the 7 past the 25th taken as +infinity, so that each
// comparator touching them does nothing and is left out; the compiler
// drops the comparators the 13th output does not depend on. A lane is a
// pixel: 25 vector loads (one per box offset), then only Min and Max.

#include <algorithm>
#include <cmath>
#include <utility>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "filter/median_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "median_kernel.h"

#ifndef ZDENOISE_MEDIAN_NETWORK
#    define ZDENOISE_MEDIAN_NETWORK
namespace zdenoise {
namespace detail {
namespace {

constexpr int kBoxValues = 25;  ///< the 5x5 box
constexpr int kNetworkInputs = 32;

struct Comparator {
    int a = 0, b = 0;
};

struct Comparators {
    Comparator pair[200] {};
    int count = 0;
};

/// Batcher's odd-even merge sort on kNetworkInputs, without the
/// comparators that reach past kBoxValues (their inputs are +infinity).
constexpr Comparators
median_network()
{
    Comparators c;
    const int n = kNetworkInputs;
    for (int p = 1; p < n; p *= 2)
        for (int k = p; k >= 1; k /= 2)
            for (int j = k % p; j <= n - 1 - k; j += 2 * k)
                for (int i = 0; i <= std::min(k - 1, n - j - k - 1); ++i)
                    if ((i + j) / (2 * p) == (i + j + k) / (2 * p)
                        && i + j + k < kBoxValues) {
                        c.pair[c.count].a   = i + j;
                        c.pair[c.count++].b = i + j + k;
                    }
    return c;
}

constexpr Comparators kMedianNetwork = median_network();

}  // namespace
}  // namespace detail
}  // namespace zdenoise
#endif

HWY_BEFORE_NAMESPACE();
namespace zdenoise {
namespace detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

template<class V, size_t... I>
HWY_INLINE void
sort_network(V* v, std::index_sequence<I...>)
{
    // Each comparator in order, unrolled, so that v stays in registers.
    auto compare = [&](int a, int b) {
        const V lo = hn::Min(v[a], v[b]);
        v[b]       = hn::Max(v[a], v[b]);
        v[a]       = lo;
    };
    (compare(kMedianNetwork.pair[I].a, kMedianNetwork.pair[I].b), ...);
}

/// median5x5_row() for x in [x, n) of D's width.
template<class D>
HWY_INLINE int
median_points(D d, const float* const rows[5], int x, int n, float* med)
{
    using V = hn::Vec<D>;
    const int lanes = int(hn::Lanes(d));
    constexpr size_t kPairs = size_t(kMedianNetwork.count);
    for (; x + lanes <= n; x += lanes) {
        V v[kBoxValues];
        auto any_nan = hn::IsNaN(hn::Zero(d));
        for (int dy = 0; dy < 5; ++dy)
            for (int dx = 0; dx < 5; ++dx) {
                v[5 * dy + dx] = hn::LoadU(d, rows[dy] + x + dx);
                any_nan = hn::Or(any_nan, hn::IsNaN(v[5 * dy + dx]));
            }
        sort_network(v, std::make_index_sequence<kPairs>());
        hn::StoreU(hn::IfThenElse(any_nan, hn::Set(d, NAN), v[kBoxValues / 2]), d,
                   med + x);
    }
    return x;
}

void
Median5x5Row(const float* const rows[5], int n, float* med)
{
    const int x = median_points(hn::ScalableTag<float>(), rows, 0, n, med);
    median_points(hn::CappedTag<float, 1>(), rows, x, n, med);
}

}  // namespace HWY_NAMESPACE
}  // namespace detail
}  // namespace zdenoise
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace zdenoise {
namespace detail {

HWY_EXPORT(Median5x5Row);

void
median5x5_row(const float* const rows[5], int n, float* med)
{
    HWY_DYNAMIC_DISPATCH(Median5x5Row)(rows, n, med);
}

}  // namespace detail
}  // namespace zdenoise
#endif
