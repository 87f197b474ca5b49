// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The least and the most of the elements within r of each element of a row
// or column, by van Herk and Gil-Werman's block prefixes and suffixes: three
// comparisons an element whatever r. Shared by radiance_bounds() (the
// selection's bounds, docs/FILTER.md section 13.2) and bound_highlights()
// (section 1a).

#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace zdenoise {
namespace detail {

/// Sliding extrema over n elements `stride` apart, the window clipped at
/// both ends. Exact, so any order gives the same floats. Keeps its scratch
/// between calls: one per thread.
class SlidingExtrema {
public:
    /// out_lo[i], out_hi[i]: the least of lo and the most of hi within r of
    /// element i (+inf and -inf where the window holds none).
    void run(const float* lo, const float* hi, int n, size_t stride, int r,
             float* out_lo, float* out_hi)
    {
        sweep(lo, n, stride, r, out_lo, Least{});
        sweep(hi, n, stride, r, out_hi, Most{});
    }

    /// out_hi[i]: the most of hi within r of element i.
    void run_most(const float* hi, int n, size_t stride, int r, float* out_hi)
    {
        sweep(hi, n, stride, r, out_hi, Most{});
    }

private:
    struct Least {
        static constexpr float none = std::numeric_limits<float>::infinity();
        float operator()(float a, float b) const { return std::min(a, b); }
    };
    struct Most {
        static constexpr float none = -std::numeric_limits<float>::infinity();
        float operator()(float a, float b) const { return std::max(a, b); }
    };

    template<class Pick>
    void sweep(const float* v, int n, size_t stride, int r, float* out, Pick pick)
    {
        const int k = 2 * r + 1, m = n + 2 * r;  // padded by r on each side
        prefix.resize(size_t(m)), suffix.resize(size_t(m));
        auto at = [&](int i) { return i < r || i >= r + n ? Pick::none : v[size_t(i - r) * stride]; };
        for (int i = 0; i < m; ++i)
            prefix[size_t(i)] = i % k == 0 ? at(i) : pick(prefix[size_t(i) - 1], at(i));
        for (int i = m - 1; i >= 0; --i) {
            const bool end    = i % k == k - 1 || i == m - 1;
            suffix[size_t(i)] = end ? at(i) : pick(suffix[size_t(i) + 1], at(i));
        }
        // Element i's window is [i, i + 2r] of the padded array.
        for (int i = 0; i < n; ++i)
            out[i] = pick(suffix[size_t(i)], prefix[size_t(i + 2 * r)]);
    }

    std::vector<float> prefix, suffix;
};

}  // namespace detail
}  // namespace zdenoise
