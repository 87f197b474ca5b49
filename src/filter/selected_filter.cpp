// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// regression_filter() with FilterOptions::select = 1 (docs/FILTER.md
// section 13): today's filter and two feature regressions, and the
// per-pixel choice among them by their estimated error. Stages, in order:
//   regression_filter()    candidate 0, today's filter, its maps and its
//                          hat diagonal D
//   decode_filter_inputs() what the feature regressions fit (outliers
//                          capped), the outliers' spread light, and
//                          radiance_bounds() of their output
//   residual_bounded_variance()  without halves: the noise for SURE and
//                          the pilot, at most what candidate 0's residuals
//                          allow
//   filter_halves()        with halves: every candidate on each half alone
//   feature_regression()   candidates 1 and 2, candidate 0 as their pilot
//   sure_risk() or halves_risk()  each candidate's risk, relative-MSE
//                          weighted
//   select_by_risk()       the choice map and the blend

#include "selected_filter.h"

#include <zdenoise/selection.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>

#include <OpenImageIO/imagebufalgo.h>

#include "filter_inputs.h"
#include "internal.h"

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

/// Outliers are left out of the risk averages (of every candidate alike):
/// a firefly's own squared error would decide its whole neighbourhood.
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

/// The least and the most of the elements within r of each of n elements
/// (stride apart), the window clipped at both ends, by van Herk and
/// Gil-Werman's block prefixes and suffixes: three comparisons an element
/// whatever r. Exact, so any order gives the same floats.
struct SlidingExtrema {
    std::vector<float> prefix_lo, prefix_hi, suffix_lo, suffix_hi;
    void run(const float* lo, const float* hi, int n, size_t stride, int r,
             float* out_lo, float* out_hi)
    {
        const float inf = std::numeric_limits<float>::infinity();
        const int k = 2 * r + 1, m = n + 2 * r;  // padded by r on each side
        prefix_lo.resize(size_t(m)), prefix_hi.resize(size_t(m));
        suffix_lo.resize(size_t(m)), suffix_hi.resize(size_t(m));
        auto at_lo = [&](int i) { return i < r || i >= r + n ? inf : lo[size_t(i - r) * stride]; };
        auto at_hi = [&](int i) { return i < r || i >= r + n ? -inf : hi[size_t(i - r) * stride]; };
        for (int i = 0; i < m; ++i) {
            const bool start = i % k == 0;
            prefix_lo[size_t(i)] = start ? at_lo(i) : std::min(prefix_lo[size_t(i) - 1], at_lo(i));
            prefix_hi[size_t(i)] = start ? at_hi(i) : std::max(prefix_hi[size_t(i) - 1], at_hi(i));
        }
        for (int i = m - 1; i >= 0; --i) {
            const bool end = i % k == k - 1 || i == m - 1;
            suffix_lo[size_t(i)] = end ? at_lo(i) : std::min(suffix_lo[size_t(i) + 1], at_lo(i));
            suffix_hi[size_t(i)] = end ? at_hi(i) : std::max(suffix_hi[size_t(i) + 1], at_hi(i));
        }
        // Element i's window is [i, i + 2r] of the padded array.
        for (int i = 0; i < n; ++i) {
            out_lo[i] = std::min(suffix_lo[size_t(i)], prefix_lo[size_t(i + 2 * r)]);
            out_hi[i] = std::max(suffix_hi[size_t(i)], prefix_hi[size_t(i + 2 * r)]);
        }
    }
};

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
                std::vector<float>& inv_albedo, int nthreads)
{
    const float inf = std::numeric_limits<float>::infinity();
    const ROI rows(out.xbegin, out.xend, std::max(out.ybegin - r_max, in.region.ybegin),
                   std::min(out.yend + r_max, in.region.yend));
    const size_t w = size_t(out.width()), n = out.npixels();
    const int rw = in.region.width();
    // Per channel: the extremes over each row's window, rows.height() rows
    // of w, then over the columns of those.
    std::vector<float> rlo(3 * w * size_t(rows.height())), rhi(rlo.size());
    for_rows(rows, nthreads, [&](int y) {
        const size_t nrow = size_t(rw);
        std::vector<float> vlo(nrow), vhi(nrow), elo(nrow), ehi(nrow);
        SlidingExtrema ext;
        for (int c = 0; c < 3; ++c) {
            for (int u = 0; u < rw; ++u) {
                const size_t i = in.index(in.region.xbegin + u, y);
                const bool fit = (in.cls[i] & kFitPoint) != 0;
                vlo[size_t(u)] = fit ? in.lfit[c][i] : inf;
                vhi[size_t(u)] = fit ? in.lfit[c][i] : -inf;
            }
            ext.run(vlo.data(), vhi.data(), rw, 1, r_max, elo.data(), ehi.data());
            const size_t k = (size_t(c) * size_t(rows.height()) + size_t(y - rows.ybegin)) * w;
            std::copy_n(&elo[size_t(out.xbegin - in.region.xbegin)], w, &rlo[k]);
            std::copy_n(&ehi[size_t(out.xbegin - in.region.xbegin)], w, &rhi[k]);
        }
    });
    lo.assign(3 * n, inf);
    hi.assign(3 * n, -inf);
    inv_albedo.assign(3 * n, 0.0f);
    const int rh = rows.height();
    parallel_for(int64_t(0), int64_t(3 * w), [&](int64_t col) {
        const size_t c = size_t(col) / w, x = size_t(col) % w;
        const size_t ncol = size_t(rh);
        std::vector<float> elo(ncol), ehi(ncol);
        SlidingExtrema ext;
        const size_t first = c * size_t(rh) * w + x;
        ext.run(&rlo[first], &rhi[first], rh, w, r_max, elo.data(), ehi.data());
        for (int y = out.ybegin; y < out.yend; ++y) {
            const size_t k = 3 * (size_t(y - out.ybegin) * w + x) + c;
            lo[k] = elo[size_t(y - rows.ybegin)];
            hi[k] = ehi[size_t(y - rows.ybegin)];
            inv_albedo[k] = in.inv_albedo[c][in.index(out.xbegin + int(x), y)];
        }
    }, paropt_any_length(nthreads));
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
/// the box), and so does `in`. Returns 0 where `s` is 0 (no observation).
std::vector<float>
residual_bounded_variance(const FilterInputs& in, const ROI& pil,
                          const ROI& k0reg, const std::vector<float>& out_l,
                          const std::vector<float>& d0,
                          const std::vector<float>& s, int nthreads)
{
    const int kw = k0reg.width();
    auto at      = [&](int x, int y) {
        return size_t(y - k0reg.ybegin) * size_t(kw) + size_t(x - k0reg.xbegin);
    };
    // Each pixel's term (z_l - out_l)^2 / (1 - 2 D), NaN where it has none.
    std::vector<float> term(k0reg.npixels(), NAN);
    for_rows(k0reg, nthreads, [&](int y) {
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
    for_ranges(np, nthreads, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i)
            if (s[i] > 0.0f) {
                const float d = luminance(&o[0][3 * i]) - luminance(&o[1][3 * i]);
                dif2[i]       = d * d;
            }
    });
    for (int k = 0; k < 2; ++k) {
        const std::vector<float> z = read_channels(half_z[k], pil, 0, 3);
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
    // the pilot over its own, the pilot's noise candidate 0 over its box,
    // and candidate 0 the quotient over the filter's.
    return selection_halo(SelectionOptions {}) + feature_candidates_halo()
           + kVarianceRadius + filter_halo(base);
}


bool
selected_regression_filter(ImageBuf& dst, const ImageBuf& quotient,
                           const ImageBuf& albedo, const Guides& guides,
                           const FilterOptions& options, ROI roi, int nthreads,
                           FilterStats& totals)
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
    ROI k0reg = halo_region(pil, frame, kVarianceRadius);
    ROI qreg = halo_region(k0reg, frame, filter_halo(base));
    sel.chbegin = pil.chbegin = k0reg.chbegin = qreg.chbegin = roi.chbegin = 0;
    sel.chend = pil.chend = k0reg.chend = qreg.chend = roi.chend = nch;
    auto fail = [&](const ImageBuf& from) {
        dst.errorfmt("{}", from.geterror());
        return false;
    };
    auto progress = [&](float lo, float hi) -> std::function<void(float)> {
        if (!options.progress)
            return nullptr;
        return [&, lo, hi](float f) { options.progress(lo + (hi - lo) * f); };
    };

    const size_t np = pil.npixels();
    ImageBuf out0, maps, hat0;
    std::vector<float> o0, o0_l, d0_k0;
    // Candidate 0's noise estimate (section 3) over pil: the standard
    // deviation of z_l at fit points, else 0 (no observation).
    std::vector<float> s(np, 0.0f);
    // What the feature regressions fit: the quotient of the fit points with
    // the outliers capped (section 3a), NaN elsewhere, as candidate 0 fits
    // it; the outliers' spread light is added to them as to candidate 0.
    std::vector<float> zfit(3 * np, NAN);
    std::vector<double> spread(3 * sel.npixels(), 0.0);
    std::vector<float> bound_lo, bound_hi, bound_ia, sigma2;
    {
        // One decode of the inputs for candidate 0 and the selection's own
        // stages: over candidate 0's region and its filter's halo, which
        // holds the receivers of every outlier within r_max of the
        // selection's pixels and the noise estimate's footprint.
        FilterInputs in;
        if (!decode_filter_inputs(in, dst, quotient, albedo, guides, base, qreg,
                                  nthreads))
            return false;
        // Candidate 0 over the pilot's support and its noise's box (with
        // its maps if asked for, and its hat diagonal for SURE).
        ROI r0 = k0reg;
        if (!prepare_dst(out0, quotient, r0, "regression_filter")
            || (options.diagnostics
                && !prepare_diagnostics(out0, maps, k0reg, frame,
                                        "regression_filter"))
            || (!halves
                && !prepare_result(out0, hat0, k0reg, frame, 1,
                                   "regression_filter", "hat diagonal")))
            return fail(out0);
        base.diagnostics = options.diagnostics ? &maps : nullptr;
        base.progress    = progress(0.0f, halves ? 0.3f : 0.6f);
        std::vector<double> k0spread;
        // Its statistics are the output pixels' (roi), as without select.
        if (!filter_decoded(out0, quotient, in, base, k0reg, roi, nthreads,
                            totals, halves ? nullptr : &hat0, &k0spread))
            return fail(out0);
        base.diagnostics = nullptr;
        o0 = read_channels(out0, pil, 0, 3);
        // Candidate 0's light and D over k0reg (D: 1 with halves, unused).
        o0_l = read_channels(out0, k0reg, 0, 3);
        {
            std::vector<float> l(k0reg.npixels());
            for_ranges(l.size(), nthreads, [&](size_t b, size_t e) {
                for (size_t k = b; k < e; ++k)
                    l[k] = luminance(&o0_l[3 * k]);
            });
            o0_l = std::move(l);
        }
        d0_k0 = halves ? std::vector<float>(k0reg.npixels(), 1.0f)
                       : read_channels(hat0, k0reg, 0, 1);
        for_rows(pil, nthreads, [&](int y) {
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
        });
        // The outliers' spread light over sel: candidate 0's (each pixel's
        // sum is the same over any region that holds it).
        for_rows(sel, nthreads, [&](int y) {
            const size_t k  = size_t(y - sel.ybegin) * size_t(sel.width());
            const size_t k0 = size_t(y - k0reg.ybegin) * size_t(k0reg.width())
                              + size_t(sel.xbegin - k0reg.xbegin);
            std::copy_n(&k0spread[3 * k0], 3 * size_t(sel.width()), &spread[3 * k]);
        });
        radiance_bounds(in, sel, base.r_max, bound_lo, bound_hi, bound_ia, nthreads);
        if (!halves)
            sigma2 = residual_bounded_variance(in, pil, k0reg, o0_l, d0_k0, s,
                                               nthreads);
    }

    // What the risks need: with halves, every candidate on each half alone
    // (their cross errors rank them with no noise estimate and no D);
    // without, candidate 0's hat diagonal and the bounded noise. Either
    // gives the variance of candidate 0's luminance, the pilot's.
    std::vector<float> pilot_var(np);
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
        // sum_j H_qj^2 sigma_j^2 ~ D sigma^2.
        for_rows(pil, nthreads, [&](int y) {
            for (int x = pil.xbegin; x < pil.xend; ++x) {
                const size_t i = size_t(y - pil.ybegin) * size_t(pil.width())
                                 + size_t(x - pil.xbegin);
                const float d = d0_k0[size_t(y - k0reg.ybegin) * size_t(k0reg.width())
                                      + size_t(x - k0reg.xbegin)];
                pilot_var[i] = sigma2[i] * std::min(std::max(d, 0.0f), 1.0f);
            }
        });
    }
    ImageBuf pilot = float_image(pil, frame, 4);
    {
        std::vector<float> pv(4 * np);
        for_ranges(np, nthreads, [&](size_t b, size_t e) {
            for (size_t i = b; i < e; ++i) {
                for (int c = 0; c < 3; ++c)
                    pv[4 * i + c] = o0[3 * i + c];
                pv[4 * i + 3] = pilot_var[i];
            }
        });
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
        for_ranges(sel.npixels(), nthreads, [&](size_t b, size_t e) {
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
                    v = saturated_float(double(v) + spread[3 * k + size_t(c)]);
                }
        });
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
        for_rows(sel, nthreads, [&](int y) {
            for (int x = sel.xbegin; x < sel.xend; ++x) {
                const size_t k = size_t(y - sel.ybegin) * size_t(sel.width())
                                 + size_t(x - sel.xbegin);
                const size_t i = size_t(y - pil.ybegin) * size_t(pil.width())
                                 + size_t(x - pil.xbegin);
                for (int c = 0; c < 3; ++c)
                    c0[4 * k + c] = o0[3 * i + c];
                c0[4 * k + 3] = d0_k0[size_t(y - k0reg.ybegin) * size_t(k0reg.width())
                                      + size_t(x - k0reg.xbegin)];
                const float o_l = luminance(&o0[3 * i]);
                const bool outlier = std::fabs(luminance(&z[3 * k]) - o_l)
                                     > kOutlierSigmas * s[i];
                v[k] = outlier ? 0.0f : halves ? s[i] * s[i] : sigma2[i];
                // relMSE (x - ref)^2 / (ref^2 + 0.01) in radiance, written
                // in z: radiance = z (a + albedo_eps).
                const double al = std::max(luminance(&a[3 * k]), 0.0f)
                                  + options.albedo_eps;
                w[k] = halves && !(v[k] > 0.0f)
                           ? NAN
                           : float(al * al / (o_l * o_l * al * al + 0.01));
            }
        });
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
    for_rows(roi, nthreads, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t k = size_t(y - roi.ybegin) * size_t(roi.width())
                             + size_t(x - roi.xbegin);
            const size_t i = size_t(y - pil.ybegin) * size_t(pil.width())
                             + size_t(x - pil.xbegin);
            if (s[i] > 0.0f)
                for (int c = 0; c < 3; ++c)
                    out[size_t(nch) * k + size_t(c)] = rgb[3 * k + size_t(c)];
        }
    });
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
