// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The two OutputSinks the job writes to: an image in memory (run_job()
// without a sink, the OIIO plugin) and a file written as it is computed
// (run_job_to_file()).

#pragma once

#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include "job_types.h"
#include "output.h"

namespace zdenoise {
namespace job {

/// The output image in memory, float, with its write formats set.
class ImageSink final : public OutputSink {
public:
    explicit ImageSink(OIIO::ImageBuf& image)
        : m_image(image)
    {
    }
    bool begin(const OIIO::ImageSpec& spec, const std::vector<OIIO::TypeDesc>& formats,
               std::string& error) override
    {
        m_image.reset(spec);
        m_image.set_write_format(formats);
        return true;
    }
    bool float_rows() const override { return true; }
    bool holds_image() const override { return true; }
    bool rows(int ybegin, int yend, const void* data,
              std::string& error) override
    {
        const OIIO::ImageSpec& s = m_image.spec();
        if (m_image.set_pixels(ROI(s.x, s.x + s.width, ybegin, yend, s.z,
                                   s.z + 1, 0, s.nchannels),
                               OIIO::TypeFloat, data))
            return true;
        error = m_image.geterror();
        return false;
    }

private:
    OIIO::ImageBuf& m_image;
};


/// The output file, written as ImageBuf::write would write the image in
/// memory: scanlines, each channel in its output type, the pixel type of
/// the spec the widest.
class FileSink final : public OutputSink {
public:
    explicit FileSink(const std::string& path)
        : m_path(path)
    {
    }
    bool begin(const OIIO::ImageSpec& spec, const std::vector<OIIO::TypeDesc>& formats,
               std::string& error) override
    {
        const OIIO::ImageSpec s = native_spec(spec, formats);
        m_out = OIIO::ImageOutput::create(m_path);
        if (!m_out)
            return failed(OIIO::geterror(), error);
        if (!m_out->open(m_path, s))
            return failed(m_out->geterror(), error);
        m_z = s.z;
        return true;
    }
    bool rows(int ybegin, int yend, const void* data,
              std::string& error) override
    {
        return m_out->write_scanlines(ybegin, yend, m_z, OIIO::TypeUnknown, data)
               || failed(m_out->geterror(), error);
    }
    bool end(std::string& error) override
    {
        return m_out->close() || failed(m_out->geterror(), error);
    }
    /// Whether the failure, if any, was writing.
    bool write_failed() const { return m_failed; }

private:
    bool failed(std::string why, std::string& error)
    {
        m_failed = true;
        error    = why.empty() ? std::string("unknown error") : why;
        return false;
    }

    std::string m_path;
    std::unique_ptr<OIIO::ImageOutput> m_out;
    int m_z       = 0;
    bool m_failed = false;
};

}  // namespace job
}  // namespace zdenoise
