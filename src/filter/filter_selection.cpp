// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The risk estimates of a candidate filter and the per-pixel selection
// among candidates by them (docs/FILTER.md sections 13.3-13.4):
//   sure_risk()       Stein's unbiased risk estimate, from D and a variance
//   halves_risk()     the same from two independent halves, no variance
//   select_by_risk()  the choice and the blend (13.4), in stages:
//     check_selection()   its arguments; dst and the weights prepared
//     choose_by_risk()    the choice map: box-averaged risk differences to
//                         candidate 0 and the confidence rule
//     blend_weight()      a candidate's one-hot choice over the map's box
//     blend_candidates()  the candidates' RGB so weighted, normalised

#include <zdenoise/selection.h>

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imagebufalgo_util.h>

#include "filter_inputs.h"
#include "checks.h"
#include "internal.h"

namespace zdenoise {

using namespace OIIO;

namespace {

/// A per-pixel risk over roi from `risk(i)`, each input read over roi.
template<class Risk>
bool
risk_image(ImageBuf& dst, const char* opname, const ImageBuf& first,
           std::initializer_list<std::pair<const ImageBuf*, const char*>> inputs,
           ROI roi, Risk&& risk)
{
    if (!roi.defined())
        roi = first.roi();
    roi.chbegin = 0;
    roi.chend   = 1;
    for (const auto& in : inputs)
        if (!detail::check_input(dst, *in.first, opname, in.second, roi, 1))
            return false;
    if (!detail::prepare_result(dst, dst, roi, first.roi_full(), 1, opname, "the destination"))
        return false;
    std::vector<float> out(roi.npixels());
    risk(out);
    return dst.set_pixels(roi, TypeFloat, out.data());
}

/// Box sums of the plane `v` (width w, height h) over (2 r + 1)^2 clipped
/// to the plane, in double: a horizontal pass then a vertical one, each
/// row or column in a fixed order.
std::vector<double>
box_sum(const std::vector<double>& v, int w, int h, int r, int nthreads)
{
    std::vector<double> row(v.size()), out(v.size());
    parallel_for(int64_t(0), int64_t(h), [&](int64_t y) {
        const double* src = &v[size_t(y) * size_t(w)];
        double* dst       = &row[size_t(y) * size_t(w)];
        for (int x = 0; x < w; ++x) {
            double s = 0.0;
            for (int t = std::max(0, x - r); t <= std::min(w - 1, x + r); ++t)
                s += src[t];
            dst[x] = s;
        }
    }, detail::paropt_any_length(nthreads));
    parallel_for(int64_t(0), int64_t(h), [&](int64_t y) {
        for (int x = 0; x < w; ++x) {
            double s = 0.0;
            for (int t = std::max(0, int(y) - r); t <= std::min(h - 1, int(y) + r); ++t)
                s += row[size_t(t) * size_t(w) + size_t(x)];
            out[size_t(y) * size_t(w) + size_t(x)] = s;
        }
    }, detail::paropt_any_length(nthreads));
    return out;
}

/// select_by_risk()'s arguments: 2 or more candidates and a risk each, the
/// options in range, the inputs over roi (the risks over its halo). Fills
/// in o.frame and roi where undefined; prepares dst and weights.
bool
check_selection(ImageBuf& dst, const std::vector<const ImageBuf*>& candidates,
                const std::vector<const ImageBuf*>& risks, SelectionOptions& o,
                ImageBuf* weights, ROI& roi)
{
    const char* opname = "select_by_risk";
    const int K        = int(candidates.size());
    if (K < 2 || risks.size() != candidates.size()) {
        dst.errorfmt("{}: needs 2 or more candidates and one risk image each "
                     "(got {} and {})", opname, K, risks.size());
        return false;
    }
    for (int k = 0; k < K; ++k)
        if (!candidates[size_t(k)] || !risks[size_t(k)]) {
            dst.errorfmt("{}: candidate or risk {} is missing", opname, k);
            return false;
        }
    if (!o.frame.defined())
        o.frame = candidates[0]->roi();
    if (!roi.defined())
        roi = o.frame;
    if (o.risk_radius < 0 || o.risk_radius > 64 || o.map_radius < 0
        || o.map_radius > 64) {
        dst.errorfmt("{}: options risk_radius = {} and map_radius = {} need "
                     "0..64", opname, o.risk_radius, o.map_radius);
        return false;
    }
    if (!(o.confidence >= 0.0f) || !std::isfinite(o.confidence)) {
        dst.errorfmt("{}: option confidence = {} is invalid: needs a finite "
                     "number >= 0", opname, o.confidence);
        return false;
    }
    if (!detail::check_frame(dst, opname, roi, o.frame))
        return false;
    const ROI region = detail::halo_region(roi, o.frame, selection_halo(o));
    for (int k = 0; k < K; ++k)
        if (!detail::check_input(dst, *candidates[size_t(k)], opname,
                                 "candidate", roi, 3)
            || !detail::check_input(dst, *risks[size_t(k)], opname, "risk",
                                    region, 1))
            return false;
    return detail::prepare_result(dst, dst, roi, o.frame, 3, opname, "the destination")
           && (!weights
               || detail::prepare_result(dst, *weights, roi, o.frame, K, opname,
                                         "the weights image"));
}

/// The choice at each pixel of `region` (FILTER.md 13.4): the candidate
/// with the most negative mean risk difference to candidate 0 over the
/// risk's box, where that is below -confidence standard errors; else 0.
std::vector<int>
choose_by_risk(const std::vector<const ImageBuf*>& risks, const ROI& region,
               const SelectionOptions& o, int nthreads)
{
    const int K = int(risks.size());
    const int w = region.width(), h = region.height();
    const size_t n = region.npixels();
    std::vector<std::vector<float>> r(static_cast<size_t>(K));
    for (int k = 0; k < K; ++k)
        r[size_t(k)] = detail::read_channels(*risks[size_t(k)], region, 0, 1);
    std::vector<int> choice(n, 0);
    std::vector<double> best(n, 0.0);
    for (int k = 1; k < K; ++k) {
        if (detail::cancel_requested(o.cancel))
            break;  // select_by_risk() then reports it
        std::vector<double> d(n, 0.0), d2(n, 0.0), m(n, 0.0);
        detail::for_ranges(n, nthreads, [&](size_t ib, size_t ie) {
            for (size_t i = ib; i < ie; ++i) {
                const float a = r[size_t(k)][i], b = r[0][i];
                if (std::isfinite(a) && std::isfinite(b)) {
                    d[i]  = double(a) - b;
                    d2[i] = d[i] * d[i];
                    m[i]  = 1.0;
                }
            }
        });
        const std::vector<double> s1 = box_sum(d, w, h, o.risk_radius, nthreads);
        const std::vector<double> s2 = box_sum(d2, w, h, o.risk_radius, nthreads);
        const std::vector<double> cnt = box_sum(m, w, h, o.risk_radius, nthreads);
        detail::for_ranges(n, nthreads, [&](size_t ib, size_t ie) {
            for (size_t i = ib; i < ie; ++i) {
                if (cnt[i] < 2.0)
                    continue;
                const double mean = s1[i] / cnt[i];
                const double var  = std::max(0.0, s2[i] / cnt[i] - mean * mean);
                const double se   = std::sqrt(var / (cnt[i] - 1.0));
                if (mean < -o.confidence * se && mean < best[i]) {
                    best[i]   = mean;
                    choice[i] = k;
                }
            }
        });
    }
    return choice;
}

/// Candidate k's blend weight: its one-hot choice averaged over the map's
/// box (unnormalised: a box sum).
std::vector<double>
blend_weight(const std::vector<int>& choice, int k, int w, int h, int map_radius,
             int nthreads)
{
    std::vector<double> onehot(choice.size());
    detail::for_ranges(choice.size(), nthreads, [&](size_t ib, size_t ie) {
        for (size_t i = ib; i < ie; ++i)
            onehot[i] = choice[i] == k ? 1.0 : 0.0;
    });
    return box_sum(onehot, w, h, map_radius, nthreads);
}

/// The output over roi: the candidates' RGB weighted by `alpha` (over
/// `region`) and normalised, and the normalised weights when asked for.
bool
blend_candidates(ImageBuf& dst, ImageBuf* weights,
                 const std::vector<const ImageBuf*>& candidates,
                 const std::vector<std::vector<double>>& alpha, const ROI& roi,
                 const ROI& region, int nthreads)
{
    const int K = int(candidates.size());
    const int w = region.width();
    const size_t nout = roi.npixels();
    std::vector<float> out(3 * nout, 0.0f), wout(weights ? size_t(K) * nout : 0);
    ROI roi3    = roi;
    roi3.chbegin = 0;
    roi3.chend   = 3;
    std::vector<std::vector<float>> c(static_cast<size_t>(K));
    for (int k = 0; k < K; ++k)
        c[size_t(k)] = detail::read_channels(*candidates[size_t(k)], roi3, 0, 3);
    // Each pixel adds its candidates in the order k = 0, 1, ...
    detail::for_rows(roi, nthreads, [&](int y) {
        for (int x = roi.xbegin; x < roi.xend; ++x) {
            const size_t o_ = size_t(y - roi.ybegin) * size_t(roi.width())
                              + size_t(x - roi.xbegin);
            const size_t i = size_t(y - region.ybegin) * size_t(w)
                             + size_t(x - region.xbegin);
            double acc[3] = { 0.0, 0.0, 0.0 }, total = 0.0;
            for (int k = 0; k < K; ++k) {
                const double a = alpha[size_t(k)][i];
                for (int ch = 0; ch < 3; ++ch)
                    acc[ch] += a * c[size_t(k)][3 * o_ + size_t(ch)];
                total += a;
                if (weights)
                    wout[size_t(K) * o_ + size_t(k)] = float(a);
            }
            for (int ch = 0; ch < 3; ++ch)
                out[3 * o_ + size_t(ch)] = float(acc[ch] / total);
            if (weights)
                for (int k = 0; k < K; ++k)
                    wout[size_t(K) * o_ + size_t(k)] /= float(total);
        }
    });
    if (!dst.set_pixels(roi3, TypeFloat, out.data()))
        return false;
    if (weights) {
        ROI rk    = roi;
        rk.chbegin = 0;
        rk.chend   = K;
        return weights->set_pixels(rk, TypeFloat, wout.data());
    }
    return true;
}

}  // namespace


bool
sure_risk(ImageBuf& dst, const ImageBuf& candidate, const ImageBuf& quotient,
          const ImageBuf& variance, const ImageBuf& weight, float clip_sigmas,
          ROI roi, int nthreads)
{
    const char* opname = "sure_risk";
    if (!(clip_sigmas >= 0.0f) || !std::isfinite(clip_sigmas)) {
        dst.errorfmt("sure_risk: clip_sigmas must be 0 or more, got {}",
                     clip_sigmas);
        return false;
    }
    const double clip2 = double(clip_sigmas) * double(clip_sigmas);
    if (!roi.defined())
        roi = candidate.roi();
    if (!detail::check_input(dst, candidate, opname, "candidate", roi, 4)
        || !detail::check_input(dst, quotient, opname, "quotient", roi, 3))
        return false;
    return risk_image(dst, opname, candidate,
                      { { &variance, "variance" }, { &weight, "weight" } }, roi,
                      [&](std::vector<float>& out) {
        const std::vector<float> c = detail::read_channels(candidate, roi, 0, 4);
        const std::vector<float> z = detail::read_channels(quotient, roi, 0, 3);
        const std::vector<float> v = detail::read_channels(variance, roi, 0, 1);
        const std::vector<float> w = detail::read_channels(weight, roi, 0, 1);
        parallel_for(int64_t(0), int64_t(out.size()), [&](int64_t i) {
            const double e   = double(detail::luminance(&c[4 * i])) - detail::luminance(&z[3 * i]);
            const double var = v[size_t(i)];
            // Noise-free (var 0): the exact squared error, never clipped.
            const double e2  = clip2 > 0.0 && var > 0.0 ? std::min(e * e, clip2 * var)
                                                        : e * e;
            const double r   = w[size_t(i)] * (e2 - var + 2.0 * var * c[4 * i + 3]);
            out[size_t(i)]   = var >= 0.0 && std::isfinite(r) ? float(r) : NAN;
        }, detail::paropt_any_length(nthreads));
    });
}


bool
halves_risk(ImageBuf& dst, const ImageBuf& candidate_a,
            const ImageBuf& candidate_b, const ImageBuf& quotient_a,
            const ImageBuf& quotient_b, const ImageBuf& weight, ROI roi,
            int nthreads)
{
    const char* opname = "halves_risk";
    if (!roi.defined())
        roi = candidate_a.roi();
    for (auto [img, name] : { std::pair { &candidate_a, "candidate A" },
                              std::pair { &candidate_b, "candidate B" },
                              std::pair { &quotient_a, "half A" },
                              std::pair { &quotient_b, "half B" } })
        if (!detail::check_input(dst, *img, opname, name, roi, 3))
            return false;
    return risk_image(dst, opname, candidate_a, { { &weight, "weight" } }, roi,
                      [&](std::vector<float>& out) {
        const std::vector<float> fa = detail::read_channels(candidate_a, roi, 0, 3);
        const std::vector<float> fb = detail::read_channels(candidate_b, roi, 0, 3);
        const std::vector<float> za = detail::read_channels(quotient_a, roi, 0, 3);
        const std::vector<float> zb = detail::read_channels(quotient_b, roi, 0, 3);
        const std::vector<float> w  = detail::read_channels(weight, roi, 0, 1);
        parallel_for(int64_t(0), int64_t(out.size()), [&](int64_t i) {
            const double ea = double(detail::luminance(&fa[3 * i])) - detail::luminance(&zb[3 * i]);
            const double eb = double(detail::luminance(&fb[3 * i])) - detail::luminance(&za[3 * i]);
            const double r  = w[size_t(i)] * 0.5 * (ea * ea + eb * eb);
            out[size_t(i)]  = std::isfinite(r) ? float(r) : NAN;
        }, detail::paropt_any_length(nthreads));
    });
}


int
selection_halo(const SelectionOptions& o)
{
    return std::max(o.risk_radius, 0) + std::max(o.map_radius, 0);
}


bool
select_by_risk(ImageBuf& dst, const std::vector<const ImageBuf*>& candidates,
               const std::vector<const ImageBuf*>& risks,
               const SelectionOptions& options, ImageBuf* weights, ROI roi,
               int nthreads)
{
    SelectionOptions o = options;
    const bool dst_was_given = dst.initialized();
    if (!check_selection(dst, candidates, risks, o, weights, roi))
        return false;
    const int K      = int(candidates.size());
    const ROI region = detail::halo_region(roi, o.frame, selection_halo(o));
    const int w = region.width(), h = region.height();
    const std::vector<int> choice = choose_by_risk(risks, region, o, nthreads);
    if (detail::cancel_requested(o.cancel))
        return detail::cancelled(dst, dst_was_given, roi, nthreads);
    std::vector<std::vector<double>> alpha(static_cast<size_t>(K));
    for (int k = 0; k < K; ++k)
        alpha[size_t(k)] = blend_weight(choice, k, w, h, o.map_radius, nthreads);
    if (detail::cancel_requested(o.cancel))
        return detail::cancelled(dst, dst_was_given, roi, nthreads);
    return blend_candidates(dst, weights, candidates, alpha, roi, region,
                            nthreads);
}

}  // namespace zdenoise
