#!/usr/bin/python3
"""path_cost.py - the default's wall time beside beauty mode, Intel OIDN and oiiotool, in one run.

On one frame (default: ../shared/data/perf/cornell_1080p_spp16.exr, which has Cycles' lobe
passes, so that no flags filters it by path), runs alternately, --runs times each:

  zdenoise (no flags)        the default: light by path where the render has DiffDir
  zdenoise --mode beauty     the beauty as one (the default before light by path)
  oidnDenoise                Intel OIDN 2.4 --hdr with the file's albedo and normal, on PFMs
                             written beforehand (its process; its filter's own msec from -v 2)
  oiiotool                   reading the frame and writing its Combined RGBA
  oiiotool, every channel    reading the frame and writing all of it (what zdenoise's
                             output holds: the denoised beauty and every channel carried
                             through): the floor of zdenoise's own reading and writing

and prints each one's median wall time and peak RSS (/usr/bin/time -f '%e %M'), zdenoise's
own read / denoise / write seconds (its -v line), and zdenoise's ratios to beauty mode, to
OIDN's process and filter, and to oiiotool.

    bench/path_cost.py --oidn OIDN_DIR [--in FRAME.exr] [--runs 3] [--threads 2]
                       [--extra "LABEL=FLAGS" ...]

Each --extra adds a zdenoise column with those flags (`--extra "edges 2=--stride-edges 2"`).

OIDN_DIR: ../shared/peers/oidn-install.tar.zst extracted (bin/oidnDenoise). A yardstick run
beside zdenoise, never part of it. Runs with Debian's /usr/bin/python3.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.path.normpath(os.path.join(REPO, "..", "shared"))


def timed(cmd, env=None):
    """(wall seconds, peak RSS MiB, stderr) of one run of cmd."""
    r = subprocess.run(["/usr/bin/time", "-f", "%e %M"] + cmd, capture_output=True, text=True,
                       env=env)
    if r.returncode != 0:
        sys.exit(f"path_cost.py: {cmd[0]} failed: {r.stderr.strip()[-400:]}")
    wall, rss = r.stderr.strip().split("\n")[-1].split()
    return float(wall), float(rss) / 1024.0, r.stdout + r.stderr


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--in", dest="frame",
                    default=os.path.join(SHARED, "data", "perf", "cornell_1080p_spp16.exr"))
    ap.add_argument("--oidn", required=True, help="extracted oidn-install directory")
    ap.add_argument("--zdenoise", default=os.path.join(REPO, "build", "bin", "zdenoise"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--extra", action="append", default=[],
                    help="LABEL=FLAGS: another zdenoise column with FLAGS")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="zd_path_cost_")
    pfm = os.path.join(tmp, "in")
    subprocess.run(["/usr/bin/python3", os.path.join(SHARED, "peers", "exr2pfm.py"), a.frame, pfm,
                    "beauty", "alb", "nrm"], check=True)
    oidn_env = dict(os.environ, LD_LIBRARY_PATH=os.path.join(a.oidn, "lib"))
    t = str(a.threads)
    rgba = ",".join(f"ViewLayer.Combined.{c}" for c in "RGBA")
    # The rows the ratios are taken against, by name.
    beauty = "zdenoise --mode beauty"
    oidn_name = "oidnDenoise (process)"
    oiio_name = "oiiotool read + write"
    tools = [
        ("zdenoise (no flags: path)", [a.zdenoise, "--in", a.frame, "-o",
                                       os.path.join(tmp, "path.exr"), "--threads", t, "-v"], None),
        (beauty, [a.zdenoise, "--in", a.frame, "-o", os.path.join(tmp, "beauty.exr"),
                  "--threads", t, "--mode", "beauty", "-v"], None),
        (oidn_name, [os.path.join(a.oidn, "bin", "oidnDenoise"), "--hdr", pfm + "_beauty.pfm",
                     "--alb", pfm + "_alb.pfm", "--nrm", pfm + "_nrm.pfm", "--threads", t,
                     "-v", "2", "-o", os.path.join(tmp, "oidn.pfm")], oidn_env),
        (oiio_name, ["oiiotool", "--threads", t, a.frame, "--ch", rgba, "-o",
                     os.path.join(tmp, "oiio.exr")], None),
        ("oiiotool, every channel", ["oiiotool", "--threads", t, a.frame, "-o",
                                     os.path.join(tmp, "oiio_all.exr")], None),
    ]
    for n, extra in enumerate(a.extra):
        label, _, flags = extra.partition("=")
        tools.insert(2 + n, (f"zdenoise {label}", [a.zdenoise, "--in", a.frame, "-o",
                                                   os.path.join(tmp, f"extra{n}.exr"),
                                                   "--threads", t, "-v"] + flags.split(),
                              None))
    walls = {name: [] for name, _, _ in tools}
    rss = {name: [] for name, _, _ in tools}
    oidn_filter = []
    zdenoise_rows = [name for name, _, _ in tools if name.startswith("zdenoise")]
    stages = {name: [] for name in zdenoise_rows}
    for _ in range(a.runs):
        for name, cmd, env in tools:
            wall, peak, out = timed(cmd, env)
            walls[name].append(wall)
            rss[name].append(peak)
            if name == oidn_name:
                ms = re.findall(r"msec=([\d.]+)", out)
                if ms:
                    oidn_filter.append(float(ms[-1]) / 1000.0)
            times = re.findall(r"read ([\d.]+)s, denoise ([\d.]+)s, write ([\d.]+)s", out)
            if name in stages and times:
                stages[name].append(tuple(float(v) for v in times[-1]))
    med = {n: statistics.median(v) for n, v in walls.items()}
    print(f"{a.frame}, {a.threads} threads, median of {a.runs} alternating runs\n")
    print("| tool | wall (s) | runs | peak RSS (MiB) |")
    print("|---|---|---|---|")
    for name, _, _ in tools:
        print(f"| {name} | {med[name]:.2f} | {' / '.join(f'{w:.2f}' for w in walls[name])} "
              f"| {statistics.median(rss[name]):.0f} |")
    if oidn_filter:
        med["oidn filter"] = statistics.median(oidn_filter)
        print(f"| OIDN's filter (its msec) | {med['oidn filter']:.2f} | "
              f"{' / '.join(f'{w:.2f}' for w in oidn_filter)} | |")
    print("\nzdenoise's own stages (its -v line), medians:\n")
    print("| zdenoise | read (s) | denoise (s) | write (s) |")
    print("|---|---|---|---|")
    for name, runs in stages.items():
        if runs:
            print(f"| {name} | " + " | ".join(f"{statistics.median(r[k] for r in runs):.2f}"
                                            for k in range(3)) + " |")
    print()
    for name in zdenoise_rows:
        print(f"{name}: {med[name] / med[beauty]:.2f}x beauty mode, "
              f"{med[name] / med[oidn_name]:.2f}x OIDN's process, "
              f"{med[name] / med[oiio_name]:.2f}x oiiotool"
              + (f", {med[name] / med['oidn filter']:.2f}x OIDN's filter" if oidn_filter else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
