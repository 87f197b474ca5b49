// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Writing an image so that the destination is never half-written.

#pragma once

#include <functional>
#include <string>

#include <OpenImageIO/imagebuf.h>

namespace zdenoise {
namespace job {

/// The temporary file write_atomically() is writing right now, or null.
/// Async-signal-safe, for a handler that must remove it before exiting
/// (zdenoise writes one file at a time).
const char*
temporary_file_in_flight();

/// Write `image` to `path` through a temporary file in the same folder,
/// renamed over `path` only once complete. On failure the temporary file is
/// removed, any existing `path` is untouched, and `error` says why.
bool
write_atomically(const OIIO::ImageBuf& image, const std::string& path,
                 std::string& error);

/// Write `path` the same way, with `write(temporary_path, why)` writing the
/// file's contents (and saying why not when it returns false).
bool
write_atomically(const std::string& path,
                 const std::function<bool(const std::string& temporary_path,
                                          std::string& why)>& write,
                 std::string& error);

/// Write the text file `path` the same way.
bool
write_text_atomically(const std::string& path, const std::string& text,
                      std::string& error);

}  // namespace job
}  // namespace zdenoise
