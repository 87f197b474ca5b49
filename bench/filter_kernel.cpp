// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// Microbenchmark of the regression filter's kernel (Google Benchmark):
// the time per pixel of regression_filter() on synthetic scenes at
// several noise levels. The adaptive radius makes the cost follow the
// content: noisier images grow bigger windows, and a window that stops at
// radius R costs about (4/3) R^3 point visits (bench/results/2026-12-performance-log.md), so the
// counters report the mean radius too.
//
//   build/bin/zdenoise_bench_filter                      # all cases
//   build/bin/zdenoise_bench_filter --benchmark_filter=Staircase
//
// Counters: per_px (time per output pixel; CPU time, or wall time for the
// thread cases), mean_radius, windows.

#include <benchmark/benchmark.h>

#include <zdenoise/zdenoise.h>

#include "synthetic_scenes.h"

namespace {

constexpr int kSize = 128;
/// Thread scaling needs enough blocks of centres for both threads to the
/// end of each phase: 384 x 384 gives 12 x 6 blocks.
constexpr int kThreadsSize = 384;

/// The quotient (noisy / albedo) and guides of a scene, made once per case.
struct KernelInput {
    synth::Scene scene;
    OIIO::ImageBuf quotient;
    zdenoise::Guides guides;

    explicit KernelInput(synth::Scene s)
        : scene(std::move(s))
    {
        quotient = zdenoise::demodulate(scene.noisy, scene.albedo);
        guides.normal    = &scene.normal;
        guides.depth     = &scene.depth;
        guides.object_id = &scene.object_id;
    }
};

/// Every fit point a centre: the cost of the window kernel itself, the same
/// whatever the lattice (the default stride 3 fits about 60 % of the
/// windows on the perf frame); today's filter alone (candidate 0 of the
/// selection, which Selection times whole).
zdenoise::FilterOptions
kernel_options()
{
    zdenoise::FilterOptions o;
    o.centre_stride = 1;
    o.select        = 0;
    return o;
}

void
run_filter(benchmark::State& state, const KernelInput& in, int nthreads,
           const zdenoise::FilterOptions& options = kernel_options())
{
    zdenoise::FilterStats stats;
    for (auto _ : state) {
        OIIO::ImageBuf out = zdenoise::regression_filter(in.quotient, in.scene.albedo, in.guides,
                                                         options, &stats, {}, nthreads);
        benchmark::DoNotOptimize(out.localpixels());
    }
    const double pixels = double(stats.pixels) * double(state.iterations());
    // Seconds per pixel (printed with an SI prefix: "12.3u" is 12.3 us).
    state.counters["per_px"] = benchmark::Counter(pixels, benchmark::Counter::kIsRate
                                                              | benchmark::Counter::kInvert);
    state.counters["mean_radius"] = stats.mean_radius;
    state.counters["windows"]     = double(stats.windows);
}

/// Staircase (treads with depth steps and lighting edges), range(0) = spp.
void
Staircase(benchmark::State& state)
{
    const KernelInput in(synth::staircase(kSize, kSize, 8, { int(state.range(0)), 7 }));
    run_filter(state, in, 1);
}

/// Fine texture under smooth light: windows grow until the noise is gone.
void
FineTexture(benchmark::State& state)
{
    const KernelInput in(synth::fine_texture(kSize, kSize, { int(state.range(0)), 7 }));
    run_filter(state, in, 1);
}

/// Thread scaling on the staircase at 8 spp: range(0) = threads.
void
StaircaseThreads(benchmark::State& state)
{
    const KernelInput in(synth::staircase(kThreadsSize, kThreadsSize, 8, { 8, 7 }));
    run_filter(state, in, int(state.range(0)));
}

/// The cost per pixel against r_max (range(0)) where windows grow to it:
/// fine texture at 2 spp. A window tries radii 2, 4, ..., r_max, so its
/// cost grows as r_max^2 (issue 17 asks for at most r_max beyond 16).
void
RMax(benchmark::State& state)
{
    const KernelInput in(synth::fine_texture(kSize, kSize, { 2, 7 }));
    zdenoise::FilterOptions o = kernel_options();
    o.r_max                   = int(state.range(0));
    run_filter(state, in, 1, o);
}

/// RMax with the trial radii beyond the default r_max (16) fitted on the
/// pyramid's level 1 (FilterOptions::pyramid_radius 32, docs/FILTER.md 5.1).
void
RMaxPyramid(benchmark::State& state)
{
    const KernelInput in(synth::fine_texture(kSize, kSize, { 2, 7 }));
    zdenoise::FilterOptions o = kernel_options();
    o.r_max                   = int(state.range(0));
    o.pyramid_radius          = 32;
    run_filter(state, in, 1, o);
}

/// The default filter (the selection, docs/FILTER.md section 13, default
/// stride) on the staircase at 8 spp: candidate 0, the feature
/// regressions, the risks and the choice.
void
Selection(benchmark::State& state)
{
    const KernelInput in(synth::staircase(kSize, kSize, 8, { 8, 7 }));
    run_filter(state, in, 1, zdenoise::FilterOptions {});
}

}  // namespace

BENCHMARK(Staircase)->Arg(2)->Arg(8)->Arg(32)->Arg(128)->Unit(benchmark::kMillisecond);
BENCHMARK(FineTexture)->Arg(2)->Arg(8)->Arg(32)->Arg(128)->Unit(benchmark::kMillisecond);
BENCHMARK(StaircaseThreads)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(RMax)->Arg(16)->Arg(32)->Arg(64)->Unit(benchmark::kMillisecond);
BENCHMARK(RMaxPyramid)->Arg(32)->Arg(64)->Unit(benchmark::kMillisecond);
BENCHMARK(Selection)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
