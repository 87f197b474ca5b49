// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The neighbouring frames of --temporal (docs/TEMPORAL.md).

#include "neighbour_frames.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imagebufalgo_util.h>

#include "internal.h"
#include "failure.h"
#include "strips.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

namespace {

/// The neighbour's file that plays the role frame t's `path` plays. The
/// files the user named come first: frame t's job has the conventions'
/// defaults filled in (its albedo may be the --in or --aux file), the
/// neighbours' jobs do not.
std::string
neighbour_path(const Job& j, const Job& nj, const std::string& path)
{
    for (InputArg Job::*m : { &Job::in, &Job::aux, &Job::motion, &Job::albedo,
                              &Job::normal, &Job::depth, &Job::id,
                              &Job::variance, &Job::half_a, &Job::half_b })
        if ((j.*m).given && (nj.*m).given && (j.*m).path == path)
            return (nj.*m).path;
    return path;  // not reached: every selection names one of the inputs
}

}  // namespace


FrameRoles
read_neighbour_roles(const Job& j, const Job& nj, const RoleSelections& roles,
                     InputFiles& frame_files, const ROI& frame_t,
                     const ROI& rows, int threads)
{
    struct Wanted {
        const Selection* selection;
        ImageBuf FrameRoles::*image;
    };
    std::vector<Wanted> wanted = { { &roles.radiance, &FrameRoles::radiance },
                                   { &roles.albedo, &FrameRoles::albedo } };
    const std::pair<const OptionalRole*, ImageBuf FrameRoles::*> optional[]
        = { { &roles.normal, &FrameRoles::normal },
            { &roles.depth, &FrameRoles::depth },
            { &roles.id, &FrameRoles::id },
            { &roles.variance, &FrameRoles::variance },
            { &roles.half_a, &FrameRoles::half_a },
            { &roles.half_b, &FrameRoles::half_b },
            { &roles.motion, &FrameRoles::motion } };
    for (const auto& [role, image] : optional)
        if (role->used)
            wanted.push_back({ &role->selection, image });

    InputFiles files;
    std::vector<Selection> selections;
    for (const Wanted& w : wanted) {
        Selection s = *w.selection;
        s.path      = neighbour_path(j, nj, w.selection->path);
        const InputHeader& h = files.header(s.path);
        if (!(h.window() == frame_t))
            fail(format("'{}' covers other pixels than '{}'", s.path, j.in.path));
        const std::vector<std::string>& names
            = frame_files.header(w.selection->path).channelnames;
        for (int c : s.indices)
            if (size_t(c) >= h.channelnames.size()
                || h.channelnames[size_t(c)] != names[size_t(c)])
                fail(format("'{}' has no channel '{}' where '{}' has it",
                            s.path, names[size_t(c)], w.selection->path));
        files.want(s.path, s.indices);
        selections.push_back(s);
    }
    for (const std::string& path : files.paths()) {
        std::string err;
        files.rows(path).reserve(rows.height());
        if (!files.rows(path).hold(rows.ybegin, rows.yend, threads, err))
            fail(format("cannot read '{}': {}", path, one_line(err)));
    }
    Strip band;
    band.files   = &files;
    band.threads = threads;
    band.core = band.held = ROI(frame_t.xbegin, frame_t.xend, rows.ybegin,
                                rows.yend);
    FrameRoles f;
    for (size_t i = 0; i < wanted.size(); ++i)
        f.*(wanted[i].image) = band.image(selections[i]);  // copies
    return f;
}


ROI
rows_reached(const ImageBuf* flow, const ROI& over, const ROI& frame)
{
    ROI rows(frame.xbegin, frame.xend, over.ybegin, over.yend);
    if (!flow)
        return rows;
    ROI ys  = over;
    ys.chbegin = 1;
    ys.chend   = 2;
    std::vector<float> fy(ys.npixels());
    flow->get_pixels(ys, TypeFloat, fy.data());
    int lo = frame.yend, hi = frame.ybegin - 1;
    for (int y = over.ybegin; y < over.yend; ++y)
        for (size_t i = size_t(y - over.ybegin) * size_t(over.width()),
                    e = i + size_t(over.width());
             i < e; ++i) {
            if (!std::isfinite(fy[i]) || std::fabs(fy[i]) > 1e8f)
                continue;
            const int q = int(std::floor(float(y) + 0.5f + fy[i]));
            lo = std::min(lo, q);
            hi = std::max(hi, q);
        }
    rows.ybegin = std::max(lo, frame.ybegin);
    rows.yend   = std::min(hi + 1, frame.yend);
    if (rows.yend <= rows.ybegin)  // lands nowhere: one row, unused
        rows.yend = (rows.ybegin = std::min(std::max(over.ybegin, frame.ybegin),
                                            frame.yend - 1)) + 1;
    return rows;
}


ImageBuf
vector_flow(const ImageBuf& vectors, int direction, int threads)
{
    const ROI roi = vectors.roi();
    ImageSpec spec(roi.width(), roi.height(), 2, TypeDesc::FLOAT);
    spec.x = roi.xbegin;
    spec.y = roi.ybegin;
    ImageBuf flow(spec);
    // Cycles (bench/temporal/README.md, verified on renders): pixel (x, y)
    // is at (x + X, y - Y) in the previous frame and (x - Z, y + W) in the
    // next. Two channels: the motion since the previous frame, y up.
    const bool cycles = vectors.nchannels() >= 4;
    const int c0      = cycles && direction > 0 ? 2 : 0;
    const float sx    = cycles ? (direction > 0 ? -1.0f : 1.0f) : float(direction);
    const float sy    = -sx;
    ImageBufAlgo::parallel_image(roi, detail::paropt_any_length(threads), [&](ROI r) {
        for (ImageBuf::ConstIterator<float> v(vectors, r); !v.done(); ++v) {
            float* f = static_cast<float*>(flow.pixeladdr(v.x(), v.y()));
            f[0]     = sx * v[c0];
            f[1]     = sy * v[c0 + 1];
        }
    });
    return flow;
}

}  // namespace job
}  // namespace zdenoise
