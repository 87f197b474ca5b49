// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// demodulate() and remodulate(): division by and multiplication with the
// albedo (docs/FILTER.md section 1). One typed loop serves both, as
// OIIO's mul and div share imagebufalgo_muldiv.cpp.

#include <zdenoise/zdenoise.h>

#include <OpenImageIO/half.h>
#include <OpenImageIO/imagebufalgo_util.h>

#include "checks.h"
#include "modulate.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;
using half = Imath::half;

namespace {

enum class Modulation { Divide, Multiply };

template<class Dtype, class Stype, class Atype>
bool
modulate_(ImageBuf& dst, const ImageBuf& src, const ImageBuf& albedo,
          float albedo_eps, Modulation mode, ROI roi, int nthreads)
{
    ImageBufAlgo::parallel_image(roi, paropt(nthreads), [&](ROI r) {
        ImageBuf::Iterator<Dtype> d(dst, r);
        ImageBuf::ConstIterator<Stype> s(src, r);
        ImageBuf::ConstIterator<Atype> a(albedo, r);
        for (; !d.done(); ++d, ++s, ++a) {
            for (int c = r.chbegin; c < r.chend; ++c) {
                float v = s[c];
                if (c < 3) {
                    const float alb = a[c];
                    if (detail::albedo_demodulated(alb, albedo_eps))
                        v = mode == Modulation::Divide
                                ? v / (alb + albedo_eps)
                                : v * (alb + albedo_eps);
                }
                d[c] = v;
            }
        }
    });
    return true;
}


bool
modulate(ImageBuf& dst, const ImageBuf& src, const ImageBuf& albedo,
         float albedo_eps, Modulation mode, ROI roi, int nthreads)
{
    const char* opname = mode == Modulation::Divide ? "demodulate"
                                                    : "remodulate";
    if (!detail::prepare_dst(dst, src, roi, opname))
        return false;
    const char* what = mode == Modulation::Divide ? "radiance" : "quotient";
    if (!detail::check_input(dst, src, opname, what, roi, 3)
        || !detail::check_input(dst, albedo, opname, "albedo", roi, 3))
        return false;
    if (!(albedo_eps > 0.0f) || !std::isfinite(albedo_eps)) {
        dst.errorfmt("{}: albedo_eps must be a positive number, got {}",
                     opname, albedo_eps);
        return false;
    }
    bool ok = false;
    OIIO_DISPATCH_COMMON_TYPES3(ok, opname, modulate_, dst.spec().format,
                                src.spec().format, albedo.spec().format, dst,
                                src, albedo, albedo_eps, mode, roi, nthreads);
    return ok;
}

}  // namespace


bool
demodulate(ImageBuf& dst, const ImageBuf& radiance, const ImageBuf& albedo,
           float albedo_eps, ROI roi, int nthreads)
{
    return modulate(dst, radiance, albedo, albedo_eps, Modulation::Divide, roi,
                    nthreads);
}


ImageBuf
demodulate(const ImageBuf& radiance, const ImageBuf& albedo, float albedo_eps,
           ROI roi, int nthreads)
{
    return detail::returned_image("demodulate", [&](ImageBuf& result) {
        return demodulate(result, radiance, albedo, albedo_eps, roi, nthreads);
    });
}


bool
remodulate(ImageBuf& dst, const ImageBuf& quotient, const ImageBuf& albedo,
           float albedo_eps, ROI roi, int nthreads)
{
    return modulate(dst, quotient, albedo, albedo_eps, Modulation::Multiply,
                    roi, nthreads);
}


bool
detail::remodulation_albedo(ImageBuf& dst, const ImageBuf& albedo,
                            const ImageBuf& remodulation_albedo,
                            float albedo_eps, ROI roi)
{
    const char* opname = "remodulate";
    ROI rgb     = roi;
    rgb.chbegin = 0;
    rgb.chend   = 3;
    if (!check_input(dst, albedo, opname, "albedo", rgb, 3)
        || !check_input(dst, remodulation_albedo, opname,
                        "remodulation albedo", rgb, 3))
        return false;
    ImageSpec spec(rgb, TypeFloat);
    dst.reset(spec);
    std::vector<float> own(rgb.npixels() * 3), clean(own.size());
    if (!albedo.get_pixels(rgb, TypeFloat, own.data())
        || !remodulation_albedo.get_pixels(rgb, TypeFloat, clean.data())) {
        dst.errorfmt("{}: cannot read the albedos", opname);
        return false;
    }
    for (size_t i = 0; i < own.size(); ++i)
        if (albedo_demodulated(own[i], albedo_eps)
            && albedo_demodulated(clean[i], albedo_eps))
            own[i] = clean[i];
    return dst.set_pixels(rgb, TypeFloat, own.data());
}


bool
remodulate(ImageBuf& dst, const ImageBuf& quotient, const ImageBuf& albedo,
           const ImageBuf& remodulation_albedo, float albedo_eps, ROI roi,
           int nthreads)
{
    if (!detail::prepare_dst(dst, quotient, roi, "remodulate"))
        return false;
    ImageBuf effective;
    if (!detail::remodulation_albedo(effective, albedo, remodulation_albedo,
                                     albedo_eps, roi)) {
        dst.errorfmt("{}", effective.geterror());
        return false;
    }
    return remodulate(dst, quotient, effective, albedo_eps, roi, nthreads);
}


ImageBuf
remodulate(const ImageBuf& quotient, const ImageBuf& albedo, float albedo_eps,
           ROI roi, int nthreads)
{
    return detail::returned_image("remodulate", [&](ImageBuf& result) {
        return remodulate(result, quotient, albedo, albedo_eps, roi, nthreads);
    });
}

}  // namespace zdenoise
