#!/usr/bin/python3
"""cancel_latency.py - how soon a cancelled denoise stops, on the 1080p frame.

Runs zdenoise.denoise() (the Python module, i.e. the library's denoise())
on the beauty, albedo, normal, depth and Cryptomatte ids of
../shared/data/perf/cornell_1080p_spp16.exr with the command's defaults
(albedo_samples=16, as the command reads it from the file), threads=2.
First it times whole runs; then, for each fraction (default 25, 50 and
75 % of that time), it starts a run in a worker thread, sets its
zdenoise.Cancel from this thread at that point, and reports the time from
the set to the call's return (zdenoise.Cancelled), the median of --repeat
runs. --fractions 0.05,0.1,... scans for the slowest stage to stop.

    flock /tmp/zd-build.lock bench/cancel_latency.py
    bench/cancel_latency.py --build build-release --fractions 0.1,0.9

Run with Debian's /usr/bin/python3 (OpenImageIO, numpy); the module is
taken from --build/python.
"""
import argparse
import os
import statistics
import sys
import threading
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FRAME = os.path.join(os.path.dirname(REPO), "shared", "data", "perf",
                     "cornell_1080p_spp16.exr")


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--build", default=os.path.join(REPO, "build"))
    p.add_argument("--frame", default=FRAME)
    p.add_argument("--fractions", default="0.25,0.5,0.75")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--threads", type=int, default=2)
    return p.parse_args()


def read_inputs(path):
    """The arrays the command takes from a Cycles frame in beauty mode."""
    import OpenImageIO as oiio
    image = oiio.ImageBuf(path)
    pixels = image.get_pixels(oiio.FLOAT)
    if image.has_error:
        sys.exit("cancel_latency: %s" % image.geterror())
    names = list(image.spec().channelnames)

    def pick(*channels):
        return pixels[:, :, [names.index("ViewLayer." + c) for c in channels]]

    return dict(
        radiance=pick(*("Combined." + c for c in "RGBA")),
        albedo=pick(*("Denoising Albedo." + c for c in "RGB")),
        normal=pick(*("Denoising Normal." + c for c in "XYZ")),
        depth=pick("Denoising Depth.Z"),
        ids=pick(*("CryptoObject00." + c for c in "rgba")))


def cancelled_run(zdenoise, inputs, options, delay):
    """Seconds from setting the Cancel `delay` s into a run to its return,
    or None when the run finished first."""
    flag = zdenoise.Cancel()
    started = threading.Event()
    returned = {}

    def work():
        started.set()
        try:
            zdenoise.denoise(cancel=flag, **inputs, **options)
        except zdenoise.Cancelled:
            returned["cancelled"] = True
        returned["at"] = time.monotonic()

    worker = threading.Thread(target=work)
    worker.start()
    started.wait()
    time.sleep(delay)
    set_at = time.monotonic()
    flag.cancel()
    worker.join()
    return returned["at"] - set_at if returned.get("cancelled") else None


def main():
    args = parse_args()
    sys.path.insert(0, os.path.join(args.build, "python"))
    import zdenoise
    inputs = read_inputs(args.frame)
    options = dict(albedo_samples=16, threads=args.threads)
    whole = []
    for _ in range(args.repeat):
        t0 = time.monotonic()
        zdenoise.denoise(**inputs, **options)
        whole.append(time.monotonic() - t0)
    run = statistics.median(whole)
    print("whole run: median %.2f s of %s (threads %d)"
          % (run, ", ".join("%.2f" % t for t in whole), args.threads))
    print("| set at | latency median (s) | runs (s) |")
    print("|---|---|---|")
    for fraction in (float(f) for f in args.fractions.split(",")):
        stops = [cancelled_run(zdenoise, inputs, options, fraction * run)
                 for _ in range(args.repeat)]
        done = [s for s in stops if s is not None]
        text = ", ".join("%.3f" % s if s is not None else "finished" for s in stops)
        median = "%.3f" % statistics.median(done) if done else "-"
        print("| %d %% | %s | %s |" % (round(100 * fraction), median, text))


if __name__ == "__main__":
    main()
