// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Fuzzing denoise() on small images with fuzzed pixels (NaN, Inf, huge and
// negative values included), guides and filter options. Whatever the input,
// it must not crash, must report a refusal with a message, and a result
// must keep the promises of zdenoise.h and docs/FILTER.md: no NaN or Inf in
// the RGB channels, other channels copied bit for bit, and a ROI giving
// exactly the pixels of a whole-image run.
//
// Input: 6 bytes of shape and guide flags, 19 bytes of options, then one
// byte per pixel value (cycled; see value()).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>

#include <OpenImageIO/imagebuf.h>

#include <zdenoise/zdenoise.h>

using namespace OIIO;

namespace {

[[noreturn]] void
violated(const char* what)
{
    std::fprintf(stderr, "fuzz_denoise: %s\n", what);
    std::abort();
}

/// Reads the fuzzer's bytes; past the end, zeros (or the pixel bytes
/// again, cycled).
class Bytes {
public:
    Bytes(const uint8_t* data, size_t size) : m_data(data), m_size(size) {}

    uint8_t next() { return m_pos < m_size ? m_data[m_pos++] : 0; }

    /// A pixel value: mostly ordinary ones in [-0.5, 3.4], and now and
    /// then every kind of bad value.
    float value()
    {
        const size_t n = m_size - std::min(m_pos, m_size);
        const uint8_t b = n ? m_data[m_pos + (m_pixel++ % n)] : 0;
        switch (b) {
        case 250: return std::numeric_limits<float>::quiet_NaN();
        case 251: return std::numeric_limits<float>::infinity();
        case 252: return -std::numeric_limits<float>::infinity();
        case 253: return 1e30f;
        case 254: return -1e30f;
        case 255: return 1e-30f;
        default: return float(b) / 64.0f - 0.5f;
        }
    }

    /// An option: its default scaled by [0, 4), or a bad value.
    float option(float default_value)
    {
        const uint8_t b = next();
        switch (b) {
        case 250: return std::numeric_limits<float>::quiet_NaN();
        case 251: return std::numeric_limits<float>::infinity();
        case 252: return -1.0f;
        case 253: return 0.0f;
        case 254: return 1e30f;
        case 255: return 1e-30f;
        default: return default_value * float(b) / 64.0f;
        }
    }

private:
    const uint8_t* m_data;
    size_t m_size, m_pos = 0, m_pixel = 0;
};

ImageBuf
image(Bytes& bytes, int w, int h, int nchannels)
{
    ImageBuf buf(ImageSpec(w, h, nchannels, TypeFloat));
    float* p = static_cast<float*>(buf.localpixels());
    for (size_t i = 0, n = size_t(w) * size_t(h) * size_t(nchannels); i < n;
         ++i)
        p[i] = bytes.value();
    return buf;
}

bool
same_bits(float a, float b)
{
    return std::memcmp(&a, &b, sizeof a) == 0;
}

}  // namespace


extern "C" int
LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    Bytes bytes(data, size);
    const int w          = 1 + bytes.next() % 16;
    const int h          = 1 + bytes.next() % 16;
    const uint8_t guides = bytes.next();
    const uint8_t shape  = bytes.next();
    const int roi_x      = bytes.next() % w;
    const int roi_y      = bytes.next() % h;

    zdenoise::FilterOptions opt;
    opt.r_min           = (bytes.next() % 4);  // 0: invalid on purpose
    opt.r_max           = opt.r_min + bytes.next() % 5 - 1;
    opt.eta_target      = bytes.option(opt.eta_target);
    opt.edge_k          = bytes.option(opt.edge_k);
    opt.tau_min         = bytes.option(opt.tau_min);
    opt.value_k         = bytes.option(opt.value_k);
    opt.sigma_good      = bytes.option(opt.sigma_good);
    opt.albedo_eps      = bytes.option(opt.albedo_eps);
    opt.depth_tolerance = bytes.option(opt.depth_tolerance);
    opt.normal_cut      = bytes.option(0.25f) - 1.0f;
    opt.normal_power    = bytes.option(opt.normal_power);
    opt.quadrant_power  = bytes.option(opt.quadrant_power);
    opt.centre_stride   = 1 + bytes.next() % 4;  // > r_min + 1: refused
    opt.radius_growth   = bytes.option(opt.radius_growth);
    // The options of whole-number and 0|1 ranges, a value past each range
    // now and then (refused): the pyramid (0, 1-3 refused, 4..), the
    // selection, the edge centres and the outliers' spread.
    opt.pyramid_radius  = bytes.next() % 8;
    opt.select          = bytes.next() % 3;
    opt.stride_edges    = bytes.next() % 3;
    opt.outlier_spread  = bytes.next() % 3;
    const uint8_t large = bytes.next();
    if (large & 1) {
        // Windows past the frame's size, as --rmax 32 on a small frame.
        opt.r_max = opt.r_min + 4 + large % 29;
    }
    // The value term's noise scale from the same byte's top bits (a byte
    // of its own would shift the corpus's inputs).
    opt.value_noise = (large >> 6) % 3;
    // The box core from bits 1-4 of the same byte: radii up to 8 (0 is
    // refused).
    if ((large >> 1) & 1) {
        opt.core       = 1;
        opt.box_radius = (large >> 2) % 9;
    }

    const int nchannels = 3 + shape % 3;  // RGB, + alpha, + an AOV
    ImageBuf radiance   = image(bytes, w, h, nchannels);
    if (nchannels > 3) {
        ImageSpec& spec   = radiance.specmod();
        spec.channelnames = { "R", "G", "B", "A", "aov" };
        spec.channelnames.resize(size_t(nchannels));
        spec.alpha_channel = 3;
    }
    ImageBuf albedo = image(bytes, w, h, 3);
    ImageBuf normal, depth, id, variance, half_a, half_b;
    zdenoise::Guides g;
    if (guides & 1)
        g.normal = &(normal = image(bytes, w, h, 3));
    if (guides & 2)
        g.depth = &(depth = image(bytes, w, h, 1));
    if (guides & 4)
        g.object_id = &(id = image(bytes, w, h, (guides & 8) ? 4 : 1));
    if (guides & 16)
        g.variance = &(variance = image(bytes, w, h, (guides & 32) ? 3 : 1));
    if (guides & 64) {
        g.half_a = &(half_a = image(bytes, w, h, 3));
        g.half_b = &(half_b = image(bytes, w, h, 3));
    }

    ImageBuf out;
    if (!zdenoise::denoise(out, radiance, albedo, g, opt, nullptr, {}, 1)) {
        if (out.geterror().empty())
            violated("refused without a message");
        return 0;
    }
    if (out.roi() != radiance.roi())
        violated("the result does not cover the radiance's pixels");
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < 3; ++c)
                if (!std::isfinite(out.getchannel(x, y, 0, c)))
                    violated("a NaN or Inf in the result");
            for (int c = 3; c < nchannels; ++c)
                if (!same_bits(out.getchannel(x, y, 0, c),
                               radiance.getchannel(x, y, 0, c)))
                    violated("a channel other than RGB was changed");
        }

    if (shape & 8) {
        // A ROI: exactly the whole-image run's pixels there.
        const ROI roi(roi_x, w, roi_y, h);
        ImageBuf part;
        if (!zdenoise::denoise(part, radiance, albedo, g, opt, nullptr, roi,
                               1))
            violated("a ROI refused where the whole image was not");
        for (int y = roi.ybegin; y < roi.yend; ++y)
            for (int x = roi.xbegin; x < roi.xend; ++x)
                for (int c = 0; c < nchannels; ++c)
                    if (!same_bits(part.getchannel(x, y, 0, c),
                                   out.getchannel(x, y, 0, c)))
                        violated("a ROI run differs from the whole image");
    }
    return 0;
}
