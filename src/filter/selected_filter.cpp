// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// regression_filter() with FilterOptions::select = 1 (docs/FILTER.md
// section 13): today's filter and two feature regressions, and the
// per-pixel choice among them by their estimated error. Stages, in order:
//   regression_filter()    candidate 0, today's filter, and its maps
//   decode_filter_inputs() what the feature regressions fit (outliers
//                          capped), the outliers' spread light, and
//                          radiance_bounds() of their output
//   monte_carlo_hat_diagonal()  without halves: candidate 0's D
//   filter_halves()        with halves: every candidate on each half alone
//   feature_regression()   candidates 1 and 2, candidate 0 as their pilot
//   sure_risk() or halves_risk()  each candidate's risk, relative-MSE
//                          weighted
//   select_by_risk()       the choice map and the blend

#include "selected_filter.h"

#include <zdenoise/selection.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>

#include <OpenImageIO/imagebufalgo.h>

#include "filter_inputs.h"
#include "internal.h"
#include "outliers.h"

namespace zdenoise {
namespace detail {

using namespace OIIO;

namespace {

/// Size of the nudge of Monte-Carlo SURE, relative to the local light
/// level: smooth from pixel to pixel (a nudge scaled by the noisy per-pixel
/// sigma makes the neighbours' cross terms explode where sigma dips), small
/// enough that the filter's stops rarely move, large enough for floats.
constexpr float kNudge = 0.02f;

/// The confidence rule of the choice with halves: their cross errors rank
/// the candidates run on one half, at half the samples, and that ranking
/// carries over to the candidates run on (A + B) / 2 only where it is
/// clear (measured: zigzag_steps 4+4 spp 0.00713 with 0, 0.00659 with 1,
/// today's filter alone 0.00665; a synthetic saw-tooth 24 % worse with 0).
/// SURE ranks the candidates of the output itself: 0, the default.
constexpr float kHalvesConfidence = 1.0f;

/// Half-size of the box whose mean |z_l| is the local light level.
constexpr int kScaleRadius = 3;

/// How far the noise estimate of a pixel looks (filter_halo()'s 6).
constexpr int kNoiseFootprint = 6;

/// Outliers are left out of the risk averages (of every candidate alike):
/// a firefly's own squared error would decide its whole neighbourhood.
constexpr float kOutlierSigmas = 4.0f;

/// +1 or -1, a hash of the pixel's position in the frame (relative to its
/// origin): the same for any strip and any data window origin.
float
nudge_sign(int x, int y)
{
    uint32_t h = uint32_t(x) * 0x9E3779B1u ^ (uint32_t(y) * 0x85EBCA77u);
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    h ^= h >> 12;
    return (h & 1u) ? 1.0f : -1.0f;
}

/// Store `v` (all of img's channels a pixel) over the pixels of r.
void
store(ImageBuf& img, ROI r, const std::vector<float>& v)
{
    r.chbegin = 0;
    r.chend   = img.nchannels();
    img.set_pixels(r, TypeFloat, v.data());
}

ImageBuf
float_image(const ROI& r, const ROI& frame, int nch)
{
    return ImageBuf(result_spec(r, frame, nch));
}

/// The feature-regression candidates, after today's filter: NFOR's window
/// (radius 9) and a wider one for light that is smooth over more than
/// today's windows reach (the low-frequency residue at low spp), at a
/// stride that keeps its cost per pixel that of the first.
const std::vector<FeatureRegressionOptions>&
feature_candidates()
{
    static const std::vector<FeatureRegressionOptions> table = [] {
        FeatureRegressionOptions nfor, wide;
        wide.radius        = 15;
        wide.centre_stride = 5;
        return std::vector<FeatureRegressionOptions> { nfor, wide };
    }();
    return table;
}

/// The bounds of the feature regressions' output at each pixel of `out`
/// (docs/FILTER.md section 13.2): per channel, the least and the most
/// radiance of the fit points within r_max (the largest window of today's
/// filter; a Chebyshev square, min and max by rows then columns), and the
/// pixel's 1 / (La + albedo_eps) (0 where not demodulated). A window of
/// the wider feature regression reaches 2 x 15 pixels, and its linear model
/// in the normal extrapolates across facets: without these bounds it put
/// light 1.2x brighter than any within 16 pixels on zigzag_steps.
void
radiance_bounds(const FilterInputs& in, const ROI& out, int r_max,
                std::vector<float>& lo, std::vector<float>& hi,
                std::vector<float>& inv_albedo)
{
    const float inf = std::numeric_limits<float>::infinity();
    const ROI rows(out.xbegin, out.xend, std::max(out.ybegin - r_max, in.region.ybegin),
                   std::min(out.yend + r_max, in.region.yend));
    const size_t w = size_t(out.width()), n = out.npixels();
    std::vector<float> rlo(3 * w * size_t(rows.height())), rhi(rlo.size());
    for (int y = rows.ybegin; y < rows.yend; ++y)
        for (int x = out.xbegin; x < out.xend; ++x) {
            float l[3] = { inf, inf, inf }, h[3] = { -inf, -inf, -inf };
            for (int u = std::max(x - r_max, in.region.xbegin);
                 u < std::min(x + r_max + 1, in.region.xend); ++u) {
                const size_t i = in.index(u, y);
                if (!(in.cls[i] & kFitPoint))
                    continue;
                for (int c = 0; c < 3; ++c) {
                    l[c] = std::min(l[c], in.lfit[c][i]);
                    h[c] = std::max(h[c], in.lfit[c][i]);
                }
            }
            const size_t k = 3 * (size_t(y - rows.ybegin) * w + size_t(x - out.xbegin));
            for (int c = 0; c < 3; ++c)
                rlo[k + size_t(c)] = l[c], rhi[k + size_t(c)] = h[c];
        }
    lo.assign(3 * n, inf);
    hi.assign(3 * n, -inf);
    inv_albedo.assign(3 * n, 0.0f);
    for (int y = out.ybegin; y < out.yend; ++y)
        for (int x = out.xbegin; x < out.xend; ++x) {
            const size_t k = 3 * (size_t(y - out.ybegin) * w + size_t(x - out.xbegin));
            for (int v = std::max(y - r_max, rows.ybegin); v < std::min(y + r_max + 1, rows.yend); ++v) {
                const size_t j = 3 * (size_t(v - rows.ybegin) * w + size_t(x - out.xbegin));
                for (int c = 0; c < 3; ++c) {
                    lo[k + size_t(c)] = std::min(lo[k + size_t(c)], rlo[j + size_t(c)]);
                    hi[k + size_t(c)] = std::max(hi[k + size_t(c)], rhi[j + size_t(c)]);
                }
            }
            for (int c = 0; c < 3; ++c)
                inv_albedo[k + size_t(c)] = in.inv_albedo[c][in.index(x, y)];
        }
}

/// The largest halo of the feature-regression candidates.
int
feature_candidates_halo()
{
    int halo = 0;
    for (const FeatureRegressionOptions& c : feature_candidates())
        halo = std::max(halo, feature_regression_halo(c));
    return halo;
}

/// Candidate 0's hat diagonal over `pil` by Monte-Carlo SURE (Ramani, Blu &
/// Unser 2008): `base` run once more on the quotient nudged by +-kNudge
/// times the local light level (the 7x7 mean of |z_l|, a function of the
/// frame's pixels only, so that every strip nudges a pixel alike) over
/// `qreg`, everything that run reads. `o0` is candidate 0's RGB over pil;
/// d0 keeps 1 where `s` (the noise) is 0: no observation.
bool
monte_carlo_hat_diagonal(ImageBuf& dst, const ImageBuf& quotient,
                         const ImageBuf& albedo, const Guides& guides,
                         const FilterOptions& base, const ROI& pil,
                         const ROI& qreg, const std::vector<float>& o0,
                         const std::vector<float>& s, std::vector<float>& d0,
                         int nthreads)
{
    const ROI& frame = base.frame;
    const int nch    = quotient.nchannels();
    std::vector<float> q = read_channels(quotient, qreg, 0, nch);
    std::vector<float> scale(qreg.npixels(), 0.0f);
    const ROI lreg = halo_region(qreg, frame, kScaleRadius);
    const std::vector<float> zq = read_channels(quotient, lreg, 0, 3);
    for (int y = qreg.ybegin; y < qreg.yend; ++y)
        for (int x = qreg.xbegin; x < qreg.xend; ++x) {
            double sum = 0.0;
            int n      = 0;
            for (int v = std::max(y - kScaleRadius, lreg.ybegin);
                 v < std::min(y + kScaleRadius + 1, lreg.yend); ++v)
                for (int u = std::max(x - kScaleRadius, lreg.xbegin);
                     u < std::min(x + kScaleRadius + 1, lreg.xend); ++u) {
                    const float l = luminance(
                        &zq[3 * (size_t(v - lreg.ybegin) * size_t(lreg.width())
                                 + size_t(u - lreg.xbegin))]);
                    if (std::isfinite(l))
                        sum += std::fabs(l), ++n;
                }
            const size_t j = size_t(y - qreg.ybegin) * size_t(qreg.width())
                             + size_t(x - qreg.xbegin);
            scale[j] = n ? float(kNudge * sum / n) : 0.0f;
            const float d = nudge_sign(x - frame.xbegin, y - frame.ybegin) * scale[j];
            for (int c = 0; c < 3; ++c)
                q[size_t(nch) * j + size_t(c)] += d;
        }
    ImageSpec qspec = quotient.spec();
    qspec.x = qreg.xbegin, qspec.y = qreg.ybegin;
    qspec.width = qreg.width(), qspec.height = qreg.height();
    qspec.set_format(TypeFloat);
    ImageBuf nudged(qspec), nudged_out0;
    nudged.set_pixels(qreg, TypeFloat, q.data());
    q = {};
    if (!regression_filter(nudged_out0, nudged, albedo, guides, base, nullptr,
                           pil, nthreads)) {
        dst.errorfmt("{}", nudged_out0.geterror());
        return false;
    }
    const std::vector<float> o0n = read_channels(nudged_out0, pil, 0, 3);
    d0.assign(pil.npixels(), 1.0f);
    for (size_t i = 0; i < d0.size(); ++i) {
        const int x = pil.xbegin + int(i % size_t(pil.width()));
        const int y = pil.ybegin + int(i / size_t(pil.width()));
        const float nudge = scale[size_t(y - qreg.ybegin) * size_t(qreg.width())
                                  + size_t(x - qreg.xbegin)];
        if (s[i] > 0.0f && nudge > 0.0f)
            d0[i] = nudge_sign(x - frame.xbegin, y - frame.ybegin)
                    * (luminance(&o0n[3 * i]) - luminance(&o0[3 * i])) / nudge;
    }
    return true;
}

/// The candidates run on each half's quotient alone (FILTER.md 13.3):
/// candidate 0 over `pil` with its own noise estimate, then the feature
/// regressions `fos` over `sel`, each with that half's candidate 0 as
/// pilot and the pilot variance (F0(A)_l - F0(B)_l)^2 / 2 (two filtered
/// halves differ by twice a half's filter variance), fitting the half's
/// quotient at the fit points (`s` > 0). Also returns that squared
/// difference over pil (0 where s is 0), and each half's quotient over
/// `qreg`.
bool
filter_halves(ImageBuf& dst, const ImageBuf& albedo, const Guides& guides,
              const FilterOptions& base,
              const std::function<std::function<void(float)>(float, float)>& progress,
              const std::vector<FeatureRegressionOptions>& fos, const ROI& sel,
              const ROI& pil, const ROI& qreg, const std::vector<float>& s,
              ImageBuf half_z[2], ImageBuf half_out0[2],
              std::vector<ImageBuf> half_out1[2], std::vector<float>& dif2,
              int nthreads)
{
    const ROI& frame = base.frame;
    const size_t np  = pil.npixels();
    auto fail = [&](const ImageBuf& from) {
        dst.errorfmt("{}", from.geterror());
        return false;
    };
    Guides own   = guides;  // each half estimates its own noise
    own.half_a   = own.half_b = nullptr;
    own.variance = nullptr;
    const ImageBuf* half[2] = { guides.half_a, guides.half_b };
    std::vector<float> o[2];
    for (int k = 0; k < 2; ++k) {
        if (!demodulate(half_z[k], *half[k], albedo, base.albedo_eps, qreg,
                        nthreads))
            return fail(half_z[k]);
        FilterOptions opt = base;
        opt.progress      = progress(0.3f + 0.25f * float(k), 0.55f + 0.25f * float(k));
        if (!regression_filter(half_out0[k], half_z[k], albedo, own, opt, nullptr,
                               pil, nthreads))
            return fail(half_out0[k]);
        o[k] = read_channels(half_out0[k], pil, 0, 3);
    }
    dif2.assign(np, 0.0f);
    for (size_t i = 0; i < np; ++i)
        if (s[i] > 0.0f) {
            const float d = luminance(&o[0][3 * i]) - luminance(&o[1][3 * i]);
            dif2[i]       = d * d;
        }
    for (int k = 0; k < 2; ++k) {
        const std::vector<float> z = read_channels(half_z[k], pil, 0, 3);
        std::vector<float> pv(4 * np), fz(3 * np, NAN);
        for (size_t i = 0; i < np; ++i) {
            for (int c = 0; c < 3; ++c) {
                pv[4 * i + c] = o[k][3 * i + c];
                if (s[i] > 0.0f)
                    fz[3 * i + c] = z[3 * i + c];
            }
            pv[4 * i + 3] = 0.5f * dif2[i];
        }
        ImageBuf pilot = float_image(pil, frame, 4), fitted = float_image(pil, frame, 3);
        store(pilot, pil, pv);
        store(fitted, pil, fz);
        half_out1[k].resize(fos.size());
        for (size_t f = 0; f < fos.size(); ++f)
            if (!feature_regression(half_out1[k][f], fitted, albedo, pilot, own,
                                    fos[f], sel, nthreads))
                return fail(half_out1[k][f]);
    }
    return true;
}

}  // namespace


int
selected_filter_halo(const FilterOptions& base)
{
    // The choice reads the candidates over its halo, the feature regression
    // the pilot (candidate 0) over its own, candidate 0 and its nudged run
    // the quotient over the filter's, and the nudge its 7x7.
    return selection_halo(SelectionOptions {}) + feature_candidates_halo()
           + filter_halo(base) + kScaleRadius;
}


bool
selected_regression_filter(ImageBuf& dst, const ImageBuf& quotient,
                           const ImageBuf& albedo, const Guides& guides,
                           const FilterOptions& options, FilterStats* stats,
                           ROI roi, int nthreads)
{
    const ROI& frame = options.frame;
    FilterOptions base = options;
    base.select      = 0;
    std::vector<FeatureRegressionOptions> fos = feature_candidates();
    for (FeatureRegressionOptions& f : fos) {
        f.frame      = frame;
        f.albedo_eps = options.albedo_eps;
    }
    const size_t nf     = fos.size();
    const int fo_halo   = feature_candidates_halo();
    const bool halves   = guides.half_a && guides.half_b;
    SelectionOptions so;
    so.frame = frame;
    if (halves)
        so.confidence = kHalvesConfidence;
    const int nch = quotient.nchannels();
    ROI sel = halo_region(roi, frame, selection_halo(so));
    ROI pil = halo_region(sel, frame, fo_halo);
    ROI qreg = halo_region(pil, frame, filter_halo(base));
    sel.chbegin = pil.chbegin = qreg.chbegin = roi.chbegin = 0;
    sel.chend = pil.chend = qreg.chend = roi.chend = nch;
    auto fail = [&](const ImageBuf& from) {
        dst.errorfmt("{}", from.geterror());
        return false;
    };
    auto progress = [&](float lo, float hi) -> std::function<void(float)> {
        if (!options.progress)
            return nullptr;
        return [&, lo, hi](float f) { options.progress(lo + (hi - lo) * f); };
    };

    // Candidate 0 over the pilot's support (with its maps if asked for).
    ImageBuf out0, maps;
    base.diagnostics = options.diagnostics ? &maps : nullptr;
    base.progress    = progress(0.0f, halves ? 0.3f : 0.4f);
    if (!regression_filter(out0, quotient, albedo, guides, base, stats, pil,
                           nthreads))
        return fail(out0);
    base.diagnostics = nullptr;
    const size_t np = pil.npixels();
    const std::vector<float> o0 = read_channels(out0, pil, 0, 3);
    // Its noise estimate (section 3), decoded with the footprint it has in
    // the filter, so that it is the same in any strip: the standard
    // deviation of z_l at fit points, else 0 (no observation).
    std::vector<float> s(np, 0.0f);
    // What the feature regressions fit: the quotient of the fit points with
    // the outliers capped (section 3a), NaN elsewhere, as candidate 0 fits
    // it; the outliers' spread light is added to them as to candidate 0.
    std::vector<float> zfit(3 * np, NAN);
    std::vector<double> spread(3 * sel.npixels(), 0.0);
    std::vector<float> bound_lo, bound_hi, bound_ia;
    {
        // The decode reaches the receivers of every outlier within r_max
        // of the selection's pixels, and the noise estimate's footprint.
        FilterInputs in;
        const int reach = std::max(fo_halo, 2 * base.r_max);
        if (!decode_filter_inputs(in, dst, quotient, albedo, guides, base,
                                  halo_region(sel, frame, reach + kNoiseFootprint),
                                  nthreads))
            return false;
        for (int y = pil.ybegin; y < pil.yend; ++y)
            for (int x = pil.xbegin; x < pil.xend; ++x) {
                const size_t i = in.index(x, y);
                const size_t k = size_t(y - pil.ybegin) * size_t(pil.width())
                                 + size_t(x - pil.xbegin);
                if (in.cls[i] & kFitPoint) {
                    s[k] = std::sqrt(std::max(in.vs[i], 0.0f));
                    for (int c = 0; c < 3; ++c)
                        zfit[3 * k + size_t(c)] = in.zfit[c][i];
                }
            }
        spread_outliers(in, base, sel, spread, nthreads);
        radiance_bounds(in, sel, base.r_max, bound_lo, bound_hi, bound_ia);
    }

    // What the risks need: with halves, every candidate on each half alone
    // (their cross errors rank them with no noise estimate and no D);
    // without, candidate 0's hat diagonal. Either gives the variance of
    // candidate 0's luminance, the pilot's.
    std::vector<float> d0(np, 1.0f), pilot_var(np);
    ImageBuf half_z[2], half_out0[2];
    std::vector<ImageBuf> half_out1[2];
    if (halves) {
        std::vector<float> dif2;
        if (!filter_halves(dst, albedo, guides, base, progress, fos, sel, pil, qreg,
                           s, half_z, half_out0, half_out1, dif2, nthreads))
            return false;
        // E (F(A) - F(B))^2 = 2 Var F(half) ~ 4 Var F((A + B) / 2).
        for (size_t i = 0; i < np; ++i)
            pilot_var[i] = 0.25f * dif2[i];
    } else {
        base.progress = progress(0.4f, 0.8f);
        if (!monte_carlo_hat_diagonal(dst, quotient, albedo, guides, base, pil,
                                      qreg, o0, s, d0, nthreads))
            return false;
        // sum_j H_qj^2 sigma_j^2 ~ D sigma^2.
        for (size_t i = 0; i < np; ++i)
            pilot_var[i] = s[i] * s[i] * std::min(std::max(d0[i], 0.0f), 1.0f);
    }
    ImageBuf pilot = float_image(pil, frame, 4);
    {
        std::vector<float> pv(4 * np);
        for (size_t i = 0; i < np; ++i) {
            for (int c = 0; c < 3; ++c)
                pv[4 * i + c] = o0[3 * i + c];
            pv[4 * i + 3] = pilot_var[i];
        }
        store(pilot, pil, pv);
    }

    // The feature regressions, bounded by the radiance around each pixel,
    // and the outliers' light.
    std::vector<ImageBuf> out1(nf);
    ImageBuf fitted = float_image(pil, frame, 3);
    store(fitted, pil, zfit);
    zfit = {};
    for (size_t f = 0; f < nf; ++f) {
        if (!feature_regression(out1[f], fitted, albedo, pilot, guides, fos[f], sel,
                                nthreads))
            return fail(out1[f]);
        std::vector<float> c1 = read_channels(out1[f], sel, 0, 4);
        for (size_t k = 0; k < sel.npixels(); ++k)
            for (int c = 0; c < 3; ++c) {
                float& v      = c1[4 * k + size_t(c)];
                const float a = bound_ia[3 * k + size_t(c)];
                if (a > 0.0f && bound_lo[3 * k + size_t(c)] <= bound_hi[3 * k + size_t(c)])
                    v = std::min(std::max(v, bound_lo[3 * k + size_t(c)] * a),
                                 bound_hi[3 * k + size_t(c)] * a);
                v = float(double(v) + spread[3 * k + size_t(c)]);
            }
        store(out1[f], sel, c1);
    }

    // Risks over the selection's support: variance (0 at outliers and non
    // fit points: no observation), relative-MSE weight (NaN without an
    // observation, for the halves' risk, which reads no variance).
    const size_t ns = sel.npixels();
    ImageBuf cand0 = float_image(sel, frame, 4), var = float_image(sel, frame, 1),
             weight = float_image(sel, frame, 1);
    {
        const std::vector<float> z = read_channels(quotient, sel, 0, 3);
        const std::vector<float> a = read_channels(albedo, sel, 0, 3);
        std::vector<float> c0(4 * ns), v(ns), w(ns);
        for (int y = sel.ybegin; y < sel.yend; ++y)
            for (int x = sel.xbegin; x < sel.xend; ++x) {
                const size_t k = size_t(y - sel.ybegin) * size_t(sel.width())
                                 + size_t(x - sel.xbegin);
                const size_t i = size_t(y - pil.ybegin) * size_t(pil.width())
                                 + size_t(x - pil.xbegin);
                for (int c = 0; c < 3; ++c)
                    c0[4 * k + c] = o0[3 * i + c];
                c0[4 * k + 3] = d0[i];
                const float o_l = luminance(&o0[3 * i]);
                const bool outlier = std::fabs(luminance(&z[3 * k]) - o_l)
                                     > kOutlierSigmas * s[i];
                v[k] = outlier ? 0.0f : s[i] * s[i];
                // relMSE (x - ref)^2 / (ref^2 + 0.01) in radiance, written
                // in z: radiance = z (a + albedo_eps).
                const double al = std::max(luminance(&a[3 * k]), 0.0f)
                                  + options.albedo_eps;
                w[k] = halves && !(v[k] > 0.0f)
                           ? NAN
                           : float(al * al / (o_l * o_l * al * al + 0.01));
            }
        store(cand0, sel, c0);
        store(var, sel, v);
        store(weight, sel, w);
    }
    ImageBuf risk0, chosen;
    std::vector<ImageBuf> risk1(nf);
    if (halves) {
        if (!halves_risk(risk0, half_out0[0], half_out0[1], half_z[0], half_z[1],
                         weight, sel, nthreads))
            return fail(risk0);
        for (size_t f = 0; f < nf; ++f)
            if (!halves_risk(risk1[f], half_out1[0][f], half_out1[1][f], half_z[0],
                             half_z[1], weight, sel, nthreads))
                return fail(risk1[f]);
    } else {
        if (!sure_risk(risk0, cand0, quotient, var, weight, sel, nthreads))
            return fail(risk0);
        for (size_t f = 0; f < nf; ++f)
            if (!sure_risk(risk1[f], out1[f], quotient, var, weight, sel, nthreads))
                return fail(risk1[f]);
    }
    std::vector<const ImageBuf*> candidates = { &cand0 }, risks = { &risk0 };
    for (size_t f = 0; f < nf; ++f) {
        candidates.push_back(&out1[f]);
        risks.push_back(&risk1[f]);
    }
    if (!select_by_risk(chosen, candidates, risks, so, nullptr, roi, nthreads))
        return fail(chosen);

    // The output: candidate 0 (every channel), with the chosen RGB at the
    // fit points (elsewhere both candidates pass the pixel through).
    std::vector<float> out = read_channels(out0, roi, 0, nch);
    const std::vector<float> rgb = read_channels(chosen, roi, 0, 3);
    for (int y = roi.ybegin; y < roi.yend; ++y)
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t k = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            const size_t i = size_t(y - pil.ybegin) * size_t(pil.width())
                             + size_t(x - pil.xbegin);
            if (s[i] > 0.0f)
                for (int c = 0; c < 3; ++c)
                    out[size_t(nch) * k + size_t(c)] = rgb[3 * k + size_t(c)];
        }
    if (!dst.set_pixels(roi, TypeFloat, out.data())) {
        dst.errorfmt("regression_filter: could not store the result");
        return false;
    }
    if (options.diagnostics) {
        if (!prepare_diagnostics(dst, *options.diagnostics, roi, frame,
                                 "regression_filter"))
            return false;
        ROI r4    = roi;
        r4.chbegin = 0;
        r4.chend   = 4;
        const std::vector<float> m = read_channels(maps, r4, 0, 4);
        options.diagnostics->set_pixels(r4, TypeFloat, m.data());
    }
    if (options.progress)
        options.progress(1.0f);
    return true;
}

}  // namespace detail
}  // namespace zdenoise
