// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause

#include "synthetic_scenes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <OpenImageIO/imagebufalgo.h>

namespace synth {

namespace {

constexpr double PI = 3.14159265358979323846;

/// Uniform in (0, 1) from a 32-bit mt19937 draw, exactly reproducible.
double
uniform01(std::mt19937& rng)
{
    return (double(rng()) + 0.5) * (1.0 / 4294967296.0);
}

/// Exponential(1): heavy-ish right tail, mean 1, variance 1.
double
exponential1(std::mt19937& rng)
{
    return -std::log(uniform01(rng));
}

/// Per-pixel scene description before rendering.
struct Builder {
    int w, h;
    int nid = 1;
    std::vector<float> albedo, light, emission, normal, depth, id;

    Builder(int w_, int h_, int nid_ = 1)
        : w(w_), h(h_), nid(nid_), albedo(size_t(w_) * h_ * 3, 0.5f),
          light(size_t(w_) * h_ * 3, 1.0f), emission(size_t(w_) * h_ * 3, 0.0f),
          normal(size_t(w_) * h_ * 3, 0.0f), depth(size_t(w_) * h_, 5.0f),
          id(size_t(w_) * h_ * nid_, 0.0f)
    {
        for (size_t i = 0; i < size_t(w) * h; ++i) {
            normal[i * 3 + 2] = 1.0f;
            id[i * nid]       = 1.0f;
            if (nid == 4)
                id[i * nid + 1] = 1.0f;
        }
    }
    size_t i3(int x, int y, int c) const { return (size_t(y) * w + x) * 3 + c; }
    void set_albedo(int x, int y, float r, float g, float b)
    {
        albedo[i3(x, y, 0)] = r;
        albedo[i3(x, y, 1)] = g;
        albedo[i3(x, y, 2)] = b;
    }
    void set_light(int x, int y, float l, const float col[3])
    {
        for (int c = 0; c < 3; ++c)
            light[i3(x, y, c)] = l * col[c];
    }
    void set_normal(int x, int y, float nx, float ny, float nz)
    {
        normal[i3(x, y, 0)] = nx;
        normal[i3(x, y, 1)] = ny;
        normal[i3(x, y, 2)] = nz;
    }
};

/// Render clean and noisy radiance (see the header) and pack the scene.
Scene
finish(const Builder& b, const std::string& name, Noise noise)
{
    if (noise.spp < 2 || noise.spp % 2)
        throw std::invalid_argument("synth: spp must be even and >= 2");
    const int w = b.w, h = b.h;
    const size_t n = size_t(w) * h;
    std::vector<float> clean(n * 3), noisy(n * 3), var(n * 3), ha(n * 3),
        hb(n * 3);
    std::mt19937 rng(noise.seed);
    const int half = noise.spp / 2;
    for (size_t i = 0; i < n; ++i) {
        double sa = 0.0, sb = 0.0;
        for (int s = 0; s < half; ++s)
            sa += exponential1(rng);
        for (int s = 0; s < half; ++s)
            sb += exponential1(rng);
        double ma = sa / half, mb = sb / half;
        for (int c = 0; c < 3; ++c) {
            double v      = double(b.albedo[i * 3 + c]) * b.light[i * 3 + c]
                       + b.emission[i * 3 + c];
            clean[i * 3 + c] = float(v);
            ha[i * 3 + c]    = float(v * ma);
            hb[i * 3 + c]    = float(v * mb);
            noisy[i * 3 + c] = float(v * 0.5 * (ma + mb));
            var[i * 3 + c]   = float(v * v / noise.spp);
        }
    }
    Scene s;
    s.name      = name;
    s.w         = w;
    s.h         = h;
    s.clean     = make_image(w, h, 3, clean);
    s.noisy     = make_image(w, h, 3, noisy);
    s.albedo    = make_image(w, h, 3, b.albedo);
    s.normal    = make_image(w, h, 3, b.normal);
    s.depth     = make_image(w, h, 1, b.depth);
    s.object_id = make_image(w, h, b.nid, b.id);
    s.variance  = make_image(w, h, 3, var);
    s.half_a    = make_image(w, h, 3, ha);
    s.half_b    = make_image(w, h, 3, hb);
    return s;
}

const float WHITE[3] = { 1.0f, 1.0f, 1.0f };
const float WARM[3]  = { 1.0f, 0.95f, 0.85f };

}  // namespace

OIIO::ImageBuf
make_image(int w, int h, int nch, const std::vector<float>& px)
{
    OIIO::ImageSpec spec(w, h, nch, OIIO::TypeFloat);
    OIIO::ImageBuf buf(spec);
    buf.set_pixels(buf.roi(), OIIO::TypeFloat, px.data());
    return buf;
}

double
luminance(const OIIO::ImageBuf& img, int x, int y)
{
    float p[3];
    img.getpixel(x, y, p, 3);
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

std::vector<float>
pixels(const OIIO::ImageBuf& img)
{
    std::vector<float> px(img.spec().image_pixels() * img.nchannels());
    img.get_pixels(img.roi(), OIIO::TypeFloat, px.data());
    return px;
}

double
rel_mse(const OIIO::ImageBuf& img, const OIIO::ImageBuf& ref, int x0, int x1,
        int y0, int y1)
{
    double sum = 0.0;
    int n      = 0;
    float a[3], r[3];
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x, ++n) {
            img.getpixel(x, y, a, 3);
            ref.getpixel(x, y, r, 3);
            for (int c = 0; c < 3; ++c) {
                double d = double(a[c]) - double(r[c]);
                sum += d * d / (double(r[c]) * r[c] + 1e-2);
            }
        }
    return n ? sum / (3.0 * n) : 0.0;
}

double
rel_mse(const OIIO::ImageBuf& img, const OIIO::ImageBuf& ref)
{
    const OIIO::ROI r = ref.roi();
    return rel_mse(img, ref, r.xbegin, r.xend, r.ybegin, r.yend);
}

bool
same_pixels(const OIIO::ImageBuf& a, const OIIO::ImageBuf& b)
{
    const auto d = OIIO::ImageBufAlgo::compare(a, b, 0.0f, 0.0f);
    return !d.error && d.nfail == 0 && d.maxerror == 0.0;
}

double
mean_luminance(const OIIO::ImageBuf& img, int x0, int x1, int y0, int y1)
{
    double sum = 0.0;
    int n      = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x, ++n)
            sum += luminance(img, x, y);
    return n ? sum / n : 0.0;
}

namespace {
std::vector<double>
highpass(const OIIO::ImageBuf& img)
{
    const int w = img.spec().width, h = img.spec().height;
    const int x0 = img.spec().x, y0 = img.spec().y;
    std::vector<double> lum(size_t(w) * h), hp(size_t(w) * h, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            lum[size_t(y) * w + x] = luminance(img, x0 + x, y0 + y);
    for (int y = 2; y < h - 2; ++y)
        for (int x = 2; x < w - 2; ++x) {
            double s = 0.0;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx)
                    s += lum[size_t(y + dy) * w + x + dx];
            hp[size_t(y) * w + x] = lum[size_t(y) * w + x] - s / 25.0;
        }
    return hp;
}
}  // namespace

double
highpass_correlation(const OIIO::ImageBuf& a, const OIIO::ImageBuf& b, int border)
{
    const int w = a.spec().width, h = a.spec().height;
    border      = std::max(border, 2);
    std::vector<double> ha = highpass(a), hb = highpass(b);
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    int n = 0;
    for (int y = border; y < h - border; ++y)
        for (int x = border; x < w - border; ++x) {
            double u = ha[size_t(y) * w + x], v = hb[size_t(y) * w + x];
            sa += u, sb += v, saa += u * u, sbb += v * v, sab += u * v;
            ++n;
        }
    double cov = sab / n - (sa / n) * (sb / n);
    double va = saa / n - (sa / n) * (sa / n), vb = sbb / n - (sb / n) * (sb / n);
    return cov / std::sqrt(std::max(va * vb, 1e-300));
}

OIIO::ImageBuf
shifted(const OIIO::ImageBuf& img, int x, int y)
{
    OIIO::ImageSpec spec = img.spec();
    spec.x = spec.full_x = x;
    spec.y = spec.full_y = y;
    spec.set_format(OIIO::TypeFloat);
    OIIO::ImageBuf out(spec);
    std::vector<float> px = pixels(img);
    out.set_pixels(out.roi(), OIIO::TypeFloat, px.data());
    return out;
}

Scene
fine_texture(int w, int h, Noise noise)
{
    Builder b(w, h);
    std::mt19937 tex(noise.seed ^ 0x5eedu);
    const float col[3] = { 0.8f, 0.65f, 0.45f };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float chk = (((x >> 1) + (y >> 1)) & 1) ? 0.85f : 0.3f;
            float var = float(0.7 + 0.6 * uniform01(tex));
            b.set_albedo(x, y, col[0] * chk * var, col[1] * chk * var,
                         col[2] * chk * var);
            float l = float(0.55 + 0.3 * std::sin(2 * PI * (x + 0.5) / w)
                                      * std::cos(2 * PI * (y + 0.5) / h));
            b.set_light(x, y, l, WARM);
        }
    return finish(b, "fine_texture", noise);
}

Scene
corrugated_patch(int w, int h, Noise noise)
{
    Builder b(w, h);
    const float lean = std::sqrt(1.0f - 0.4f * 0.4f);
    auto in_patch = [&](int x, int y) {
        return x >= w / 2 - 4 && x < w / 2 + 4 && y >= h / 2 - 4 && y < h / 2 + 4;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            b.set_albedo(x, y, 0.5f, 0.5f, 0.5f);
            if (in_patch(x, y))
                b.set_normal(x, y, 0.0f, 0.0f, 1.0f);
            else
                b.set_normal(x, y, x % 2 ? lean : -lean, 0.0f, 0.4f);
            b.set_light(x, y, 0.5f, WHITE);
        }
    Scene s = finish(b, "corrugated_patch", noise);
    std::vector<float> var = pixels(s.variance);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (in_patch(x, y))
                for (int c = 0; c < 3; ++c)
                    var[3 * size_t(y * w + x) + size_t(c)] = 100.0f;
    s.variance = make_image(w, h, 3, var);
    return s;
}

Scene
shadow_edge(int w, int h, Noise noise)
{
    Builder b(w, h);
    const int edge = w / 2;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            b.set_albedo(x, y, 0.6f, 0.5f, 0.4f);
            b.set_light(x, y, x < edge ? 1.0f : 0.25f, WHITE);
        }
    Scene s  = finish(b, "shadow_edge", noise);
    s.edge_x = edge;
    s.levels = { 1.0f, 0.25f };
    return s;
}

Scene
sawtooth(int w, int h, int face_width, Noise noise)
{
    Builder b(w, h);
    const double th  = 40.0 * PI / 180.0;  // each face tilted 40 degrees
    const double lx  = -0.6, lz = 0.8;      // light direction (unit)
    const double nxe = -std::sin(th), nxo = std::sin(th), nz = std::cos(th);
    const float le   = float(0.05 + std::max(0.0, nxe * lx + nz * lz));
    const float lo   = float(0.05 + std::max(0.0, nxo * lx + nz * lz));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool odd = (x / face_width) & 1;
            b.set_albedo(x, y, 0.5f, 0.5f, 0.5f);
            b.set_normal(x, y, float(odd ? nxo : nxe), 0.0f, float(nz));
            b.set_light(x, y, odd ? lo : le, WARM);
        }
    Scene s      = finish(b, "sawtooth", noise);
    s.face_width = face_width;
    s.levels     = { le, lo };
    return s;
}

Scene
staircase(int w, int h, int tread_height, Noise noise)
{
    Builder b(w, h);
    const float levels[] = { 1.0f, 0.45f, 0.8f, 0.3f, 0.65f, 0.2f, 0.9f, 0.5f };
    const int nlev       = int(sizeof(levels) / sizeof(levels[0]));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            int k = y / tread_height;
            b.set_albedo(x, y, 0.55f, 0.55f, 0.5f);
            b.set_light(x, y, levels[k % nlev], WHITE);
            b.set_normal(x, y, 0.0f, 1.0f, 0.0f);
            // inverse depth: a step between treads, a slight slant within
            double zeta0 = 1.0 / (3.0 + 0.6 * k);
            double zeta  = zeta0 * (1.0 + 0.002 * (y - k * tread_height));
            b.depth[size_t(y) * w + x] = float(1.0 / zeta);
        }
    Scene s        = finish(b, "staircase", noise);
    s.tread_height = tread_height;
    for (int k = 0; k * tread_height < h; ++k)
        s.levels.push_back(levels[k % nlev]);
    return s;
}

Scene
two_objects(int w, int h, Noise noise, float dark)
{
    Builder b(w, h);
    const int edge = w / 2;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            b.set_albedo(x, y, 0.5f, 0.5f, 0.5f);
            b.set_light(x, y, x < edge ? 1.0f : dark, WARM);
            b.id[size_t(y) * w + x] = x < edge ? 1.0f : 2.0f;
        }
    Scene s  = finish(b, "two_objects", noise);
    s.edge_x = edge;
    s.levels = { 1.0f, dark };
    return s;
}

Scene
two_objects_cryptomatte(int w, int h, Noise noise, float dark)
{
    Builder b(w, h, 4);
    const int edge  = w / 2;   // first pure column of object B
    const int blend = edge - 1;  // the anti-aliased column
    // Cryptomatte ids are float-encoded hashes
    const float idA = 0.31415927f, idB = -7.2831855e-3f;
    const float LA = 1.0f, LB = dark;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            b.set_albedo(x, y, 0.5f, 0.5f, 0.5f);
            float cA = x < blend ? 1.0f : x > blend ? 0.0f
                                      : float(0.2 + 0.6 * std::fmod(y * 0.37, 1.0));
            float cB = 1.0f - cA;
            float* id = &b.id[(size_t(y) * w + x) * 4];
            if (cA >= cB) {
                id[0] = idA, id[1] = cA, id[2] = cB > 0 ? idB : 0.0f, id[3] = cB;
            } else {
                id[0] = idB, id[1] = cB, id[2] = cA > 0 ? idA : 0.0f, id[3] = cA;
            }
            b.set_light(x, y, cA * LA + cB * LB, WARM);
        }
    Scene s  = finish(b, "two_objects_cryptomatte", noise);
    s.edge_x = edge;
    s.levels = { LA, LB };
    return s;
}

Scene
holes(int w, int h, Noise noise)
{
    Builder b(w, h);
    std::mt19937 tex(noise.seed ^ 0xab1eu);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float v = float(0.85 + 0.3 * uniform01(tex));
            b.set_albedo(x, y, 0.6f * v, 0.55f * v, 0.45f * v);
            float l = float(0.6 + 0.25 * std::sin(2 * PI * (x + 0.5) / w + 0.5)
                                      * std::sin(2 * PI * (y + 0.5) / h + 1.0));
            b.set_light(x, y, l, WARM);
        }
    // a lattice of special pixels, 5 apart so that none are adjacent
    std::vector<Pixel> zero, partial, bad;
    int k = 0;
    for (int y = 3; y < h - 1; y += 5)
        for (int x = 2 + (y % 3); x < w - 1; x += 5, ++k) {
            switch (k % 3) {
            case 0: zero.push_back({ x, y }); break;
            case 1: partial.push_back({ x, y }); break;
            default: bad.push_back({ x, y }); break;
            }
        }
    for (const Pixel& p : zero) {
        b.set_albedo(p[0], p[1], 0.0f, 0.0f, 0.0f);
        for (int c = 0; c < 3; ++c)
            b.emission[b.i3(p[0], p[1], c)] = 2.0f;
    }
    for (const Pixel& p : partial) {
        b.albedo[b.i3(p[0], p[1], 2)]   = 0.0f;
        b.emission[b.i3(p[0], p[1], 2)] = 0.5f;
    }
    Scene s = finish(b, "holes", noise);
    const float values[3] = { std::numeric_limits<float>::quiet_NaN(),
                              std::numeric_limits<float>::infinity(),
                              -std::numeric_limits<float>::infinity() };
    for (size_t i = 0; i < bad.size(); ++i) {
        const Pixel& p = bad[i];
        float v        = values[i % 3];
        float px[3];
        s.noisy.getpixel(p[0], p[1], px, 3);
        if (i % 2)
            px[0] = px[1] = px[2] = v;
        else
            px[1] = v;
        s.noisy.setpixel(p[0], p[1], px, 3);
    }
    s.zero_albedo    = zero;
    s.partial_albedo = partial;
    s.nonfinite      = bad;
    return s;
}


void
vary_guides(Scene& s, bool depth_treads)
{
    for (int y = 0; y < s.h; ++y)
        for (int x = 0; x < s.w; ++x) {
            const float t = ((x / 2 + y / 3) % 2) ? 1.0f : 0.6f;
            float a[3], l[3], n[3];
            s.albedo.getpixel(x, y, a, 3);
            s.noisy.getpixel(x, y, l, 3);
            s.normal.getpixel(x, y, n, 3);
            for (int c = 0; c < 3; ++c)
                a[c] *= t, l[c] *= t;
            n[0] += ((x / 4 + y / 4) % 2) ? 0.35f : -0.35f;
            s.albedo.setpixel(x, y, a, 3);
            s.noisy.setpixel(x, y, l, 3);
            s.normal.setpixel(x, y, n, 3);
            if (depth_treads) {
                const float depth = s.depth.getchannel(x, y, 0, 0)
                                    * (1.0f + 0.06f * ((y / 5) % 3));
                s.depth.setpixel(x, y, &depth, 1);
            }
        }
}

}  // namespace synth
