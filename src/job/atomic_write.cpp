// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "atomic_write.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

namespace zdenoise {
namespace job {

using OIIO::Strutil::fmt::format;
namespace Filesystem = OIIO::Filesystem;

bool
write_atomically(const OIIO::ImageBuf& image, const std::string& path,
                 std::string& error)
{
    // Same folder (so the rename is atomic), hidden name, same extension (so
    // that the format is chosen from it).
    std::string dir  = Filesystem::parent_path(path);
    std::string ext  = Filesystem::extension(path);
    std::string stem = Filesystem::filename(path);
    std::string tmp  = format("{}{}.{}.zdenoise-tmp-{}{}",
                              dir, dir.empty() ? "" : "/", stem, ::getpid(), ext);
    if (!image.write(tmp)) {
        std::string why = image.geterror();
        Filesystem::remove(tmp);
        if (why.empty())
            why = "unknown error";
        error = format("cannot write '{}': {}", path, OIIO::Strutil::strip(why));
        return false;
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        error = format("cannot write '{}': {}", path, std::strerror(errno));
        Filesystem::remove(tmp);
        return false;
    }
    return true;
}

}  // namespace job
}  // namespace zdenoise
