// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// classify_pixels(): the pixel classes of docs/FILTER.md section 2 (surface,
// fit point, receiver channels), the luminance of the fit points and the
// inverse depth the guide weight reads.

#include "pixel_classes.h"

#include <cmath>

#include "internal.h"

namespace zdenoise {
namespace detail {

void
classify_pixels(FilterInputs& in, const std::vector<float>& z,
                const std::vector<float>& albedo,
                const std::vector<float>& alpha,
                const std::vector<float>& depth, float albedo_eps,
                int nthreads)
{
    const size_t npix = in.region.npixels();
    in.cls.assign(npix, 0);
    in.zl.assign(npix, 0.0f);
    if (!depth.empty())
        in.invdepth.assign(npix, 0.0f);
    const float eps_a = albedo_eps;
    for_rows(in.region, nthreads, [&](int y) {
        for (size_t i = in.index(in.region.xbegin, y), e = i + in.width; i < e;
             ++i) {
            bool surface = alpha.empty() || alpha[i] > 0.0f;
            if (!depth.empty()) {
                const float d = depth[i];
                surface       = surface && std::isfinite(d) && d > 0.0f
                          && d < 1e9f;
                if (surface)
                    in.invdepth[i] = 1.0f / d;
            }
            uint8_t cls  = surface ? kSurface : 0;
            bool all_fit = surface;
            for (int c = 0; c < 3; ++c) {
                const bool finite = std::isfinite(z[3 * i + c]);
                if (!finite)
                    cls |= kNonFinite;
                const bool demod = albedo_demodulated(albedo[3 * i + c], eps_a);
                if (surface && demod)
                    cls |= uint8_t(kReceiveR << c);
                all_fit = all_fit && demod
                          && std::fabs(z[3 * i + c]) <= kLargestFitQuotient;
            }
            if (all_fit) {
                cls |= kFitPoint;
                const float* zp = &z[3 * i];
                in.zl[i] = kLumaWeights[0] * zp[0] + kLumaWeights[1] * zp[1]
                           + kLumaWeights[2] * zp[2];
            }
            in.cls[i] = cls;
        }
    });
}

}  // namespace detail
}  // namespace zdenoise
