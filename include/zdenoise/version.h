// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// The single source of the version number: CMakeLists.txt reads it from here.
#define ZDENOISE_VERSION_MAJOR 0
#define ZDENOISE_VERSION_MINOR 1
#define ZDENOISE_VERSION_PATCH 0
#define ZDENOISE_VERSION_STRING "0.1.0"
