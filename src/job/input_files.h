// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The job's input files: each opened once however many roles it serves,
// its headers checked before any pixel is read (a bad file, or a frame too
// large for memory, is refused first), and the channels of each role
// chosen from them, by name (RoleSelections) rather than by position.
// Separate from job.cpp because it is the one place that knows what a
// file's header must satisfy.

#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "channel_spec.h"
#include "job_types.h"
#include "row_reader.h"

namespace zdenoise {
namespace job {

/// An input file's headers, checked: each part's spec (as an ImageBuf
/// reading it holds it, and as the file has it), and the channel names of
/// all its parts in one list (part k > 0 as part_channel_names() names
/// them).
struct InputHeader {
    /// Part 0, header only (the colour guess reads it). Held, never
    /// copied: copying an ImageBuf reads its pixels.
    std::shared_ptr<const OIIO::ImageBuf> first;
    OIIO::ImageSpec spec;                 ///< part 0's
    std::vector<OIIO::ImageSpec> specs;   ///< every part's
    std::vector<OIIO::ImageSpec> native;  ///< every part's, in the file's types
    std::vector<std::string> channelnames;
    int parts = 1;

    OIIO::ROI window() const
    {
        return OIIO::ROI(spec.x, spec.x + spec.width, spec.y, spec.y + spec.height);
    }
    /// Channel c's pixel type in the file.
    OIIO::TypeDesc format(int c) const
    {
        for (const OIIO::ImageSpec& s : native) {
            if (c < s.nchannels)
                return s.channelformat(c);
            c -= s.nchannels;
        }
        return OIIO::TypeUnknown;
    }
};


/// Input files, each opened once however many roles it serves. Headers
/// are read first (header()), so that a bad file or a frame too large for
/// memory is refused before any pixel is read.
class InputFiles {
public:
    const InputHeader& header(const std::string& path);

    /// The file's rows (rows() needs want() first for every channel used).
    RowReader& rows(const std::string& path);

    /// Channels `indices` of `path` will be read.
    void want(const std::string& path, const std::vector<int>& indices);

    /// Every file with wanted channels.
    std::vector<std::string> paths() const;

private:
    std::map<std::string, InputHeader> m_headers;
    std::map<std::string, std::vector<bool>> m_wanted;
    std::map<std::string, std::unique_ptr<RowReader>> m_rows;
};


/// The channels of one role (the radiance, the albedo, a guide, one term
/// of a layer's sum), chosen from a file's header.
struct Selection {
    std::string path;
    std::vector<int> indices;        ///< in the file's channel list
    std::vector<std::string> names;  ///< the role image's channel names
};

/// A role the job may go without (a guide, the variance, a half).
struct OptionalRole {
    const char* label;  ///< as -v shows it
    Role role;
    bool used = false;
    Selection selection;
};

/// Every channel a job reads, by role.
struct RoleSelections {
    Selection radiance;
    Selection albedo;  ///< beauty mode only (layers bring their own)
    OptionalRole normal { "normal", Role::Normal, false, {} };
    OptionalRole depth { "depth", Role::Depth, false, {} };
    OptionalRole id { "id", Role::ObjectId, false, {} };
    OptionalRole variance { "variance", Role::Variance, false, {} };
    OptionalRole half_a { "half A", Role::Radiance, false, {} };
    OptionalRole half_b { "half B", Role::Radiance, false, {} };
    /// The auxiliary image's albedo, when it remodulates what the render's
    /// own albedo demodulated (beauty mode).
    OptionalRole remodulation { "aux albedo", Role::Albedo, false, {} };
    /// The --in file's own albedo, when an auxiliary one demodulates: the
    /// auxiliary albedo is checked against it and pooled with it
    /// (albedo_plan.h).
    OptionalRole own_albedo { "own albedo", Role::Albedo, false, {} };
    /// Motion vectors, with --temporal (docs/TEMPORAL.md).
    OptionalRole motion { "motion", Role::Motion, false, {} };
    /// The halves' own albedos, whose difference is the prefilter's
    /// variance of the --in file's albedo (plan_albedo()).
    OptionalRole half_a_albedo { "half A albedo", Role::Albedo, false, {} };
    OptionalRole half_b_albedo { "half B albedo", Role::Albedo, false, {} };

    /// The optional roles, in the order -v lists them.
    std::vector<const OptionalRole*> optional() const
    {
        return { &normal, &depth, &id, &variance, &half_a, &half_b,
                 &remodulation, &own_albedo, &motion, &half_a_albedo,
                 &half_b_albedo };
    }
};

/// Choose every role's channels of job `j` (its defaults applied), and
/// want every channel of the --in file (the output takes them all): a
/// missing channel or a file of other pixels fails before any pixel is
/// read.
RoleSelections
select_roles(InputFiles& files, const Job& j, bool layered);

/// Choose the channels of `arg` for `role`, checking they exist and that
/// the file covers the noisy input's pixels (`noisy`, from
/// `reference_path`; none for the noisy input itself).
Selection
select_role(InputFiles& files, const InputArg& arg, Role role,
            const OIIO::ROI* noisy, const std::string& reference_path);

/// Is the auxiliary render `aux` a render of the --in file's shot? Refused
/// with a one-line error naming both files when the two headers say
/// otherwise: another display window (resolution, overscan), pixel aspect
/// or screen window, another camera (its name, or its worldToCamera /
/// worldToNDC matrices), another frame. What a header does not carry is
/// not compared: a file without metadata passes on its size alone.
void
check_same_shot(InputFiles& files, const std::string& aux,
                const std::string& in);

/// The selections of `selections` ('+' between them) of the --in file,
/// each R,G,B: the terms of a sum. Their channels are added to `shown`.
std::vector<Selection>
select_sum(InputFiles& files, const std::string& path,
           const std::string& selections, const OIIO::ROI& noisy,
           std::string& shown);

/// Channels `idx` of `names`, as messages list them: "R,G,B".
std::string
channel_list(const std::vector<std::string>& names,
             const std::vector<int>& idx);

}  // namespace job
}  // namespace zdenoise
