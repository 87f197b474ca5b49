// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The weighted least-squares plane of docs/FILTER.md section 5: the moments
// of one fit and their solution, with the predicted variance of the
// plane's value at the centre (the edge test's noise).

#pragma once

#include "internal.h"

namespace zdenoise {
namespace detail {

/// Weighted moments of one least-squares plane fit, in window coordinates
/// u = dx/R, v = dy/R.
struct FitMoments {
    double s[6] = {};     ///< sum w {1, u, v, uu, uv, vv}
    double t[3][3] = {};  ///< per channel: sum w z {1, u, v}
    double n[6] = {};     ///< sum w^2 Vs {1, u, v, uu, uv, vv}
    int count = 0;

    FitMoments& operator+=(const FitMoments& o)
    {
        for (int k = 0; k < 6; ++k) {
            s[k] += o.s[k];
            n[k] += o.n[k];
        }
        for (int ch = 0; ch < 3; ++ch)
            for (int k = 0; k < 3; ++k)
                t[ch][k] += o.t[ch][k];
        count += o.count;
        return *this;
    }
};

/// A solved plane per channel, Z_c = c + a u + b v.
struct Plane {
    bool present = false;
    double c[3] = {}, a[3] = {}, b[3] = {};
    double var0 = 0.0;  ///< predicted variance of the luminance at p0
    /// The quadratic form e^T M^-1 e, e = (1, u, v): a fit point's own
    /// weight times it is the fit's derivative in the point's value
    /// (docs/SELECTION.md 2.2), {m00, 2 m01, 2 m02, m11, 2 m12, m22};
    /// {1 / s0, 0, ...} for a constant.
    double hat[6] = {};

    double at(int ch, double u, double v) const
    {
        return c[ch] + a[ch] * u + b[ch] * v;
    }
    double luminance0() const
    {
        return kLumaWeights[0] * c[0] + kLumaWeights[1] * c[1]
               + kLumaWeights[2] * c[2];
    }
};

/// Solve the normal equations of a fit (in double): absent without weight,
/// a constant with fewer than 3 points or a near-singular matrix.
Plane
solve(const FitMoments& m);

}  // namespace detail
}  // namespace zdenoise
