// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The remaining-error map as a picture a lighter reads at a glance
// (--diagnostics-png; docs/DIAGNOSTICS.md): false colour on a log scale
// with a legend under it.

#pragma once

#include <vector>

#include <OpenImageIO/imagebuf.h>

namespace zdenoise {
namespace job {

/// The log scale of the picture: relative errors from kPictureLowest
/// (darkest) to kPictureHighest (brightest; above it saturates).
constexpr float kPictureLowest  = 0.001f;
constexpr float kPictureHighest = 0.1f;

/// The remaining-error map of a whole frame, gathered strip by strip,
/// and its picture.
class ErrorPicture {
public:
    ErrorPicture() = default;
    explicit ErrorPicture(const OIIO::ROI& frame);

    /// Keep the rows `core` of a strip's maps (FilterOptions::diagnostics);
    /// false with the error in `maps` when they do not hold them.
    bool keep(const OIIO::ImageBuf& maps, const OIIO::ROI& core);

    /// An 8-bit RGB picture of the error map with the legend in a band
    /// below it: pixels no window reached (stop 0) are grey, the others
    /// coloured by log10(error) from kPictureLowest to kPictureHighest.
    /// Its data window starts at (0, 0).
    OIIO::ImageBuf picture() const;

private:
    OIIO::ROI m_frame;
    std::vector<float> m_error, m_stop;
};

}  // namespace job
}  // namespace zdenoise
