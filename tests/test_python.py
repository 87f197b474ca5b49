# Copyright zdenoise contributors.
# SPDX-License-Identifier: BSD-3-Clause
"""The Python module as a pipeline script meets it, with Debian's python3
(tests/CMakeLists.txt runs this with PYTHONPATH at the built module):
zdenoise.denoise on numpy arrays, zdenoise.denoise_file against the
zdenoise command, the errors of each, and share/examples/oiio_numpy.py.

Environment: ZDENOISE_CLI (the command), ZDENOISE_SOURCE_DIR, and
ZDENOISE_HOST_ENV (in a sanitized build, what python3 was started with to
load the instrumented module; the command, built with the sanitizers, is
run without it).
"""

import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import numpy as np

import zdenoise

CLI = os.environ["ZDENOISE_CLI"]
SOURCE_DIR = os.environ["ZDENOISE_SOURCE_DIR"]
SAMPLE = os.path.join(SOURCE_DIR, "share/samples/cornell_textured_spp16_crop.exr")
REFERENCE = os.path.join(SOURCE_DIR, "share/samples/cornell_textured_ref_crop.exr")
EXAMPLE = os.path.join(SOURCE_DIR, "share/examples/oiio_numpy.py")


def command_env():
    """The environment for the command: this one without what
    ZDENOISE_HOST_ENV added for python3 (the command links the sanitizer
    runtime itself, and keeps its leak checking)."""
    env = dict(os.environ)
    for word in os.environ.get("ZDENOISE_HOST_ENV", "").split():
        env.pop(word.partition("=")[0], None)
    return env


def textured_scene(height=96, width=128, spp=4, seed=7):
    """A noisy render and its clean version: a textured albedo (checks,
    stripes, a gradient) under smooth light, the radiance of `spp` samples
    of a noisy estimator with the clean mean."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    checks = ((x // 8 + y // 8) % 2) * 0.5 + 0.3
    stripes = 0.6 + 0.3 * np.sin(x / 3.0)
    albedo = np.empty((height, width, 3))
    albedo[..., 0] = checks
    albedo[..., 1] = np.where(x < width / 2, stripes, checks * 0.8)
    albedo[..., 2] = 0.2 + 0.6 * y / height
    light = 1.0 + 0.8 * np.exp(-((x - 0.3 * width) ** 2 + (y - 0.4 * height) ** 2)
                               / (0.2 * width * height))
    clean = albedo * light[..., None]
    rng = np.random.default_rng(seed)
    # The mean of spp samples of an exponential estimator (relative
    # noise 1/sqrt(spp) per pixel).
    noise = rng.gamma(spp, 1.0 / spp, clean.shape)
    noisy = clean * noise
    return (noisy.astype(np.float32), albedo.astype(np.float32),
            clean.astype(np.float32))


def rmse(a, b):
    return float(np.sqrt(np.mean((a.astype(np.float64) - b) ** 2)))


def read_pixels(path):
    import OpenImageIO as oiio
    image = oiio.ImageBuf(path)
    pixels = image.get_pixels(oiio.FLOAT)
    assert not image.has_error, image.geterror()
    return pixels, list(image.spec().channelnames)


class Arrays(unittest.TestCase):
    def setUp(self):
        self.noisy, self.albedo, self.clean = textured_scene()

    def test_reduces_noise_and_keeps_the_mean(self):
        out = zdenoise.denoise(self.noisy, self.albedo)
        self.assertEqual(out.dtype, np.float32)
        self.assertEqual(out.shape, self.noisy.shape)
        before, after = rmse(self.noisy, self.clean), rmse(out, self.clean)
        self.assertLess(after * 3.0, before,
                        "RMSE %.4f -> %.4f: expected 3x less" % (before, after))
        mean_out, mean_clean = float(out.mean()), float(self.clean.mean())
        self.assertLess(abs(mean_out / mean_clean - 1.0), 0.02,
                        "mean %.5f, clean %.5f" % (mean_out, mean_clean))
        # Its inputs are left as they were.
        self.assertTrue(np.array_equal(self.noisy, textured_scene()[0]))

    def test_diagnostics_are_the_librarys_maps(self):
        # diagnostics=True: the same image, and the maps of
        # docs/DIAGNOSTICS.md beside it.
        out, maps = zdenoise.denoise(self.noisy, self.albedo, diagnostics=True)
        self.assertTrue(np.array_equal(out, zdenoise.denoise(self.noisy, self.albedo)))
        self.assertEqual(maps.shape, self.noisy.shape[:2] + (4,))
        self.assertEqual(maps.dtype, np.float32)
        radius, stop, noise, error = (maps[:, :, c] for c in range(4))
        # (a mean of the windows' radii, to rounding)
        self.assertTrue(((radius > 2 - 1e-4) & (radius < 16 + 1e-4)).all())
        self.assertTrue(np.isin(stop, [1, 2, 3]).all())
        self.assertGreater(float(noise.mean()), 0.0)
        self.assertTrue(((error > 0) & (error < 1)).all())
        # The remaining error is far below the input's noise.
        self.assertLess(float(error.mean()) * 3, float(noise.mean()))

    def test_any_dtype_is_the_float32_result(self):
        for dtype in (np.float64, np.float16):
            noisy, albedo = self.noisy.astype(dtype), self.albedo.astype(dtype)
            out = zdenoise.denoise(noisy, albedo)
            expected = zdenoise.denoise(noisy.astype(np.float32),
                                        albedo.astype(np.float32))
            self.assertEqual(out.dtype, np.float32)
            self.assertTrue(np.array_equal(out, expected), dtype)
        # Not C-contiguous (a view), a list of lists: copied first.
        wide = np.concatenate([self.noisy, self.noisy], axis=1)[:, ::2]
        self.assertFalse(wide.flags.c_contiguous)
        self.assertTrue(np.array_equal(
            zdenoise.denoise(wide, self.albedo),
            zdenoise.denoise(np.ascontiguousarray(wide), self.albedo)))
        small = self.noisy[:8, :8]
        self.assertTrue(np.array_equal(
            zdenoise.denoise(small.tolist(), self.albedo[:8, :8]),
            zdenoise.denoise(small, self.albedo[:8, :8])))

    def test_extra_channels_are_copied(self):
        alpha = np.linspace(0.5, 1.0, self.noisy.shape[1], dtype=np.float32)
        rgba = np.dstack([self.noisy, np.broadcast_to(alpha, self.noisy.shape[:2]),
                          self.noisy[..., :1] * 2])
        out = zdenoise.denoise(rgba, self.albedo)
        self.assertEqual(out.shape, rgba.shape)
        self.assertTrue(np.array_equal(out[..., 3:], rgba[..., 3:]))

    def test_guides(self):
        h, w = self.noisy.shape[:2]
        normal = np.zeros((h, w, 3), np.float32)
        normal[..., 2] = 1.0
        depth = np.full((h, w), 4.0, np.float32)
        ids = np.ones((h, w), np.int32)
        variance = np.full((h, w, 3), 0.01, np.float32)
        out = zdenoise.denoise(self.noisy, self.albedo, normal=normal,
                               depth=depth, ids=ids, variance=variance)
        self.assertLess(rmse(out, self.clean) * 3.0,
                        rmse(self.noisy, self.clean))
        # H x W is H x W x 1.
        self.assertTrue(np.array_equal(out, zdenoise.denoise(
            self.noisy, self.albedo, normal=normal, depth=depth[..., None],
            ids=ids[..., None], variance=variance)))
        # Object ids split the image: not what one id gives.
        halves_ids = (np.arange(w)[None, :] >= w // 2).repeat(h, 0)
        self.assertFalse(np.array_equal(out, zdenoise.denoise(
            self.noisy, self.albedo, normal=normal, depth=depth,
            ids=halves_ids, variance=variance)))
        # Halves: two half renders whose mean is the radiance.
        rng = np.random.default_rng(3)
        a = self.noisy * rng.uniform(0.8, 1.2, self.noisy.shape).astype(np.float32)
        b = 2.0 * self.noisy - a
        zdenoise.denoise(self.noisy, self.albedo, halves=(a, b))
        zdenoise.denoise(self.noisy, self.albedo, halves=[a, b])

    def test_wrong_shapes_are_value_errors_naming_the_argument(self):
        h, w = self.noisy.shape[:2]
        rgb = np.zeros((h, w, 3), np.float32)
        cases = [
            (dict(radiance=self.noisy[..., 0], albedo=self.albedo),
             "radiance: expected H×W×C with C >= 3 (R, G, B and any others, "
             "which are copied), got %d×%d" % (h, w)),
            (dict(radiance=self.noisy[..., :2], albedo=self.albedo),
             "radiance: expected H×W×C with C >= 3"),
            (dict(radiance=self.noisy, albedo=np.dstack([self.albedo, rgb[..., :1]])),
             "albedo: expected H×W×3 like radiance (%d×%d), got %d×%d×4" % (h, w, h, w)),
            (dict(radiance=self.noisy, albedo=self.albedo[:10]),
             "albedo: expected H×W×3 like radiance (%d×%d), got 10×%d×3" % (h, w, w)),
            (dict(radiance=self.noisy, albedo=None),
             "albedo: expected a numpy array, got NoneType"),
            (dict(radiance=self.noisy, albedo=self.albedo, normal=rgb[..., :2]),
             "normal: expected H×W×3 like radiance"),
            (dict(radiance=self.noisy, albedo=self.albedo, depth=rgb),
             "depth: expected H×W×1 (or H×W) like radiance"),
            (dict(radiance=self.noisy, albedo=self.albedo, ids=rgb),
             "ids: expected H×W×1 or H×W×2k"),
            (dict(radiance=self.noisy, albedo=self.albedo, variance=rgb[..., :2]),
             "variance: expected H×W×1 or H×W×3 (or H×W) like radiance"),
            (dict(radiance=self.noisy, albedo=self.albedo, halves=rgb),
             "halves: expected a pair (A, B) of H×W×3 arrays like radiance "
             "(%d×%d), got ndarray" % (h, w)),
            (dict(radiance=self.noisy, albedo=self.albedo, halves=(rgb,)),
             "halves: expected a pair (A, B) of H×W×3 arrays like radiance "
             "(%d×%d), got a tuple of 1" % (h, w)),
            (dict(radiance=self.noisy, albedo=self.albedo, halves=(rgb, rgb[1:])),
             "halves[1]: expected H×W×3 like radiance"),
            (dict(radiance=self.noisy, albedo=np.full((h, w, 3), "x")),
             "albedo: expected numbers, got an array of dtype <U1"),
        ]
        for arguments, message in cases:
            with self.assertRaises(ValueError, msg=message) as caught:
                zdenoise.denoise(**arguments)
            self.assertTrue(str(caught.exception).startswith(message),
                            "%r does not start with %r" % (str(caught.exception), message))

    def test_options_are_the_librarys(self):
        default = zdenoise.denoise(self.noisy, self.albedo)
        # Options change the result; None is "not given"; the thread count
        # does not change it.
        self.assertFalse(np.array_equal(
            default, zdenoise.denoise(self.noisy, self.albedo, eta=0.05)))
        self.assertTrue(np.array_equal(
            default, zdenoise.denoise(self.noisy, self.albedo, eta=None, threads=1)))
        self.assertTrue(np.array_equal(
            default, zdenoise.denoise(self.noisy, self.albedo, threads=2)))
        # The preset first, the others on top, whatever their order; the
        # keyword spelling of value-k.
        spec = dict(edge_k=3, value_k=2, sigma_good=1, radius_growth=1,
                    stride=1, outlier_spread=0, value_noise=0, select=0,
                    energy_radius=0)
        self.assertTrue(np.array_equal(
            zdenoise.denoise(self.noisy, self.albedo, eta=0.03, preset="spec"),
            zdenoise.denoise(self.noisy, self.albedo, eta=0.03, **spec)))
        # numpy scalars are numbers.
        self.assertTrue(np.array_equal(
            zdenoise.denoise(self.noisy, self.albedo, eta=np.float32(0.05),
                             rmax=np.int64(16)),
            zdenoise.denoise(self.noisy, self.albedo, eta=0.05)))

        cases = [
            (dict(eta="abc"), '"eta" must be a number, not "abc"'),
            (dict(value_k=True), '"value_k" must be a number, not true'),
            (dict(rmin=2.5), '"rmin" must be a whole number, not 2.5'),
            (dict(preset="fast"), "unknown preset 'fast' (known: tuned, spec)"),
            (dict(threads=-1), '"threads" must be 0 (automatic) or more, not -1'),
            (dict(eta=-1), "regression_filter: option eta_target = -1 is invalid: "
                           "needs a finite number >= 0"),
            (dict(rmin=0), "regression_filter: option r_min = 0 is invalid: needs >= 1"),
            (dict(eta=float("nan")), '"eta" must be a number, not "nan"'),
        ]
        for options, message in cases:
            with self.assertRaises(ValueError) as caught:
                zdenoise.denoise(self.noisy, self.albedo, **options)
            self.assertEqual(str(caught.exception), message)
        # An unknown key: the library's message, which lists the keys
        # denoise() takes, in their keyword spelling.
        with self.assertRaises(ValueError) as caught:
            zdenoise.denoise(self.noisy, self.albedo, valuek=1)
        message = str(caught.exception)
        self.assertTrue(message.startswith('unknown key "valuek" (known: albedo_samples, '
                                           'diagnostics, preset, rmin, rmax, eta, edge_k, '
                                           'tau_min, value_k,'), message)
        known = message[message.index("(known: ") + 8:-1].split(", ")
        self.assertIn("threads", known)
        self.assertNotIn("albedo", known)
        self.assertNotIn("tile", known)
        # A job's option is not the filter's.
        with self.assertRaises(ValueError) as caught:
            zdenoise.denoise(self.noisy, self.albedo, mode="layers")
        self.assertTrue(str(caught.exception).startswith('unknown key "mode"'))
        with self.assertRaises(TypeError) as caught:
            zdenoise.denoise(self.noisy, self.albedo, eta=object())
        self.assertTrue(str(caught.exception).startswith("eta: cannot take a object"))

    def test_the_gil_is_released(self):
        # While one thread denoises, another runs Python.
        noisy, albedo, _ = textured_scene(192, 256)
        span = {}

        def work():
            span["start"] = time.monotonic()
            zdenoise.denoise(noisy, albedo, stride=1)
            span["end"] = time.monotonic()

        worker = threading.Thread(target=work)
        ticks = []
        worker.start()
        while worker.is_alive():
            ticks.append(time.monotonic())
            time.sleep(0.001)
        worker.join()
        duration = span["end"] - span["start"]
        inside = [t for t in ticks
                  if span["start"] + 0.2 * duration < t < span["end"] - 0.2 * duration]
        self.assertGreater(duration, 0.05)
        self.assertGreater(len(inside), 5,
                           "the main thread ran %d times in the middle of a "
                           "%.2f s denoise" % (len(inside), duration))

    def test_matches_the_command_on_the_cycles_channels(self):
        # The array call on the channels the command picks from the sample
        # (a scene-linear EXR: no colour conversion) is the command's beauty
        # mode.
        with tempfile.TemporaryDirectory() as folder:
            out = os.path.join(folder, "beauty.exr")
            subprocess.run([CLI, "--in", SAMPLE, "-o", out, "--eta", "0.03",
                            "--mode", "beauty"], check=True, env=command_env())
            expected, names = read_pixels(out)
        pixels, names = read_pixels(SAMPLE)

        def pick(*channels):
            return pixels[:, :, [names.index("ViewLayer." + c) for c in channels]]

        beauty = ["Combined." + c for c in "RGBA"]
        out = zdenoise.denoise(
            pick(*beauty), pick(*("Denoising Albedo." + c for c in "RGB")),
            normal=pick(*("Denoising Normal." + c for c in "XYZ")),
            depth=pick("Denoising Depth.Z"),
            ids=pick(*("CryptoObject00." + c for c in "rgba")), eta=0.03,
            albedo_samples=16)  # the command reads it from the file
        self.assertTrue(np.array_equal(
            out, expected[:, :, [names.index("ViewLayer." + c) for c in beauty]]))


class Files(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.mkdtemp()

    def tearDown(self):
        shutil.rmtree(self.folder)

    def path(self, name):
        return os.path.join(self.folder, name)

    def command(self, *args):
        return subprocess.run([CLI, *args], capture_output=True, text=True,
                              env=command_env())

    def files(self):
        return sorted(os.listdir(self.folder))

    def test_the_same_file_as_the_command(self):
        cases = [
            ([], {}),
            (["--mode", "layers", "--eta", "0.03", "--aovs", "-d", "half",
              "--albedo:ch=ViewLayer.DiffCol", SAMPLE, "--no-depth", "--tile", "40"],
             dict(mode="layers", eta=0.03, aovs=True, data_type="half",
                  albedo={"path": SAMPLE, "channels": "ViewLayer.DiffCol"},
                  no_depth=True, tile=40)),
            (["--preset", "spec", "--value-k", "1.5", "--halves", SAMPLE, SAMPLE,
              "--threads", "1"],
             dict(value_k=1.5, preset="spec", halves=(SAMPLE, SAMPLE), threads=1)),
        ]
        for k, (args, options) in enumerate(cases):
            by_command, by_module = self.path("cmd%d.exr" % k), self.path("py%d.exr" % k)
            r = self.command("--in", SAMPLE, "-o", by_command, *args)
            self.assertEqual(r.returncode, 0, r.stderr)
            stats = zdenoise.denoise_file(SAMPLE, by_module, **options)
            with open(by_command, "rb") as a, open(by_module, "rb") as b:
                self.assertTrue(a.read() == b.read(),
                                "denoise_file(%r) is not the command's file (%s)"
                                % (options, " ".join(args)))
            self.assertGreater(stats["windows"], 0)
        # The maps as the command adds them.
        r = self.command("--in", SAMPLE, "-o", self.path("cmd_maps.exr"), "--diagnostics")
        self.assertEqual(r.returncode, 0, r.stderr)
        zdenoise.denoise_file(SAMPLE, self.path("py_maps.exr"), diagnostics=True)
        with open(self.path("cmd_maps.exr"), "rb") as a, open(self.path("py_maps.exr"), "rb") as b:
            self.assertTrue(a.read() == b.read(), "denoise_file(diagnostics=True)")
        os.remove(self.path("cmd_maps.exr"))
        os.remove(self.path("py_maps.exr"))
        # Paths as os.PathLike; nothing left behind but the outputs.
        import pathlib
        zdenoise.denoise_file(pathlib.Path(SAMPLE), pathlib.Path(self.path("p.exr")))
        self.assertEqual(self.files(), ["cmd0.exr", "cmd1.exr", "cmd2.exr", "p.exr",
                                        "py0.exr", "py1.exr", "py2.exr"])

    def test_a_frame_of_a_sequence_with_its_neighbours(self):
        # frame="2" of patterned inputs, with temporal=1: the file the
        # command writes for frame 2 of the sequence (docs/TEMPORAL.md).
        import OpenImageIO as oiio
        for f in (1, 2, 3):
            noisy, albedo, _ = textured_scene(seed=40 + f)
            for name, pixels in (("noisy", noisy), ("albedo", albedo)):
                image = oiio.ImageBuf(oiio.ImageSpec(pixels.shape[1], pixels.shape[0], 3,
                                                     oiio.FLOAT))
                image.set_pixels(oiio.ROI(), pixels)
                self.assertTrue(image.write(self.path("%s.%04d.exr" % (name, f))),
                                image.geterror())
        noisy, albedo = self.path("noisy.#.exr"), self.path("albedo.#.exr")
        r = self.command("--in", noisy, "--albedo", albedo, "--frames", "1-3",
                         "--temporal", "1", "--static-camera", "-o", self.path("cmd.#.exr"))
        self.assertEqual(r.returncode, 0, r.stderr)
        zdenoise.denoise_file(noisy, self.path("py.exr"), albedo=albedo, frame="2",
                              temporal=1, static_camera=True, shot_range="1-3")
        with open(self.path("cmd.0002.exr"), "rb") as a, open(self.path("py.exr"), "rb") as b:
            self.assertTrue(a.read() == b.read(), "frame 2 is not the command's")
        for options, message in [
            (dict(temporal=1, static_camera=True), '"temporal" needs "frame"'),
            (dict(frame="2", temporal=1, static_camera=True), '"temporal" needs "shot-range"'),
            (dict(frame="2-3"), '"frame" must be one frame'),
        ]:
            with self.assertRaises(ValueError) as caught:
                zdenoise.denoise_file(noisy, self.path("out.exr"), albedo=albedo, **options)
            self.assertTrue(str(caught.exception).startswith(message), str(caught.exception))

    def test_statistics(self):
        stats = zdenoise.denoise_file(SAMPLE, self.path("out.exr"), tile=32)
        keys = {"pixels", "windows", "stop_quality", "stop_size", "stop_edge",
                "mean_radius", "radius_sum", "passthrough_pixels",
                "nonfinite_pixels", "read_seconds", "denoise_seconds",
                "write_seconds", "strips", "strip_rows", "estimated_bytes", "log"}
        self.assertEqual(set(stats), keys)
        self.assertEqual(stats["pixels"], 96 * 96)
        self.assertEqual(stats["stop_quality"] + stats["stop_size"] + stats["stop_edge"],
                         stats["windows"])
        self.assertAlmostEqual(stats["mean_radius"],
                               stats["radius_sum"] / stats["windows"])
        self.assertEqual((stats["strips"], stats["strip_rows"]), (3, 32))
        for key in ("read_seconds", "denoise_seconds", "write_seconds"):
            self.assertGreaterEqual(stats[key], 0.0)
        # The lines -v prints of the job (after "zdenoise: ").
        self.assertTrue(all(isinstance(line, str) for line in stats["log"]))
        r = self.command("--in", SAMPLE, "-o", self.path("cmd.exr"), "--tile", "32", "-v")
        self.assertEqual(r.returncode, 0, r.stderr)
        printed = [line[len("zdenoise: "):] for line in r.stdout.splitlines()]
        self.assertEqual(printed[:len(stats["log"])], stats["log"])
        self.assertIn("parameters rmin=2 rmax=16 eta=0.02", "\n".join(stats["log"]))

    def test_errors_are_the_commands(self):
        # A job that fails: zdenoise.Error, a RuntimeError, with the
        # command's line; no output.
        missing = self.path("missing.exr")
        r = self.command("--in", missing, "-o", self.path("cmd.exr"))
        self.assertEqual(r.returncode, 1)
        with self.assertRaises(zdenoise.Error) as caught:
            zdenoise.denoise_file(missing, self.path("out.exr"))
        self.assertIsInstance(caught.exception, RuntimeError)
        self.assertEqual("zdenoise: error: %s\n" % caught.exception, r.stderr)
        with self.assertRaises(zdenoise.Error) as caught:
            zdenoise.denoise_file(SAMPLE, self.path("out.exr"),
                                  albedo={"path": SAMPLE, "channels": "Nope"})
        self.assertIn("Nope", str(caught.exception))
        self.assertEqual(self.files(), [])

        # An output that is an input: refused, untouched, unless force=True.
        shot = self.path("shot.exr")
        shutil.copy(SAMPLE, shot)
        with self.assertRaises(zdenoise.Error) as caught:
            zdenoise.denoise_file(shot, shot)
        self.assertEqual(str(caught.exception),
                         "the output '%s' is also an input; use force=True to "
                         "replace it" % shot)
        with open(shot, "rb") as f, open(SAMPLE, "rb") as g:
            self.assertTrue(f.read() == g.read())
        zdenoise.denoise_file(shot, shot, force=True)
        with open(shot, "rb") as f, open(SAMPLE, "rb") as g:
            self.assertFalse(f.read() == g.read())
        self.assertEqual(self.files(), ["shot.exr"])

        # Wrong options and arguments: ValueError (the command's usage
        # errors), TypeError for a value of no option's type.
        for options, message in [
            (dict(eta="x"), '"eta" must be a number, not "x"'),
            (dict(mode="lobes"), '"mode" must be "beauty", "layers" or "path", not "lobes"'),
            (dict(halves=(SAMPLE,)), '"halves" must be a list of two inputs, not'),
            (dict(tile=-1), '"tile" must be 0 (automatic) or a number of rows, not -1'),
            (dict(frames="1-10"), 'unknown key "frames" (known: albedo, aux, '),
        ]:
            with self.assertRaises(ValueError) as caught:
                zdenoise.denoise_file(SAMPLE, self.path("out.exr"), **options)
            self.assertTrue(str(caught.exception).startswith(message),
                            str(caught.exception))
        with self.assertRaises(ValueError) as caught:
            zdenoise.denoise_file(self.path("shot.#.exr"), self.path("out.#.exr"))
        self.assertIn("frame pattern", str(caught.exception))
        with self.assertRaises(TypeError):
            zdenoise.denoise_file(3, self.path("out.exr"))
        self.assertEqual(self.files(), ["shot.exr"])


class Cancelling(unittest.TestCase):
    """zdenoise.Cancel: set from another thread, the running call stops and
    raises zdenoise.Cancelled; given and never set, it changes nothing."""

    def setUp(self):
        self.noisy, self.albedo, _ = textured_scene(192, 256)

    def test_a_cancel_never_set_changes_nothing(self):
        flag = zdenoise.Cancel()
        self.assertFalse(flag.cancelled)
        self.assertTrue(np.array_equal(
            zdenoise.denoise(self.noisy, self.albedo, cancel=flag),
            zdenoise.denoise(self.noisy, self.albedo)))

    def test_a_cancel_set_before_the_call_raises_cancelled(self):
        flag = zdenoise.Cancel()
        flag.cancel()
        self.assertTrue(flag.cancelled)
        with self.assertRaises(zdenoise.Cancelled) as caught:
            zdenoise.denoise(self.noisy, self.albedo, cancel=flag)
        self.assertEqual(str(caught.exception), "zdenoise: cancelled")
        self.assertTrue(issubclass(zdenoise.Cancelled, zdenoise.Error))

    def test_another_thread_stops_a_running_denoise(self):
        flag = zdenoise.Cancel()
        started = threading.Event()
        outcome = {}

        def work():
            started.set()
            try:
                outcome["result"] = zdenoise.denoise(self.noisy, self.albedo,
                                                     stride=1, cancel=flag)
            except zdenoise.Cancelled as error:
                outcome["error"] = str(error)

        worker = threading.Thread(target=work)
        worker.start()
        started.wait()
        flag.cancel()  # while the worker runs (or is about to: the same)
        worker.join()
        self.assertNotIn("result", outcome, "no image is returned")
        self.assertEqual(outcome.get("error"), "zdenoise: cancelled")

    def test_a_cancelled_file_job_writes_no_file(self):
        with tempfile.TemporaryDirectory() as folder:
            out = os.path.join(folder, "out.exr")
            flag = zdenoise.Cancel()
            flag.cancel()
            with self.assertRaises(zdenoise.Cancelled) as caught:
                zdenoise.denoise_file(SAMPLE, out, cancel=flag)
            self.assertIn("cancelled", str(caught.exception))
            self.assertEqual(os.listdir(folder), [])


class Module(unittest.TestCase):
    def test_version_and_docstrings(self):
        r = subprocess.run([CLI, "--version"], capture_output=True, text=True,
                           env=command_env())
        self.assertEqual(r.stdout, "zdenoise %s\n" % zdenoise.__version__)
        for thing in (zdenoise, zdenoise.denoise, zdenoise.denoise_file,
                      zdenoise.Error):
            self.assertTrue(thing.__doc__)
        # The option names in the help come from the table.
        self.assertIn("value_k", zdenoise.denoise.__doc__)
        self.assertIn("working_colorspace", zdenoise.denoise_file.__doc__)
        self.assertTrue(issubclass(zdenoise.Error, RuntimeError))

    def test_the_example_runs(self):
        with tempfile.TemporaryDirectory() as folder:
            out = os.path.join(folder, "denoised.exr")
            r = subprocess.run([sys.executable, EXAMPLE, SAMPLE, out, "eta=0.03"],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("-> " + out, r.stdout)
            denoised, names = read_pixels(out)
            # Its output is the command's in beauty mode, every channel.
            by_command = os.path.join(folder, "cmd.exr")
            subprocess.run([CLI, "--in", SAMPLE, "-o", by_command, "--eta", "0.03",
                            "--mode", "beauty"], check=True, env=command_env())
            expected, expected_names = read_pixels(by_command)
            self.assertEqual(names, expected_names)
            self.assertTrue(np.array_equal(denoised, expected))
            # And nearer the reference than the noisy render.
            noisy, _ = read_pixels(SAMPLE)
            reference, _ = read_pixels(REFERENCE)
            rgb = [names.index("ViewLayer.Combined." + c) for c in "RGB"]
            self.assertLess(rmse(denoised[..., rgb], reference[..., :3]) * 2,
                            rmse(noisy[..., rgb], reference[..., :3]))


if __name__ == "__main__":
    unittest.main(verbosity=2)
