// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// A recipe's JSON values read as options (recipe.cpp), each error one line
// naming the key and the value.

#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace zdenoise {
namespace job {
namespace recipe_values {

/// Throw `message` with its control characters escaped: it quotes keys
/// and values the recipe or its REST arguments gave, and an error stays
/// one line whatever they hold (a newline in a key; found by
/// tests/fuzz/fuzz_recipe).
[[noreturn]] void
fail_escaped(const std::string& message);

/// A value as the recipe spells it, cut short for messages.
std::string
shown(const nlohmann::json& value);

/// A number.
double
parse_number(const std::string& key, const nlohmann::json& value);

/// A filter option's number: it must fit a float (1e50 would become
/// infinity, which a recipe cannot even be written back with).
float
parse_float(const std::string& key, const nlohmann::json& value);

/// A whole number of at most 1e6 in magnitude.
int
parse_whole_number(const std::string& key, const nlohmann::json& value);

/// A string value; `name`: one that may not be empty.
std::string
parse_string(const std::string& key, const nlohmann::json& value, bool name);

}  // namespace recipe_values
}  // namespace job
}  // namespace zdenoise
