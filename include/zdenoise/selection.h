// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Filter selection by estimated error (docs/FILTER.md section 13): a second
// candidate filter of the quotient, per-pixel risk estimates of a candidate,
// and the per-pixel choice among candidates by their smoothed risks.
// regression_filter() runs them all when FilterOptions::select is 1; they
// are public so that a pipeline can add candidates of its own, and so that
// each is tested against its reference implementation. Conventions as in
// zdenoise.h (ImageBufAlgo style, bit-identical for every thread count, a
// part of the image computed exactly given its halo and the frame).

#pragma once

#include <atomic>
#include <vector>

#include <zdenoise/zdenoise.h>

namespace zdenoise {

/// Parameters of feature_regression().
struct FeatureRegressionOptions {
    /// Window half-size: each window is (2 radius + 1)^2 pixels.
    int radius = 9;
    /// Windows are centred on every centre_stride-th pixel in x and y of a
    /// lattice anchored at the frame's origin (1 = every pixel).
    int centre_stride = 3;
    /// Half-size of the pilot's patches compared by the patch weight.
    int patch_radius = 1;
    /// Bandwidth of the patch weight in units of the pilot's standard
    /// deviation (Bitterli et al. 2016's k): larger pools more.
    float patch_k = 1.0f;
    /// Ridge on the non-constant features, relative to the window's total
    /// weight: a feature varying by less than about sqrt(ridge) over a
    /// window is left out of its fit rather than fitted to the noise.
    float ridge = 1e-3f;
    /// As FilterOptions::albedo_eps: radiance = z (albedo + albedo_eps).
    float albedo_eps = 1e-3f;
    /// The data window of the whole image (as FilterOptions::frame);
    /// undefined: the quotient's data window.
    ROI frame;
    /// As FilterOptions::cancel: set, the call stops within a row of
    /// windows and returns false with "zdenoise: cancelled", dst holding
    /// no result. Not a filter parameter: it never changes the result.
    const std::atomic<bool>* cancel = nullptr;
};

/// The first-order feature regression of the quotient (docs/FILTER.md
/// section 13.2): in each window, a weighted least-squares fit of z on the
/// features [1, dx, dy, normal - its centre value, depth relative to the
/// centre's], weights = same object id x spatial Gaussian x a patch weight
/// that compares the pilot's patches around the centre and the point,
/// splatted over the window with the same weights (collaboratively), each
/// prediction clamped so that its radiance stays within the radiance the
/// window's points have (it invents no light). The
/// weights read the pilot and guides only, never z, so the filter is linear
/// in z and channel 3 of dst is exact: the hat-matrix diagonal D(q) =
/// d out_l(q) / d z_l(q) that SURE needs (sure_risk()).
///
/// @param dst       4 channels: filtered R, G, B of the quotient and D.
///                  Pixels no window covers (no surface, non-finite) pass
///                  through (0 if not finite) with D = 1.
/// @param quotient  Demodulated radiance z, channels 0-2. A point takes
///                  part when its three values are finite and it has a
///                  surface (a valid depth, when the depth guide is given):
///                  NaN leaves a pixel out.
/// @param albedo    The albedo z was demodulated by, channels 0-2: the
///                  radiance bounds of the clamp.
/// @param pilot     A prior estimate of z (e.g. regression_filter()'s
///                  output), channels 0-2, and in channel 3 the variance of
///                  its luminance: what the patch weight compares.
/// @param guides    Optional normal, depth and object id (channel 0 of an
///                  id image: Cryptomatte's first rank); variance and halves
///                  are not read.
/// Every output pixel depends on inputs at most feature_regression_halo()
/// away.
ZDENOISE_API bool feature_regression(ImageBuf& dst, const ImageBuf& quotient,
                                     const ImageBuf& albedo,
                                     const ImageBuf& pilot,
                                     const Guides& guides = {},
                                     const FeatureRegressionOptions& options = {},
                                     ROI roi = {}, int nthreads = 0);
ZDENOISE_API int feature_regression_halo(const FeatureRegressionOptions& options);

/// Stein's unbiased risk estimate of a candidate's squared error at each
/// pixel (docs/FILTER.md section 13.3), in the luminance of the quotient,
/// weighted: weight * [(out_l - z_l)^2 - var + 2 var D]. Unbiased for
/// weight * E(out_l - mu_l)^2 when the candidate is linear in z with hat
/// diagonal D and the noise of z is independent between pixels.
///
/// @param dst        1 channel; NaN where there is no observation
///                   (variance negative or not finite, or a value not
///                   finite). A noise-free pixel (variance 0) is an
///                   observation: its risk is its exact squared error.
/// @param candidate  The candidate's output: R, G, B and D in channel 3.
/// @param quotient   The noisy z it filtered, channels 0-2.
/// @param variance   Channel 0: the variance of z_l at each pixel.
/// @param weight     Channel 0: the metric's weight of the pixel (e.g. the
///                   relative-MSE weight, FILTER.md 13.3).
/// @param clip_sigmas  When > 0, (out_l - z_l)^2 is taken at most
///                   clip_sigmas^2 var (winsorized): a pixel that every
///                   candidate departs from by more (a firefly) weighs
///                   alike in each candidate's risk instead of deciding
///                   its neighbourhood, while one candidate that departs
///                   from a pixel the others keep (a thin shadow filled
///                   in) still pays for it. Biased low where a candidate
///                   truly departs by more; 0: the unbiased estimate.
ZDENOISE_API bool sure_risk(ImageBuf& dst, const ImageBuf& candidate,
                            const ImageBuf& quotient, const ImageBuf& variance,
                            const ImageBuf& weight, float clip_sigmas = 0.0f,
                            ROI roi = {}, int nthreads = 0);

/// The same risk from two independent half renders (docs/FILTER.md section
/// 13.3): weight * [(F(A)_l - z_B,l)^2 + (F(B)_l - z_A,l)^2] / 2, where F(A)
/// is the candidate run on half A alone. It estimates weight * (MSE of a
/// half's filter + Var z_half): the variance term is common to every
/// candidate, so differences of it rank them with no noise estimate at all.
///
/// @param dst          1 channel; NaN where a value is not finite.
/// @param candidate_a  F(A), channels 0-2 (channel 3 is not read).
/// @param candidate_b  F(B).
/// @param quotient_a   z_A, channels 0-2.
/// @param quotient_b   z_B.
/// @param weight       Channel 0: the metric's weight of the pixel.
ZDENOISE_API bool halves_risk(ImageBuf& dst, const ImageBuf& candidate_a,
                              const ImageBuf& candidate_b,
                              const ImageBuf& quotient_a,
                              const ImageBuf& quotient_b,
                              const ImageBuf& weight, ROI roi = {},
                              int nthreads = 0);

/// Parameters of select_by_risk().
struct SelectionOptions {
    /// Half-size of the box the risk differences are averaged over: one
    /// pixel's estimate is far too noisy to choose by (FILTER.md 13.4).
    int risk_radius = 7;
    /// A pixel leaves candidate 0 for candidate k only where the mean risk
    /// difference is below -confidence standard errors of that mean. 0 (the
    /// default): the candidate of least estimated risk (better than 1 on
    /// average over the public set, not on every case:
    /// bench/results/2026-12-selection-log.md section 9); more is a prior
    /// for candidate 0.
    float confidence = 0.0f;
    /// Half-size of the box the one-hot choice map is averaged over into
    /// blend weights, so that a change of candidate makes no seam.
    int map_radius = 3;
    /// The data window of the whole image; undefined: the first
    /// candidate's data window.
    ROI frame;
    /// As FeatureRegressionOptions::cancel (polled per candidate).
    const std::atomic<bool>* cancel = nullptr;
};

/// The per-pixel choice among candidate filters by their estimated risk
/// (docs/FILTER.md section 13.4): for each candidate k > 0, the difference
/// of its risk to candidate 0's, averaged over a box with its standard
/// error; candidate k where that is the most negative and below
/// -confidence standard errors, else candidate 0; the one-hot choice
/// averaged over a smaller box into weights; dst = the weighted sum of the
/// candidates' R, G, B.
///
/// @param dst         3 channels (R, G, B).
/// @param candidates  2 or more outputs, channels 0-2; candidate 0 is the
///                    default a pixel keeps unless another is clearly
///                    better.
/// @param risks       One risk image per candidate (sure_risk() or
///                    halves_risk()), channel 0; NaN pixels are left out of
///                    the averages (in every candidate alike).
/// @param weights     If not null, receives the blend weight of each
///                    candidate, one channel each, over roi.
ZDENOISE_API bool select_by_risk(ImageBuf& dst,
                                 const std::vector<const ImageBuf*>& candidates,
                                 const std::vector<const ImageBuf*>& risks,
                                 const SelectionOptions& options = {},
                                 ImageBuf* weights = nullptr, ROI roi = {},
                                 int nthreads = 0);
ZDENOISE_API int selection_halo(const SelectionOptions& options);

}  // namespace zdenoise
