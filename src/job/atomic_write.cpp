// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "atomic_write.h"

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <fstream>

#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/strutil.h>

#include "failure.h"

namespace zdenoise {
namespace job {

using OIIO::Strutil::fmt::format;
namespace Filesystem = OIIO::Filesystem;

namespace {

// The name is written before the flag is set and read only while it is.
char g_in_flight[PATH_MAX];
std::atomic<bool> g_in_flight_set { false };
static_assert(std::atomic<bool>::is_always_lock_free,
              "read from a signal handler");

/// Marks `tmp` as the temporary file in flight for as long as it lives.
class InFlight {
public:
    explicit InFlight(const std::string& tmp)
    {
        if (tmp.size() < sizeof(g_in_flight)) {
            std::memcpy(g_in_flight, tmp.c_str(), tmp.size() + 1);
            g_in_flight_set = true;
        }
    }
    ~InFlight() { g_in_flight_set = false; }
};

}  // namespace


const char*
temporary_file_in_flight()
{
    return g_in_flight_set ? g_in_flight : nullptr;
}


bool
write_atomically(const std::string& path,
                 const std::function<bool(const std::string& temporary_path,
                                          std::string& why)>& write,
                 std::string& error)
{
    // Same folder (so the rename is atomic), hidden name, same extension (so
    // that an image format is chosen from it).
    std::string dir  = Filesystem::parent_path(path);
    std::string ext  = Filesystem::extension(path);
    std::string stem = Filesystem::filename(path);
    std::string tmp  = format("{}{}.{}.zdenoise-tmp-{}{}",
                              dir, dir.empty() ? "" : "/", stem, ::getpid(), ext);
    const InFlight in_flight(tmp);
    std::string why;
    if (!write(tmp, why)) {
        Filesystem::remove(tmp);
        if (why.empty())
            why = "unknown error";
        error = format("cannot write '{}': {}", path, one_line(why));
        return false;
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        error = format("cannot write '{}': {}", path, std::strerror(errno));
        Filesystem::remove(tmp);
        return false;
    }
    return true;
}


bool
write_atomically(const OIIO::ImageBuf& image, const std::string& path,
                 std::string& error)
{
    return write_atomically(
        path,
        [&](const std::string& tmp, std::string& why) {
            if (image.write(tmp))
                return true;
            why = image.geterror();
            return false;
        },
        error);
}


bool
write_text_atomically(const std::string& path, const std::string& text,
                      std::string& error)
{
    return write_atomically(
        path,
        [&](const std::string& tmp, std::string& why) {
            std::ofstream file(tmp, std::ios::binary);
            file << text;
            file.close();
            if (file)
                return true;
            why = std::strerror(errno);
            return false;
        },
        error);
}

}  // namespace job
}  // namespace zdenoise
