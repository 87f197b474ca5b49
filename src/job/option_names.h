// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Filter options by the names the command line gives them ("eta", "rmax"),
// shared by the command line and by recipes (.zdn files), so that a name
// means the same field everywhere.

#pragma once

#include <string>
#include <vector>

#include <zdenoise/zdenoise.h>

namespace zdenoise {
namespace job {

/// One FilterOptions field and its command-line name (without "--").
/// Exactly one of `real` and `whole` is set.
struct FilterOptionName {
    const char* name;
    float FilterOptions::*real = nullptr;
    int FilterOptions::*whole  = nullptr;
};

/// Every parameter of FilterOptions, in the order of `zdenoise --help`.
const std::vector<FilterOptionName>&
filter_option_names();

/// The named parameter sets: "tuned" (FilterOptions' defaults) and "spec"
/// (FilterOptions::algorithm_defaults()). Sets the parameters of `options`
/// (leaving its progress callback alone); false for an unknown name.
bool
apply_preset(const std::string& preset, FilterOptions& options);

/// The preset names, for messages: "tuned, spec".
const char*
preset_names();

/// Parse all of `text` as a finite number; false for anything else
/// ("", "1x", "nan", out of range).
bool
parse_real(const std::string& text, double& value);

/// Parse all of `text` as a whole number of at most 1e6 in magnitude.
bool
parse_whole(const std::string& text, int& value);

}  // namespace job
}  // namespace zdenoise
