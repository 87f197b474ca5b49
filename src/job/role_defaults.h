// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// What each role of a job takes when the user named no channels: the --in
// file's convention (a Cycles multilayer file's Denoising Albedo, ...),
// the convention of a file given for a role on its own, and the --aux
// file's albedo and guides. A step of plan() (job.cpp), before any channel
// is selected.

#pragma once

#include <string>
#include <vector>

#include "input_files.h"
#include "job_types.h"
#include "layer_conventions.h"

namespace zdenoise {
namespace job {

/// Fill in the defaults of the convention the --in file follows.
void
apply_defaults(Job& j, const Convention& conv, std::vector<std::string>& log);

/// A role given as a file of its own without a :ch= selection takes what
/// that file's convention names for the role, as --in does, or is refused
/// with the file's layers listed.
void
apply_file_defaults(Job& j, InputFiles& files);

/// --aux: its guides replace the --in file's (not those given by flag or
/// disabled), and its albedo is the albedo when the job has none or the
/// auxiliary one demodulates; otherwise its selection is returned in
/// `remodulation`, to remodulate. Before the --in file's defaults.
void
apply_aux(Job& j, InputFiles& files, AuxConvention& aux,
          std::string& remodulation, std::vector<std::string>& log);

}  // namespace job
}  // namespace zdenoise
