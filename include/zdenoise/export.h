// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// Symbols of libzdenoise are hidden unless marked ZDENOISE_API.
#if defined(_WIN32)
#    if defined(ZDENOISE_EXPORTS)
#        define ZDENOISE_API __declspec(dllexport)
#    else
#        define ZDENOISE_API __declspec(dllimport)
#    endif
#else
#    define ZDENOISE_API __attribute__((visibility("default")))
#endif
