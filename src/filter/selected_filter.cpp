// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// regression_filter() with FilterOptions::select = 1 (docs/FILTER.md
// section 13): today's filter and two feature regressions, and the
// per-pixel choice among them by their estimated error. Stages, in order:
//   run_candidate0()       one decode_filter_inputs() for what follows:
//     filter_candidate0()  candidate 0, today's filter, its maps and its
//                          hat diagonal D                         (13.1)
//     read_fit_points()    what the feature regressions fit (outliers
//                          capped), the noise, the outliers' spread light
//     radiance_bounds()    the bounds of their output (radiance_bounds.cpp)
//     residual_bounded_variance()  without halves: the noise for SURE and
//                          the pilot, at most what candidate 0's residuals
//                          allow                                  (13.3)
//   make_pilot()           candidate 0 and the variance of its light; with
//                          halves, filter_halves(): every candidate on
//                          each half alone                        (13.3)
//   filter_features()      candidates 1 and 2, candidate 0 their pilot,
//                          within radiance_bounds()               (13.2)
//   risk_inputs(), candidate_risks()  each candidate's risk, sure_risk()
//                          or halves_risk(), relative-MSE weighted (13.3)
//   select_by_risk()       the choice map and the blend           (13.4)
//   write_selected()       candidate 0 with the chosen RGB at the fit
//                          points

#include "selected_filter.h"

#include <zdenoise/selection.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>

#include <OpenImageIO/imagebufalgo.h>

#include "decode_inputs.h"
#include "filter_inputs.h"
#include "checks.h"
#include "internal.h"
#include "radiance_bounds.h"
#include "decoded_filter.h"

namespace zdenoise {
namespace detail {

using namespace OIIO;

namespace {

/// The confidence rule of the choice with halves: their cross errors rank
/// the candidates run on one half, at half the samples, and that ranking
/// carries over to the candidates run on (A + B) / 2 only where it is
/// clear (measured: zigzag_steps 4+4 spp 0.00713 with 0, 0.00659 with 1,
/// today's filter alone 0.00665; a synthetic saw-tooth 24 % worse with 0).
/// SURE ranks the candidates of the output itself: 0, the default.
constexpr float kHalvesConfidence = 1.0f;

/// Half-size of the box over which candidate 0's residuals bound the noise
/// (residual_bounded_variance()): 49 residuals, a bound within about 20 %.
constexpr int kVarianceRadius = 3;

/// The bound holds where the filter's noise estimate exceeds it by more
/// than this factor: a mean of 49 squared residuals has a relative standard
/// error of 0.2 for Gaussian noise and several times that for MC's heavy
/// tails, and the minimum of two noisy estimates is biased low (measured:
/// a synthetic saw-tooth 20 % worse than today's filter with 1, 3.5 % with
/// 2; the public set's cornell_textured lamp, where the estimate is 5-10x
/// the truth, is held alike by both).
constexpr float kBoundMargin = 2.0f;

/// The residuals pooled into one pixel's bound are those of pixels whose
/// candidate-0 light is within this factor of its own: MC variance follows
/// the light, so pixels of similar light have similar noise.
constexpr float kLightRatio = 2.0f;

/// Risks winsorize differences beyond this many noise deviations (a
/// firefly's square would decide its neighbourhood; sure_risk()'s
/// clip_sigmas); residual_bounded_variance() leaves such outliers out.
constexpr float kOutlierSigmas = 4.0f;

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

/// The largest halo of the feature-regression candidates.
int
feature_candidates_halo()
{
    int halo = 0;
    for (const FeatureRegressionOptions& c : feature_candidates())
        halo = std::max(halo, feature_regression_halo(c));
    return halo;
}

/// The noise variance of z_l for SURE and for the pilot over `pil`
/// (FILTER.md 13.3): the filter's estimate `s`^2, but at most what candidate
/// 0's residuals allow. For a smoother with hat diagonal D < 1/2,
/// E (z_l - out_l)^2 = sigma^2 (1 - 2 D) + MSE >= sigma^2 (1 - 2 D), so the
/// mean of (z_l - out_l)^2 / (1 - 2 D) over a box bounds sigma^2 from above.
/// The box pools the fit points (not outliers) whose light out_l is within
/// kLightRatio of the pixel's; the bound applies with kBoundMargin. The
/// filter's estimate leaks across a step of the light (its 3x3 residual
/// sees the step) and can exceed the truth there many times, which makes
/// SURE prefer any smoother filter and the pilot's patch weights accept
/// the step: the bound holds both. `out_l` and `d0` cover `k0reg` (pil and
/// the box), and so does `in`. Returns 0 where `s` is 0 (no observation);
/// no result once `cancel` is set (the remaining rows are skipped).
std::vector<float>
residual_bounded_variance(const FilterInputs& in, const ROI& pil,
                          const ROI& k0reg, const std::vector<float>& out_l,
                          const std::vector<float>& d0,
                          const std::vector<float>& s, int nthreads,
                          const std::atomic<bool>* cancel)
{
    const int kw = k0reg.width();
    auto at      = [&](int x, int y) {
        return size_t(y - k0reg.ybegin) * size_t(kw) + size_t(x - k0reg.xbegin);
    };
    // Each pixel's term (z_l - out_l)^2 / (1 - 2 D), NaN where it has none.
    std::vector<float> term(k0reg.npixels(), NAN);
    for_rows(k0reg, nthreads, [&](int y) {
        if (cancel_requested(cancel))
            return;
        for (int x = k0reg.xbegin; x < k0reg.xend; ++x) {
            const size_t i = in.index(x, y), k = at(x, y);
            if (!(in.cls[i] & kFitPoint) || !(d0[k] < 0.5f))
                continue;
            const float sd = std::sqrt(std::max(in.vs[i], 0.0f));
            const float r  = in.zl[i] - out_l[k];
            if (std::fabs(r) <= kOutlierSigmas * sd)
                term[k] = r * r / (1.0f - 2.0f * std::max(d0[k], 0.0f));
        }
    });
    std::vector<float> sigma2(pil.npixels(), 0.0f);
    for_rows(pil, nthreads, [&](int y) {
        if (cancel_requested(cancel))
            return;
        for (int x = pil.xbegin; x < pil.xend; ++x) {
            const size_t j = size_t(y - pil.ybegin) * size_t(pil.width())
                             + size_t(x - pil.xbegin);
            if (!(s[j] > 0.0f))
                continue;
            const float light = out_l[at(x, y)];
            double sum = 0.0;
            int n      = 0;
            for (int v = y - kVarianceRadius; v <= y + kVarianceRadius; ++v)
                for (int u = x - kVarianceRadius; u <= x + kVarianceRadius; ++u) {
                    if (!k0reg.contains(u, v))
                        continue;  // beyond the frame
                    const size_t k  = at(u, v);
                    const float lk  = out_l[k];
                    if (std::isfinite(term[k]) && lk <= kLightRatio * light
                        && light <= kLightRatio * lk)
                        sum += term[k], ++n;
                }
            sigma2[j] = s[j] * s[j];
            if (n)
                sigma2[j] = std::min(sigma2[j], float(kBoundMargin * sum / n));
        }
    });
    return sigma2;
}

/// What the stages share: the arguments, candidate 0's options (select 0),
/// the feature candidates', the choice's, and the regions each stage runs
/// over, each holding the next one's halo (FILTER.md 13.5).
struct Selection {
    ImageBuf& dst;
    const ImageBuf& quotient;
    const ImageBuf& albedo;
    const Guides& guides;
    const FilterOptions& options;
    int nthreads;
    FilterOptions base;
    std::vector<FeatureRegressionOptions> fos;
    SelectionOptions so;
    bool halves;  ///< the risks from halves_risk(), else sure_risk()
    ROI roi;      ///< the output pixels
    ROI counted;  ///< those whose windows and pixels the statistics count
    ROI sel;      ///< the choice's support: the risks, candidates 1 and 2
    ROI pil;      ///< the pilot's: candidate 0 as candidates 1 and 2 read it
    ROI k0reg;    ///< candidate 0's: pil and its noise bound's box
    ROI qreg;     ///< the decoded inputs': k0reg and the filter's halo

    Selection(ImageBuf& dst_, const ImageBuf& quotient_, const ImageBuf& albedo_,
              const Guides& guides_, const FilterOptions& options_, ROI roi_,
              ROI counted_, int nthreads_)
        : dst(dst_), quotient(quotient_), albedo(albedo_), guides(guides_)
        , options(options_), nthreads(nthreads_), base(options_)
        , fos(feature_candidates()), halves(guides_.half_a && guides_.half_b)
        , roi(roi_), counted(counted_)
    {
        const ROI& frame = options.frame;
        base.select      = 0;
        for (FeatureRegressionOptions& f : fos) {
            f.frame      = frame;
            f.albedo_eps = options.albedo_eps;
            f.cancel     = options.cancel;
        }
        so.frame  = frame;
        so.cancel = options.cancel;
        if (halves)
            so.confidence = kHalvesConfidence;
        sel   = halo_region(roi, frame, selection_halo(so));
        pil   = halo_region(sel, frame, feature_candidates_halo());
        k0reg = halo_region(pil, frame, kVarianceRadius);
        qreg  = halo_region(k0reg, frame, filter_halo(base));
        sel.chbegin = pil.chbegin = k0reg.chbegin = qreg.chbegin = roi.chbegin = 0;
        sel.chend = pil.chend = k0reg.chend = qreg.chend = roi.chend
            = quotient.nchannels();
    }

    /// dst takes the error of the stage's image `from`.
    bool fail(const ImageBuf& from) const
    {
        dst.errorfmt("{}", from.geterror());
        return false;
    }

    /// A stage's progress, mapped to [lo, hi] of the whole.
    std::function<void(float)> progress(float lo, float hi) const
    {
        if (!options.progress)
            return nullptr;
        const FilterOptions* o = &options;
        return [o, lo, hi](float f) { o->progress(lo + (hi - lo) * f); };
    }
};

/// Candidate 0's run, and what the stages after it read of it and of the
/// decoded inputs.
struct Candidate0 {
    ImageBuf out0, maps, hat0;
    std::vector<float> o0;     ///< its RGB over pil
    std::vector<float> o0_l;   ///< its light (luminance) over k0reg
    std::vector<float> d0_k0;  ///< its hat diagonal over k0reg (1 with halves)
    /// Its noise estimate (section 3) over pil: the standard deviation of
    /// z_l at fit points, else 0 (no observation).
    std::vector<float> s;
    /// What the feature regressions fit over pil: the quotient of the fit
    /// points with the outliers capped (section 3a), NaN elsewhere, as
    /// candidate 0 fits it.
    std::vector<float> zfit;
    std::vector<double> spread;  ///< the outliers' spread light over sel
    std::vector<float> bound_lo, bound_hi, bound_ia;  ///< radiance_bounds()
    std::vector<float> sigma2;  ///< without halves: the bounded noise over pil
};

/// Every candidate run on each half alone, for halves_risk().
struct HalvesRun {
    ImageBuf z[2], out0[2];
    std::vector<ImageBuf> out1[2];
};

/// The candidates run on each half's quotient alone (FILTER.md 13.3):
/// candidate 0 over `pil` with its own noise estimate, then the feature
/// regressions over `sel`, each with that half's candidate 0 as pilot and
/// the pilot variance (F0(A)_l - F0(B)_l)^2 / 2 (two filtered halves
/// differ by twice a half's filter variance), fitting the half's quotient
/// at the fit points (`s` > 0). Also returns that squared difference over
/// pil (0 where s is 0), and each half's quotient over `qreg`.
bool
filter_halves(const Selection& S, const std::vector<float>& s, HalvesRun& h,
              std::vector<float>& dif2)
{
    const ROI& frame = S.base.frame;
    const ROI& pil   = S.pil;
    const size_t np  = pil.npixels();
    const int nthreads = S.nthreads;
    Guides own   = S.guides;  // each half estimates its own noise
    own.half_a   = own.half_b = nullptr;
    own.variance = nullptr;
    const ImageBuf* half[2] = { S.guides.half_a, S.guides.half_b };
    std::vector<float> o[2];
    for (int k = 0; k < 2; ++k) {
        if (!demodulate(h.z[k], *half[k], S.albedo, S.base.albedo_eps, S.qreg,
                        nthreads))
            return S.fail(h.z[k]);
        FilterOptions opt = S.base;
        opt.progress      = S.progress(0.3f + 0.25f * float(k), 0.55f + 0.25f * float(k));
        if (!regression_filter(h.out0[k], h.z[k], S.albedo, own, opt, nullptr,
                               pil, nthreads))
            return S.fail(h.out0[k]);
        o[k] = read_channels(h.out0[k], pil, 0, 3);
    }
    dif2.assign(np, 0.0f);
    for_ranges(np, nthreads, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i)
            if (s[i] > 0.0f) {
                const float d = luminance(&o[0][3 * i]) - luminance(&o[1][3 * i]);
                dif2[i]       = d * d;
            }
    });
    for (int k = 0; k < 2; ++k) {
        const std::vector<float> z = read_channels(h.z[k], pil, 0, 3);
        std::vector<float> pv(4 * np), fz(3 * np, NAN);
        for_ranges(np, nthreads, [&](size_t b, size_t e) {
            for (size_t i = b; i < e; ++i) {
                for (int c = 0; c < 3; ++c) {
                    pv[4 * i + c] = o[k][3 * i + c];
                    if (s[i] > 0.0f)
                        fz[3 * i + c] = z[3 * i + c];
                }
                pv[4 * i + 3] = 0.5f * dif2[i];
            }
        });
        ImageBuf pilot = float_image(pil, frame, 4), fitted = float_image(pil, frame, 3);
        store(pilot, pil, pv);
        store(fitted, pil, fz);
        h.out1[k].resize(S.fos.size());
        for (size_t f = 0; f < S.fos.size(); ++f)
            if (!feature_regression(h.out1[k][f], fitted, S.albedo, pilot, own,
                                    S.fos[f], S.sel, nthreads))
                return S.fail(h.out1[k][f]);
    }
    return true;
}

/// Candidate 0 over k0reg (FILTER.md 13.1), with its maps if asked for
/// and, without halves, its hat diagonal for SURE; its statistics are the
/// output pixels' (roi), as without select. Reads back its RGB over pil,
/// and its light and D over k0reg.
bool
filter_candidate0(Selection& S, const FilterInputs& in, FilterStats& totals,
                  Candidate0& c0, std::vector<double>& k0spread)
{
    const ROI& frame = S.options.frame;
    ROI r0           = S.k0reg;
    if (!prepare_dst(c0.out0, S.quotient, r0, "regression_filter")
        || (S.options.diagnostics
            && !prepare_diagnostics(c0.out0, c0.maps, S.k0reg, frame,
                                    "regression_filter"))
        || (!S.halves
            && !prepare_result(c0.out0, c0.hat0, S.k0reg, frame, 1,
                               "regression_filter", "hat diagonal")))
        return S.fail(c0.out0);
    S.base.diagnostics = S.options.diagnostics ? &c0.maps : nullptr;
    S.base.progress    = S.progress(0.0f, S.halves ? 0.3f : 0.6f);
    if (!filter_decoded(c0.out0, S.quotient, in, S.base, S.k0reg, S.counted,
                        S.nthreads, totals, S.halves ? nullptr : &c0.hat0,
                        &k0spread))
        return S.fail(c0.out0);
    S.base.diagnostics = nullptr;
    c0.o0   = read_channels(c0.out0, S.pil, 0, 3);
    c0.o0_l = read_channels(c0.out0, S.k0reg, 0, 3);
    {
        std::vector<float> l(S.k0reg.npixels());
        for_ranges(l.size(), S.nthreads, [&](size_t b, size_t e) {
            for (size_t k = b; k < e; ++k)
                l[k] = luminance(&c0.o0_l[3 * k]);
        });
        c0.o0_l = std::move(l);
    }
    c0.d0_k0 = S.halves ? std::vector<float>(S.k0reg.npixels(), 1.0f)
                        : read_channels(c0.hat0, S.k0reg, 0, 1);
    return true;
}

/// From the decoded inputs: the noise and what the feature regressions fit
/// at pil's fit points, and over sel the outliers' spread light, candidate
/// 0's (each pixel's sum is the same over any region that holds it).
void
read_fit_points(const Selection& S, const FilterInputs& in,
                const std::vector<double>& k0spread, Candidate0& c0)
{
    const ROI &pil = S.pil, &sel = S.sel, &k0reg = S.k0reg;
    for_rows(pil, S.nthreads, [&](int y) {
        for (int x = pil.xbegin; x < pil.xend; ++x) {
            const size_t i = in.index(x, y);
            const size_t k = size_t(y - pil.ybegin) * size_t(pil.width())
                             + size_t(x - pil.xbegin);
            if (in.cls[i] & kFitPoint) {
                c0.s[k] = std::sqrt(std::max(in.vs[i], 0.0f));
                for (int c = 0; c < 3; ++c)
                    c0.zfit[3 * k + size_t(c)] = in.zfit[c][i];
            }
        }
    });
    for_rows(sel, S.nthreads, [&](int y) {
        const size_t k  = size_t(y - sel.ybegin) * size_t(sel.width());
        const size_t k0 = size_t(y - k0reg.ybegin) * size_t(k0reg.width())
                          + size_t(sel.xbegin - k0reg.xbegin);
        std::copy_n(&k0spread[3 * k0], 3 * size_t(sel.width()), &c0.spread[3 * k]);
    });
}

/// One decode of the inputs over qreg (it holds the receivers of every
/// outlier within r_max of the selection's pixels and the noise estimate's
/// footprint) for candidate 0 and the selection's own stages: candidate 0,
/// the fit points, radiance_bounds() over sel and, without halves,
/// residual_bounded_variance() over pil.
bool
run_candidate0(Selection& S, FilterStats& totals, Candidate0& c0)
{
    const size_t np = S.pil.npixels();
    c0.s.assign(np, 0.0f);
    c0.zfit.assign(3 * np, NAN);
    c0.spread.assign(3 * S.sel.npixels(), 0.0);
    FilterInputs in;
    if (!decode_filter_inputs(in, S.dst, S.quotient, S.albedo, S.guides, S.base,
                              S.qreg, S.nthreads))
        return false;
    std::vector<double> k0spread;
    if (!filter_candidate0(S, in, totals, c0, k0spread))
        return false;
    read_fit_points(S, in, k0spread, c0);
    radiance_bounds(in, S.sel, S.base.r_max, c0.bound_lo, c0.bound_hi,
                    c0.bound_ia, S.nthreads, S.options.cancel);
    if (cancel_requested(S.options))
        return false;
    if (!S.halves)
        c0.sigma2 = residual_bounded_variance(in, S.pil, S.k0reg, c0.o0_l,
                                              c0.d0_k0, c0.s, S.nthreads,
                                              S.options.cancel);
    return true;
}

/// The feature regressions' pilot over pil: candidate 0's RGB and the
/// variance of its luminance. With halves, from every candidate run on each
/// half alone (their cross errors rank them with no noise estimate and no
/// D); without, from candidate 0's hat diagonal and the bounded noise.
bool
make_pilot(const Selection& S, const Candidate0& c0, HalvesRun& h,
           ImageBuf& pilot)
{
    const ROI &pil = S.pil, &k0reg = S.k0reg;
    const size_t np = pil.npixels();
    std::vector<float> pilot_var(np);
    if (S.halves) {
        std::vector<float> dif2;
        if (!filter_halves(S, c0.s, h, dif2))
            return false;
        // E (F(A) - F(B))^2 = 2 Var F(half) ~ 4 Var F((A + B) / 2).
        for (size_t i = 0; i < np; ++i)
            pilot_var[i] = 0.25f * dif2[i];
    } else {
        // sum_j H_qj^2 sigma_j^2 ~ D sigma^2.
        for_rows(pil, S.nthreads, [&](int y) {
            for (int x = pil.xbegin; x < pil.xend; ++x) {
                const size_t i = size_t(y - pil.ybegin) * size_t(pil.width())
                                 + size_t(x - pil.xbegin);
                const float d = c0.d0_k0[size_t(y - k0reg.ybegin) * size_t(k0reg.width())
                                         + size_t(x - k0reg.xbegin)];
                pilot_var[i] = c0.sigma2[i] * std::min(std::max(d, 0.0f), 1.0f);
            }
        });
    }
    pilot = float_image(pil, S.options.frame, 4);
    std::vector<float> pv(4 * np);
    for_ranges(np, S.nthreads, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
            for (int c = 0; c < 3; ++c)
                pv[4 * i + c] = c0.o0[3 * i + c];
            pv[4 * i + 3] = pilot_var[i];
        }
    });
    store(pilot, pil, pv);
    return true;
}

/// Candidates 1 and 2 over sel (FILTER.md 13.2): the feature regressions
/// of zfit, bounded by the radiance around each pixel, and the outliers'
/// light added.
bool
filter_features(const Selection& S, Candidate0& c0, const ImageBuf& pilot,
                std::vector<ImageBuf>& out1)
{
    const ROI &pil = S.pil, &sel = S.sel;
    const std::vector<float>&bound_lo = c0.bound_lo, &bound_hi = c0.bound_hi,
                            &bound_ia = c0.bound_ia;
    ImageBuf fitted = float_image(pil, S.options.frame, 3);
    store(fitted, pil, c0.zfit);
    c0.zfit = {};
    for (size_t f = 0; f < S.fos.size(); ++f) {
        if (!feature_regression(out1[f], fitted, S.albedo, pilot, S.guides,
                                S.fos[f], sel, S.nthreads))
            return S.fail(out1[f]);
        std::vector<float> c1 = read_channels(out1[f], sel, 0, 4);
        for_ranges(sel.npixels(), S.nthreads, [&](size_t b, size_t e) {
            for (size_t k = b; k < e; ++k)
                for (int c = 0; c < 3; ++c) {
                    float& v      = c1[4 * k + size_t(c)];
                    const float a = bound_ia[3 * k + size_t(c)];
                    if (a > 0.0f && bound_lo[3 * k + size_t(c)] <= bound_hi[3 * k + size_t(c)]) {
                        // Saturated at the largest float, as the splats bound
                        // theirs (splat_kernel.cpp).
                        constexpr float largest = std::numeric_limits<float>::max();
                        const float lo = std::clamp(bound_lo[3 * k + size_t(c)] * a, -largest, largest);
                        const float hi = std::clamp(bound_hi[3 * k + size_t(c)] * a, -largest, largest);
                        v = std::min(std::max(std::isnan(v) ? 0.0f : v, lo), hi);
                    }
                    v = saturated_float(double(v) + c0.spread[3 * k + size_t(c)]);
                }
        });
        store(out1[f], sel, c1);
    }
    return true;
}

/// What the risks read over sel (FILTER.md 13.3): candidate 0 with its hat
/// diagonal, the noise variance (0 at outliers and non fit points: no
/// observation), the relative-MSE weight (NaN without an observation, for
/// the halves' risk, which reads no variance).
struct RiskInputs {
    ImageBuf cand0, var, weight;
};

RiskInputs
risk_inputs(const Selection& S, const Candidate0& c0)
{
    const ROI &sel = S.sel, &pil = S.pil, &k0reg = S.k0reg;
    const ROI& frame = S.options.frame;
    const size_t ns  = sel.npixels();
    RiskInputs r { float_image(sel, frame, 4), float_image(sel, frame, 1),
                   float_image(sel, frame, 1) };
    const std::vector<float> z = read_channels(S.quotient, sel, 0, 3);
    const std::vector<float> a = read_channels(S.albedo, sel, 0, 3);
    std::vector<float> c0v(4 * ns), v(ns), w(ns);
    for_rows(sel, S.nthreads, [&](int y) {
        for (int x = sel.xbegin; x < sel.xend; ++x) {
            const size_t k = size_t(y - sel.ybegin) * size_t(sel.width())
                             + size_t(x - sel.xbegin);
            const size_t i = size_t(y - pil.ybegin) * size_t(pil.width())
                             + size_t(x - pil.xbegin);
            for (int c = 0; c < 3; ++c)
                c0v[4 * k + c] = c0.o0[3 * i + c];
            c0v[4 * k + 3] = c0.d0_k0[size_t(y - k0reg.ybegin) * size_t(k0reg.width())
                                      + size_t(x - k0reg.xbegin)];
            const float o_l = luminance(&c0.o0[3 * i]);
            // Halves' risk has no noise level to winsorize at: left out.
            const bool outlier = S.halves
                                 && std::fabs(luminance(&z[3 * k]) - o_l)
                                        > kOutlierSigmas * c0.s[i];
            v[k] = outlier ? 0.0f : S.halves ? c0.s[i] * c0.s[i] : c0.sigma2[i];
            // relMSE (x - ref)^2 / (ref^2 + 0.01) in radiance, written
            // in z: radiance = z (a + albedo_eps).
            const double al = std::max(luminance(&a[3 * k]), 0.0f)
                              + S.options.albedo_eps;
            w[k] = S.halves && !(v[k] > 0.0f)
                       ? NAN
                       : float(al * al / (o_l * o_l * al * al + 0.01));
        }
    });
    store(r.cand0, sel, c0v);
    store(r.var, sel, v);
    store(r.weight, sel, w);
    return r;
}

/// Each candidate's risk over sel: halves_risk() of its runs on the halves,
/// else sure_risk().
bool
candidate_risks(const Selection& S, const RiskInputs& in, const HalvesRun& h,
                const std::vector<ImageBuf>& out1, ImageBuf& risk0,
                std::vector<ImageBuf>& risk1)
{
    const ROI& sel = S.sel;
    if (S.halves) {
        if (!halves_risk(risk0, h.out0[0], h.out0[1], h.z[0], h.z[1], in.weight,
                         sel, S.nthreads))
            return S.fail(risk0);
        for (size_t f = 0; f < out1.size(); ++f)
            if (!halves_risk(risk1[f], h.out1[0][f], h.out1[1][f], h.z[0], h.z[1],
                             in.weight, sel, S.nthreads))
                return S.fail(risk1[f]);
    } else {
        if (!sure_risk(risk0, in.cand0, S.quotient, in.var, in.weight,
                       kOutlierSigmas, sel, S.nthreads))
            return S.fail(risk0);
        for (size_t f = 0; f < out1.size(); ++f)
            if (!sure_risk(risk1[f], out1[f], S.quotient, in.var, in.weight,
                           kOutlierSigmas, sel, S.nthreads))
                return S.fail(risk1[f]);
    }
    return true;
}

/// The output over roi: candidate 0 (every channel), with the chosen RGB at
/// the fit points (elsewhere both candidates pass the pixel through), and
/// candidate 0's maps.
bool
write_selected(const Selection& S, const Candidate0& c0, const ImageBuf& chosen)
{
    const ROI &roi = S.roi, &pil = S.pil;
    const int nch  = S.quotient.nchannels();
    std::vector<float> out = read_channels(c0.out0, roi, 0, nch);
    const std::vector<float> rgb = read_channels(chosen, roi, 0, 3);
    for_rows(roi, S.nthreads, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t k = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            const size_t i = size_t(y - pil.ybegin) * size_t(pil.width())
                             + size_t(x - pil.xbegin);
            if (c0.s[i] > 0.0f)
                for (int c = 0; c < 3; ++c)
                    out[size_t(nch) * k + size_t(c)] = rgb[3 * k + size_t(c)];
        }
    });
    if (!S.dst.set_pixels(roi, TypeFloat, out.data())) {
        S.dst.errorfmt("regression_filter: could not store the result");
        return false;
    }
    if (S.options.diagnostics) {
        if (!prepare_diagnostics(S.dst, *S.options.diagnostics, roi,
                                 S.options.frame, "regression_filter"))
            return false;
        ROI r4     = roi;
        r4.chbegin = 0;
        r4.chend   = 4;
        const std::vector<float> m = read_channels(c0.maps, r4, 0, 4);
        S.options.diagnostics->set_pixels(r4, TypeFloat, m.data());
    }
    if (S.options.progress)
        S.options.progress(1.0f);
    return true;
}

}  // namespace


int
selected_filter_halo(const FilterOptions& base)
{
    // The choice reads the candidates over its halo, the feature regression
    // the pilot over its own, the pilot's noise candidate 0 over its box,
    // and candidate 0 the quotient over the filter's.
    return selection_halo(SelectionOptions {}) + feature_candidates_halo()
           + kVarianceRadius + filter_halo(base);
}


bool
selected_regression_filter(ImageBuf& dst, const ImageBuf& quotient,
                           const ImageBuf& albedo, const Guides& guides,
                           const FilterOptions& options, ROI roi,
                           const ROI& counted, int nthreads, FilterStats& totals)
{
    // Cancelled (FilterOptions::cancel): false between stages, and the
    // stages that take long (candidate 0, the feature regressions) stop
    // within; regression_filter() gives the message.
    auto stopped = [&] { return cancel_requested(options); };
    Selection S(dst, quotient, albedo, guides, options, roi, counted, nthreads);
    Candidate0 c0;
    if (!run_candidate0(S, totals, c0) || stopped())
        return false;
    HalvesRun h;
    ImageBuf pilot;
    if (!make_pilot(S, c0, h, pilot) || stopped())
        return false;
    const size_t nf = S.fos.size();
    std::vector<ImageBuf> out1(nf);
    if (!filter_features(S, c0, pilot, out1) || stopped())
        return false;
    const RiskInputs ri = risk_inputs(S, c0);
    ImageBuf risk0, chosen;
    std::vector<ImageBuf> risk1(nf);
    if (stopped() || !candidate_risks(S, ri, h, out1, risk0, risk1) || stopped())
        return false;
    std::vector<const ImageBuf*> candidates = { &ri.cand0 }, risks = { &risk0 };
    for (size_t f = 0; f < nf; ++f) {
        candidates.push_back(&out1[f]);
        risks.push_back(&risk1[f]);
    }
    if (!select_by_risk(chosen, candidates, risks, S.so, nullptr, S.roi, nthreads))
        return stopped() ? false : S.fail(chosen);
    return !stopped() && write_selected(S, c0, chosen);
}

}  // namespace detail
}  // namespace zdenoise
