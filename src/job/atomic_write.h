// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Writing an image so that the destination is never half-written.

#pragma once

#include <string>

#include <OpenImageIO/imagebuf.h>

namespace zdenoise {
namespace job {

/// Write `image` to `path` through a temporary file in the same folder,
/// renamed over `path` only once complete. On failure the temporary file is
/// removed, any existing `path` is untouched, and `error` says why.
bool
write_atomically(const OIIO::ImageBuf& image, const std::string& path,
                 std::string& error);

}  // namespace job
}  // namespace zdenoise
