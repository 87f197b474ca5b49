#!/usr/bin/python3
"""stage_profile.py - where zdenoise's time goes, stage by stage, on one frame.

Runs zdenoise once on one thread under `perf record` (call graphs by DWARF unwinding), then
prints each stage's inclusive share of the samples and the seconds that share is of the
one-thread wall time. Stages are found by their functions' names, so the table reads against
the source (docs/ARCHITECTURE.md names each stage's file). Shares nest: the windows are part
of candidate 0, which is part of the regression filter, which is part of the denoise.

    bench/stage_profile.py [--in FRAME.exr] [--frequency 99] [-- ZDENOISE FLAGS...]

Default frame: ../shared/data/perf/cornell_1080p_spp16.exr. Needs Linux `perf` with
permission to profile (perf_event_paranoid <= 2). A sample whose stack does not unwind to
main() counts in no stage, so the shares add to a little less than 100 %.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.path.normpath(os.path.join(REPO, "..", "shared"))

# (stage, regular expression a function's name matches), outermost first.
STAGES = [
    ("read the strips' channels", r"zdenoise::job::load_layers"),
    ("  colour prefilter (samples)", r"zdenoise::\(anonymous namespace\)::prefilter\b"),
    ("denoise, all layers", r"zdenoise::layered_denoise\b|zdenoise::denoise\b"),
    ("  regression filter", r"zdenoise::regression_filter\b"),
    ("    inputs: decode, noise estimate", r"zdenoise::detail::decode_filter_inputs"),
    ("      of it: noise estimate", r"zdenoise::detail::raw_variance"),
    ("    candidate 0", r"zdenoise::detail::\(anonymous namespace\)::run_candidate0"),
    ("      of it: the windows", r"zdenoise::detail::fit_block"),
    ("      of it: fireflies spread", r"zdenoise::detail::spread_outliers"),
    ("    feature regressions", r"zdenoise::feature_regression\b"),
    ("    selection: risks, choice", r"candidate_risks|risk_inputs|write_selected"),
    ("    energy correction", r"zdenoise::detail::correct_energy"),
    ("  direct light: keep structure", r"zdenoise::keep_structure\b"),
    ("write (compression)", r"\bdeflate\b|compress2"),
]


def inclusive_shares(data):
    """{symbol: inclusive percent} from perf report --children."""
    out = subprocess.run(["perf", "report", "-i", data, "--children", "--sort", "symbol",
                          "--stdio", "-g", "none"], capture_output=True, text=True).stdout
    shares = {}
    for line in out.splitlines():
        m = re.match(r"\s+([\d.]+)%\s+[\d.]+%\s+\[\.\]\s+(.*?)\s*$", line)
        if m:
            shares[m.group(2)] = max(shares.get(m.group(2), 0.0), float(m.group(1)))
    return shares


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--in", dest="frame",
                    default=os.path.join(SHARED, "data", "perf", "cornell_1080p_spp16.exr"))
    ap.add_argument("--zdenoise", default=os.path.join(REPO, "build", "bin", "zdenoise"))
    ap.add_argument("--frequency", type=int, default=99)
    ap.add_argument("flags", nargs="*", help="zdenoise flags, after --")
    args = ap.parse_args()
    for path in (args.frame, args.zdenoise):
        if not os.path.exists(path):
            sys.exit(f"stage_profile.py: '{path}' does not exist")
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "perf.data")
        cmd = ["perf", "record", "-q", "-o", data, "-F", str(args.frequency),
               "--call-graph", "dwarf,32768", args.zdenoise, "--in", args.frame,
               "-o", os.path.join(tmp, "out.exr"), "--threads", "1"] + args.flags
        t0 = time.perf_counter()
        r = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if r.returncode != 0:
            sys.exit(f"stage_profile.py: perf record failed: {r.stderr.strip()[-400:]}")
        shares = inclusive_shares(data)
    print(f"zdenoise {' '.join(args.flags) or '(no flags)'} on {os.path.basename(args.frame)}, "
          f"1 thread under perf: {wall:.1f} s wall\n")
    print("| stage | share of samples | seconds of the wall time |")
    print("|---|---|---|")
    for name, pattern in STAGES:
        share = max((s for sym, s in shares.items() if re.search(pattern, sym)), default=0.0)
        label = name.strip()
        indent = "&nbsp;" * (len(name) - len(name.lstrip()))
        print(f"| {indent}{label} | {share:.1f} % | {share * wall / 100:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
