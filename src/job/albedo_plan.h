// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// How a job makes the albedo it demodulates and remodulates by: the
// render's own prefiltered (docs/FILTER.md section 12), or with --aux the
// auxiliary albedo checked against and pooled with the render's own
// (docs/AUX.md, "Wrong auxiliary pixels"). A step of plan() and of
// run_strip() (job.cpp), beauty mode; in layers mode, which of the
// layers' colours are prefiltered.

#pragma once

#include <string>
#include <vector>

#include <zdenoise/zdenoise.h>

#include "input_files.h"
#include "job_types.h"
#include "layer_conventions.h"
#include "layers_plan.h"

namespace zdenoise {
namespace job {

struct AlbedoPlan {
    /// Samples per pixel for prefilter_albedo() after pooling; 0: none.
    int prefilter = 0;
    /// The albedo (the auxiliary one) is pooled with the render's own
    /// (RoleSelections::own_albedo) by pool_aux_albedo().
    bool pool = false;
    /// The prefilter's variance also from the halves' albedos
    /// (RoleSelections::half_a_albedo, half_b_albedo).
    bool halves = false;
    AuxAlbedoOptions pool_options;

    /// Rows of the albedo read beyond what the filter reads.
    int halo() const
    {
        return (prefilter ? albedo_prefilter_halo() : 0)
               + (pool ? aux_albedo_halo() : 0);
    }
    /// As zdenoise.parameters records it ("" when neither step runs).
    std::string describe() const;
};

/// Decide job `j`'s albedo steps (beauty mode, roles selected): with --aux
/// whose albedo demodulates and an --in file with an albedo of its own,
/// select that one into `roles.own_albedo` and pool; the samples of each
/// from --albedo-samples or the files' Cycles metadata
/// (cycles.<layer>.samples). Says what it decided in `log`.
AlbedoPlan
plan_albedo(const Job& j, InputFiles& files, const Convention& conv,
            RoleSelections& roles, const OIIO::ROI& noisy,
            std::vector<std::string>& log);

/// Layers mode: mark the layers whose colour is the render's own AOV (an
/// average of the pixel's samples, as Cycles' DiffCol, GlossCol, TransCol
/// and the residual's Denoising Albedo; not an --aux colour) to be
/// prefiltered like beauty mode's albedo, the samples from --albedo-samples
/// or the file's Cycles metadata. The plan returned carries the samples
/// (its halo and its zdenoise.parameters entry); make_albedo() is not for
/// it. Says what it decided in `log`.
AlbedoPlan
plan_layer_colours(const Job& j, InputFiles& files, LayersPlan& layers,
                   std::vector<std::string>& log);

/// The strip's albedo by plan `a`, over `region` (what the filter reads):
/// `albedo` pooled with `own` (which is then freed), then prefiltered (with
/// the halves' albedos `half_a`, `half_b` when `a.halves`). The pixels
/// rejected among `core` are added to `totals`. Fails naming `path` (the
/// albedo's file).
void
make_albedo(const AlbedoPlan& a, OIIO::ImageBuf& albedo,
            OIIO::ImageBuf& own, const OIIO::ImageBuf& half_a,
            const OIIO::ImageBuf& half_b, const OIIO::ROI& region,
            const OIIO::ROI& core, int threads, AuxAlbedoStats& totals,
            const std::string& path);

/// The -v line of the pooled pixels over the frame.
std::string
pooled_summary(const AuxAlbedoStats& totals);

}  // namespace job
}  // namespace zdenoise
