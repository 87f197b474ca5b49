// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The output: its layout (the --in file's channels, with the radiance
// replaced by the denoised beauty and, with --aovs, the denoised layers
// added; each channel's pixel type), the assembly of each strip's output
// rows, and the sinks they go to (an image in memory, a file). The pixel
// format of the output file is chosen by native_spec(), which
// the OIIO plugin uses too.

#pragma once

#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

#include "input_files.h"
#include "layers_plan.h"
#include "aov_plan.h"
#include "light_groups_plan.h"
#include "strips.h"

namespace zdenoise {
namespace job {

/// One channel of the output and where its pixels come from: a channel of
/// the --in file, or a channel of a denoised image of the strip.
struct OutputChannel {
    int file = -1;  ///< channel of the --in file, or -1
    int image = -1, image_channel = 0;  ///< else: denoised image, channel
    OIIO::TypeDesc type;  ///< pixel type in the output
};

/// The output of job `j`: the --in file `in` with its radiance RGB (the
/// channels `radiance` selects) replaced and, with --aovs, the denoised
/// layers of `layers` added; each channel in its input pixel type unless
/// -d says otherwise, Cryptomatte float; with --diagnostics the maps
/// added; the alpha that job `j` denoises from the denoised alpha. Images:
/// 0 the denoised beauty, 1 + i layer i, then the maps (diagnostics_image()),
/// then the alpha (alpha_image()), then the light groups of `groups`
/// (light_group_image()), then the AOVs of `aovs`. `spec` is as an ImageBuf of the --in file's pixels has
/// it (part 0's spec, the channels and metadata of every part).
void
layout_output(const Job& j, const InputHeader& in, const Selection& radiance,
              const LayersPlan& layers, const LightGroupPlan& groups,
              const AovPlan& aovs, OIIO::ImageSpec& spec,
              std::vector<OutputChannel>& channels,
              std::vector<OIIO::TypeDesc>& formats);

/// The spec of the output as a file holds it (and the OIIO plugin serves
/// it): `spec` in scanlines, each channel in its output pixel type
/// (`formats`), `format` the widest of them (TypeDesc::basetype_merge), the
/// per-channel formats listed only when they differ.
OIIO::ImageSpec
native_spec(const OIIO::ImageSpec& spec,
            const std::vector<OIIO::TypeDesc>& formats);


/// The index of the diagnostic maps (Job::diagnostics) among the denoised
/// images: after the beauty and the layers.
int
diagnostics_image(const LayersPlan& layers);

/// The index of the denoised alpha (alpha_plan.h) among the denoised
/// images: after the maps.
int
alpha_image(const Job& j, const LayersPlan& layers);

/// The index of light group k among the denoised images: after the alpha
/// (when job `j` denoises the alpha of `radiance`).
int
light_group_image(const Job& j, const LayersPlan& layers,
                  const Selection& radiance, size_t k);

/// Where the output of one strip comes from and goes to.
struct Output {
    /// Output rows are assembled and written this many at a time.
    static constexpr int kBandRows = 32;
    OutputSink* sink = nullptr;
    OIIO::ImageSpec spec;
    std::vector<OutputChannel> channels;
    std::vector<OIIO::TypeDesc> row_types;  ///< as the sink takes them
    std::vector<size_t> offset;             ///< of each channel in a pixel
    size_t pixel_bytes = 0;
    std::vector<unsigned char> band, plane;

    void set_row_types(bool float_rows);

    /// Assemble the output rows of `strip` band by band and give them to
    /// the sink: channels of the --in file moved from its rows (in runs of
    /// neighbours of one type), the others from the denoised `images`.
    void write(const Strip& strip, const RowReader& in,
               const std::vector<const OIIO::ImageBuf*>& images, int threads);
};

}  // namespace job
}  // namespace zdenoise
