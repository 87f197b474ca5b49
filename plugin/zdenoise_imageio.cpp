// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The OpenImageIO plugin: any OIIO program reads a zdenoise recipe (.zdn,
// share/zdn-format.md) as the image `zdenoise` would write for it. open()
// reads the inputs' headers only (job::output_spec()), so that a program
// listing recipes (iinfo, oiiotool --info, a browser) does not denoise
// them; the first pixel read runs the job, once, and the scanlines are then
// served from memory in the output's per-channel pixel types, so that a
// program writing what it reads writes the same file `zdenoise` does. The
// job streams its inputs strip by strip (src/job/job.h), but a reader must
// hold the whole output: memory follows the frame here, in the output's
// own pixel types.
//
// The format is named "zdenoise". OIIO's writers drop metadata whose
// prefix before ':' is the name of another format, which is why zdenoise's
// own metadata is "zdenoise.version" and "zdenoise.parameters" (a dot).

#include <algorithm>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <zdenoise/version.h>

#include "job/job.h"
#include "job/output.h"
#include "job/recipe.h"

using namespace OIIO;
namespace job = zdenoise::job;

namespace {

/// Recipes in the making on this thread. An input that is a recipe in
/// disguise (say `x.exr` holding JSON) reaches this reader again through
/// OIIO's "try every reader" fallback; refusing it ends the recursion.
thread_local int recipes_being_read = 0;

struct ReadingRecipe {
    ReadingRecipe() { ++recipes_being_read; }
    ~ReadingRecipe() { --recipes_being_read; }
};


/// The job's output as the file zdenoise would write for it, read back:
/// scanlines, each channel in the pixel type it is written in, with the
/// file's `format` and per-channel types (job::native_spec()).
class NativeImage final : public job::OutputSink {
public:
    ImageSpec spec;
    std::vector<unsigned char> pixels;

    bool begin(const ImageSpec& image_spec,
               const std::vector<TypeDesc>& formats,
               std::string& error) override
    {
        spec = job::native_spec(image_spec, formats);
        pixels.resize(spec.image_bytes(true));
        return true;
    }

    bool holds_image() const override { return true; }

    bool rows(int ybegin, int yend, const void* data,
              std::string& error) override
    {
        const size_t row = spec.scanline_bytes(true);
        std::memcpy(pixels.data() + size_t(ybegin - spec.y) * row, data,
                    size_t(yend - ybegin) * row);
        return true;
    }
};


class ZdnInput final : public ImageInput {
public:
    // OIIO constructs one of each reader while cataloguing formats:
    // nothing happens here.
    ZdnInput() = default;
    ~ZdnInput() override { close(); }

    const char* format_name() const override { return "zdenoise"; }

    int supports(string_view feature) const override
    {
        // The output carries the noisy input's metadata, whatever it is.
        return feature == "arbitrary_metadata";
    }

    bool valid_file(const std::string& filename) const override
    {
        try {
            return job::looks_like_recipe(filename);
        } catch (...) {
            return false;  // no exception may reach the host program
        }
    }

    bool open(const std::string& name, ImageSpec& newspec) override
    {
        try {
            return open_recipe(name, newspec);
        } catch (const std::exception& e) {  // e.g. out of memory
            close();
            errorfmt("recipe '{}': {}", name, e.what());
            return false;
        }
    }

    bool open(const std::string& name, ImageSpec& newspec,
              const ImageSpec& /*config*/) override
    {
        return open(name, newspec);
    }

    bool close() override
    {
        std::lock_guard<std::mutex> lock(m_run_mutex);
        m_recipe    = job::Job();
        m_name      = std::string();
        m_ran       = false;
        m_run_error = std::string();
        m_pixels    = std::vector<unsigned char>();
        m_spec      = ImageSpec();
        return true;
    }

    bool read_native_scanline(int subimage, int miplevel, int y, int z,
                              void* data) override
    {
        return read_native_scanlines(subimage, miplevel, y, y + 1, z, 0,
                                     m_spec.nchannels, data);
    }

    bool read_native_scanlines(int subimage, int miplevel, int ybegin,
                               int yend, int z, void* data) override
    {
        return read_native_scanlines(subimage, miplevel, ybegin, yend, z, 0,
                                     m_spec.nchannels, data);
    }

    bool read_native_scanlines(int subimage, int miplevel, int ybegin,
                               int yend, int z, int chbegin, int chend,
                               void* data) override;

private:
    bool open_recipe(const std::string& name, ImageSpec& newspec);
    /// Run the recipe unless it has run: whether its pixels are there (else
    /// the run's error is this reader's).
    bool denoised();
    /// Run the recipe into m_pixels; "" or the error, as open() words it.
    std::string run_recipe();

    /// The open recipe (its threads settled) and its file name; empty when
    /// none is open.
    job::Job m_recipe;
    std::string m_name;
    /// Reads may come from several threads: the first runs the recipe,
    /// the others wait for it; its error stays for every later read.
    std::mutex m_run_mutex;
    bool m_ran = false;
    std::string m_run_error;
    /// The denoised image in its native layout: whole scanlines, each
    /// pixel's channels in their own pixel types (m_spec.channelformats).
    std::vector<unsigned char> m_pixels;
};


bool
ZdnInput::open_recipe(const std::string& name, ImageSpec& newspec)
{
    close();
    if (recipes_being_read > 0) {
        errorfmt("recipe '{}': a recipe cannot be the input of another "
                 "recipe",
                 name);
        return false;
    }
    ReadingRecipe guard;

    job::Job recipe;
    std::string error;
    if (!job::read_recipe(name, recipe, error)) {
        errorfmt("{}", error);
        return false;
    }
    // Threads: the recipe's (or the file name's ?threads=N), else this
    // reader's policy, else (0) OIIO's global "threads" attribute.
    if (recipe.threads == 0)
        recipe.threads = threads();

    // The spec from the headers; the pixels wait for the first read.
    NativeImage image;
    if (!job::output_spec(recipe, image, m_spec, error)) {
        errorfmt("recipe '{}': {}", name, error);
        return false;
    }
    m_recipe = std::move(recipe);
    m_name   = name;
    newspec  = m_spec;
    return true;
}


bool
ZdnInput::denoised()
{
    std::lock_guard<std::mutex> lock(m_run_mutex);
    if (!m_ran) {
        try {
            m_run_error = run_recipe();
        } catch (const std::exception& e) {  // e.g. out of memory
            m_run_error = Strutil::fmt::format("recipe '{}': {}", m_name,
                                               e.what());
        }
        m_ran = true;
    }
    if (!m_run_error.empty())
        errorfmt("{}", m_run_error);
    return m_run_error.empty();
}


std::string
ZdnInput::run_recipe()
{
    ReadingRecipe guard;
    NativeImage image;
    job::JobResult result;
    std::string error;
    if (!job::run_job(m_recipe, image, result, error))
        return Strutil::fmt::format("recipe '{}': {}", m_name, error);
    // An input rewritten since open() (another size, other channels) would
    // give pixels of another layout than the spec the caller holds.
    if (image.spec.serialize(ImageSpec::SerialText, ImageSpec::SerialDetailed)
        != m_spec.serialize(ImageSpec::SerialText, ImageSpec::SerialDetailed))
        return Strutil::fmt::format("recipe '{}': its inputs changed since it "
                                    "was opened; open it again",
                                    m_name);
    m_pixels = std::move(image.pixels);
    return std::string();
}


bool
ZdnInput::read_native_scanlines(int subimage, int miplevel, int ybegin,
                                     int yend, int z, int chbegin, int chend,
                                     void* data)
{
    if (m_name.empty()) {
        errorfmt("zdenoise: no recipe is open");
        return false;
    }
    if (subimage != 0 || miplevel != 0 || z < m_spec.z
        || z >= m_spec.z + std::max(m_spec.depth, 1) || ybegin < m_spec.y
        || yend > m_spec.y + m_spec.height || ybegin > yend || chbegin < 0
        || chend > m_spec.nchannels || chbegin >= chend) {
        errorfmt("zdenoise: scanlines {}-{}, channels {}-{}, subimage {} "
                 "level {} are outside the image",
                 ybegin, yend, chbegin, chend, subimage, miplevel);
        return false;
    }
    if (!denoised())
        return false;
    const size_t pixel_bytes    = m_spec.pixel_bytes(true);
    const size_t scanline_bytes = m_spec.scanline_bytes(true);
    const size_t first          = m_spec.pixel_bytes(0, chbegin, true);
    const size_t wanted         = m_spec.pixel_bytes(chbegin, chend, true);
    const size_t plane          = scanline_bytes * size_t(m_spec.height);
    const unsigned char* src    = m_pixels.data() + plane * size_t(z - m_spec.z)
                               + scanline_bytes * size_t(ybegin - m_spec.y);
    auto* dst = static_cast<unsigned char*>(data);
    if (wanted == pixel_bytes) {
        std::memcpy(dst, src, scanline_bytes * size_t(yend - ybegin));
        return true;
    }
    const size_t pixels = size_t(m_spec.width) * size_t(yend - ybegin);
    for (size_t p = 0; p < pixels; ++p)
        std::memcpy(dst + p * wanted, src + p * pixel_bytes + first, wanted);
    return true;
}

}  // namespace


OIIO_PLUGIN_EXPORTS_BEGIN

OIIO_EXPORT int zdenoise_imageio_version = OIIO_PLUGIN_VERSION;

OIIO_EXPORT const char*
zdenoise_imageio_library_version()
{
    return "zdenoise " ZDENOISE_VERSION_STRING;
}

OIIO_EXPORT ImageInput*
zdenoise_input_imageio_create()
{
    return new ZdnInput;
}

OIIO_EXPORT const char* zdenoise_input_extensions[] = { "zdn", nullptr };

OIIO_PLUGIN_EXPORTS_END
