// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "diagnostics_picture.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

namespace zdenoise {
namespace job {

using namespace OIIO;

namespace {

/// The colours of the scale, display (sRGB) values at even steps of
/// log10(error): dark blue (clean) through green and yellow to red (noisy).
/// Lightness rises along it, so it also reads in grey.
constexpr float kScale[][3] = { { 0.05f, 0.03f, 0.25f },
                                { 0.10f, 0.33f, 0.66f },
                                { 0.16f, 0.62f, 0.45f },
                                { 0.93f, 0.80f, 0.22f },
                                { 0.98f, 0.35f, 0.18f } };
constexpr int kScaleSteps = int(sizeof(kScale) / sizeof(kScale[0])) - 1;
constexpr float kNoWindow[3]  = { 0.35f, 0.35f, 0.35f };
constexpr float kBackground[3] = { 0.12f, 0.12f, 0.12f };
constexpr float kInk[3]        = { 0.92f, 0.92f, 0.92f };

/// Where `error` lies on the scale, 0 to 1.
float
scale_position(float error)
{
    if (!(error > kPictureLowest))
        return 0.0f;
    const float t = (std::log10(error) - std::log10(kPictureLowest))
                    / (std::log10(kPictureHighest) - std::log10(kPictureLowest));
    return std::min(t, 1.0f);
}

void
scale_colour(float t, float rgb[3])
{
    const float f = t * float(kScaleSteps);
    const int i   = std::min(int(f), kScaleSteps - 1);
    const float u = f - float(i);
    for (int c = 0; c < 3; ++c)
        rgb[c] = kScale[i][c] * (1.0f - u) + kScale[i + 1][c] * u;
}

/// A 5x7 pixel font of the characters the legend writes.
struct Glyph {
    char c;
    const char* rows[7];
};
constexpr Glyph kFont[] = {
    { '0', { ".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###." } },
    { '1', { "..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###." } },
    { '2', { ".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####" } },
    { '3', { "#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###." } },
    { '4', { "...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#." } },
    { '5', { "#####", "#....", "####.", "....#", "....#", "#...#", ".###." } },
    { '6', { "..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###." } },
    { '7', { "#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..." } },
    { '8', { ".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###." } },
    { '9', { ".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.." } },
    { '.', { ".....", ".....", ".....", ".....", ".....", ".##..", ".##.." } },
    { '%', { "##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##" } },
};

/// An RGB float canvas, written to the ImageBuf at the end.
struct Canvas {
    int width, height;
    std::vector<float> px;
    Canvas(int w, int h)
        : width(w), height(h), px(size_t(w) * size_t(h) * 3, 0.0f)
    {
    }
    void set(int x, int y, const float rgb[3])
    {
        if (x < 0 || y < 0 || x >= width || y >= height)
            return;
        std::memcpy(&px[(size_t(y) * size_t(width) + size_t(x)) * 3], rgb,
                    3 * sizeof(float));
    }
    void fill(int x0, int y0, int x1, int y1, const float rgb[3])
    {
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x)
                set(x, y, rgb);
    }
    /// `text` with its top-left corner at (x, y), each font pixel s x s.
    void text(const std::string& text, int x, int y, int s)
    {
        for (char ch : text) {
            for (const Glyph& g : kFont)
                if (g.c == ch)
                    for (int r = 0; r < 7; ++r)
                        for (int c = 0; c < 5; ++c)
                            if (g.rows[r][c] == '#')
                                fill(x + c * s, y + r * s, x + (c + 1) * s,
                                     y + (r + 1) * s, kInk);
            x += 6 * s;
        }
    }
};

int
text_width(const std::string& text, int s)
{
    return int(text.size()) * 6 * s - s;
}

}  // namespace


ErrorPicture::ErrorPicture(const ROI& frame)
    : m_frame(frame)
    , m_error(size_t(frame.width()) * size_t(frame.height()), 0.0f)
    , m_stop(m_error.size(), 0.0f)
{
}


bool
ErrorPicture::keep(const ImageBuf& maps, const ROI& core)
{
    const size_t first = size_t(core.ybegin - m_frame.ybegin)
                             * size_t(m_frame.width())
                         + size_t(core.xbegin - m_frame.xbegin);
    const int stop = 1, error = 3;  // diagnostic_channels()
    for (int c : { stop, error }) {
        ROI r     = core;
        r.chbegin = c;
        r.chend   = c + 1;
        std::vector<float>& to = c == stop ? m_stop : m_error;
        if (!maps.get_pixels(r, TypeFloat, &to[first],
                             AutoStride, stride_t(m_frame.width()) * 4))
            return false;
    }
    return true;
}


ImageBuf
ErrorPicture::picture() const
{
    const int width = m_frame.width(), height = m_frame.height();
    const std::vector<float>& error = m_error;
    const std::vector<float>& stop  = m_stop;
    // The legend scales with the picture so that it stays legible on a
    // 4K frame and fits a thumbnail.
    const int s      = std::max(1, std::min(width / 256, 4));
    const int margin = 6 * s, bar = 10 * s, tick = 3 * s;
    const int band   = margin + bar + tick + 2 * s + 7 * s + margin;
    Canvas canvas(width, height + band);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            float rgb[3];
            if (stop[i] > 0.0f)
                scale_colour(scale_position(error[i]), rgb);
            else
                std::memcpy(rgb, kNoWindow, sizeof(rgb));
            canvas.set(x, y, rgb);
        }
    canvas.fill(0, height, width, height + band, kBackground);
    // The bar, then a tick and a label at each of the scale's values.
    const int x0 = margin, x1 = std::max(width - margin, x0 + 1);
    const int top = height + margin;
    for (int x = x0; x < x1; ++x) {
        float rgb[3];
        scale_colour(float(x - x0) / float(std::max(x1 - x0 - 1, 1)), rgb);
        canvas.fill(x, top, x + 1, top + bar, rgb);
    }
    const struct {
        float value;
        const char* label;
    } marks[] = { { 0.001f, "0.1%" }, { 0.003f, "0.3%" }, { 0.01f, "1%" },
                  { 0.03f, "3%" },    { 0.1f, "10%" } };
    for (const auto& m : marks) {
        const int x = x0 + int(std::lround(scale_position(m.value)
                                           * float(x1 - x0 - 1)));
        canvas.fill(x - s / 2, top + bar, x - s / 2 + s, top + bar + tick,
                    kInk);
        const int w  = text_width(m.label, s);
        const int tx = std::min(std::max(x - w / 2, 0), width - w);
        canvas.text(m.label, tx, top + bar + tick + 2 * s, s);
    }
    ImageSpec spec(width, height + band, 3, TypeUInt8);
    spec.channelnames = { "R", "G", "B" };
    // The values are display values already: no transform on writing.
    spec.attribute("oiio:ColorSpace", "sRGB");
    ImageBuf picture(spec);
    picture.set_pixels(picture.roi(), TypeFloat, canvas.px.data());
    return picture;
}

}  // namespace job
}  // namespace zdenoise
