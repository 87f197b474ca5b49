// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// solve(): the five-plane fit's normal equations (docs/FILTER.md section 5).

#include "plane_fit.h"

#include <algorithm>

namespace zdenoise {
namespace detail {

Plane
solve(const FitMoments& m)
{
    Plane p;
    const double* s = m.s;
    if (!(s[0] > 0.0))
        return p;
    p.present = true;
    // Cofactors of the symmetric normal matrix [[s0 s1 s2][s1 s3 s4][s2 s4 s5]].
    const double c00 = s[3] * s[5] - s[4] * s[4];
    const double c01 = s[2] * s[4] - s[1] * s[5];
    const double c02 = s[1] * s[4] - s[2] * s[3];
    const double c11 = s[0] * s[5] - s[2] * s[2];
    const double c12 = s[1] * s[2] - s[0] * s[4];
    const double c22 = s[0] * s[3] - s[1] * s[1];
    const double det = s[0] * c00 + s[1] * c01 + s[2] * c02;
    if (m.count < 3 || !(det > 1e-6 * s[0] * s[0] * s[0])) {
        for (int ch = 0; ch < 3; ++ch)
            p.c[ch] = m.t[ch][0] / s[0];
        p.var0   = m.n[0] / (s[0] * s[0]);
        p.hat[0] = 1.0 / s[0];
        return p;
    }
    const double inv[3][3] = { { c00 / det, c01 / det, c02 / det },
                               { c01 / det, c11 / det, c12 / det },
                               { c02 / det, c12 / det, c22 / det } };
    for (int ch = 0; ch < 3; ++ch) {
        const double* t = m.t[ch];
        p.c[ch] = inv[0][0] * t[0] + inv[0][1] * t[1] + inv[0][2] * t[2];
        p.a[ch] = inv[1][0] * t[0] + inv[1][1] * t[1] + inv[1][2] * t[2];
        p.b[ch] = inv[2][0] * t[0] + inv[2][1] * t[1] + inv[2][2] * t[2];
    }
    const double hat[6] = { inv[0][0], 2.0 * inv[0][1], 2.0 * inv[0][2],
                            inv[1][1], 2.0 * inv[1][2], inv[2][2] };
    std::copy(hat, hat + 6, p.hat);
    // Sandwich variance of the value at p0: r^T N r with r = M^-1 e0.
    const double r[3] = { inv[0][0], inv[1][0], inv[2][0] };
    const double* n   = m.n;
    p.var0 = r[0] * (n[0] * r[0] + n[1] * r[1] + n[2] * r[2])
             + r[1] * (n[1] * r[0] + n[3] * r[1] + n[4] * r[2])
             + r[2] * (n[2] * r[0] + n[4] * r[1] + n[5] * r[2]);
    return p;
}

}  // namespace detail
}  // namespace zdenoise
