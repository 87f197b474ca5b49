// Denoise a constant image through the installed library: it must stay
// constant and the call must succeed.
#include <cstdio>

#include <OpenImageIO/imagebufalgo.h>
#include <zdenoise/zdenoise.h>

int
main()
{
    OIIO::ImageSpec spec(16, 16, 3, OIIO::TypeFloat);
    OIIO::ImageBuf radiance(spec), albedo(spec);
    OIIO::ImageBufAlgo::fill(radiance, { 0.25f, 0.25f, 0.25f });
    OIIO::ImageBufAlgo::fill(albedo, { 0.5f, 0.5f, 0.5f });
    OIIO::ImageBuf out = zdenoise::denoise(radiance, albedo);
    if (out.has_error()) {
        std::fprintf(stderr, "denoise failed: %s\n", out.geterror().c_str());
        return 1;
    }
    float v = out.getchannel(8, 8, 0, 1);
    std::printf("zdenoise %s: %g\n", ZDENOISE_VERSION_STRING, v);
    return (v > 0.2499f && v < 0.2501f) ? 0 : 1;
}
