"""The Blender side of tests/blender_addon.sh (share/blender/zdenoise_addon.py).

    blender -b --factory-startup -noaudio --addons zdenoise_addon -P blender_addon_test.py \
        -- SCRATCH

Builds a tiny Cycles scene (64x64: a checkered plane, a sphere, an area light; 4 samples,
a fixed seed), renders it with the add-on on and checks the image 'zdenoise' against the
noisy render and a 256-sample one; then the output path, the auxiliary render (the same
result as the README's two commands on the same scene and render), the errors.
Leaves SCRATCH/scene.blend (the add-on on, an output path with '#') for the shell's
`-f` and `-a` runs.
"""
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_addon_common import check, empty_cycles_scene, fail  # noqa: E402

scratch = sys.argv[sys.argv.index("--") + 1]
tmp = os.environ["TMPDIR"]
W = H = 64


def build_scene():
    scene = empty_cycles_scene(W, H, samples=4, seed=7)

    checker = bpy.data.materials.new("checker")
    checker.use_nodes = True
    nodes = checker.node_tree.nodes
    bsdf = nodes["Principled BSDF"]
    tex = nodes.new("ShaderNodeTexChecker")
    tex.inputs["Scale"].default_value = 2.5
    tex.inputs["Color1"].default_value = (0.8, 0.75, 0.6, 1.0)
    tex.inputs["Color2"].default_value = (0.2, 0.3, 0.5, 1.0)
    checker.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.8
    red = bpy.data.materials.new("red")
    red.use_nodes = True
    red.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.7, 0.15, 0.1, 1)

    bpy.ops.mesh.primitive_plane_add(size=6.0)
    bpy.context.object.data.materials.append(checker)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.8, location=(0.3, 0.4, 0.8))
    bpy.ops.object.shade_smooth()
    bpy.context.object.data.materials.append(red)
    bpy.ops.object.light_add(type="AREA", location=(1.5, -1.5, 3.0))
    light = bpy.context.object
    light.data.energy = 400.0
    light.data.size = 1.5
    bpy.ops.object.camera_add(location=(0.0, -4.5, 3.2))
    cam = bpy.context.object
    cam.rotation_euler = (Vector((0, 0.3, 0.3)) - cam.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam
    world = bpy.data.worlds.new("grey")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.05, 0.06, 1)
    scene.world = world
    return scene


def render_plain(scene, name, samples):
    """The Combined RGB of a render with the add-on off, saved by the test itself."""
    scene.zdenoise.enabled = False
    scene.cycles.samples = samples
    bpy.ops.render.render()
    im = scene.render.image_settings
    im.file_format, im.color_depth, im.color_mode = "OPEN_EXR", "32", "RGBA"
    path = os.path.join(scratch, "test", name)
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    img = bpy.data.images.load(path)
    px = pixels(img)
    bpy.data.images.remove(img)
    scene.cycles.samples = 4
    return px


def pixels(img):
    a = np.empty(len(img.pixels), np.float32)
    img.pixels.foreach_get(a)
    return a.reshape(img.size[1], img.size[0], 4)


def files_outside_tmp():
    found = set()
    for root, dirs, files in os.walk(scratch):
        if os.path.abspath(root).startswith(os.path.abspath(tmp)):
            continue
        found.update(os.path.join(root, f) for f in files)
    return found


def leftovers_in_tmp():
    return [n for n in os.listdir(tmp) if n.startswith("zdenoise-")]


def render_with_addon(scene):
    before = files_outside_tmp()
    bpy.ops.render.render()  # fires render_pre and render_post in background mode too
    return files_outside_tmp() - before


def format_settings(scene):
    """The output format's settings, and those of the structs it holds."""
    def scalars(struct, prefix):
        out = {}
        for p in struct.bl_rna.properties:
            if p.is_readonly and p.type != "POINTER" or p.identifier == "rna_type":
                continue
            value = getattr(struct, p.identifier)
            if p.type == "POINTER":
                if not prefix and value is not None:
                    out.update(scalars(value, p.identifier + "."))
            elif p.type in {"ENUM", "BOOLEAN", "INT", "FLOAT", "STRING"}:
                out[prefix + p.identifier] = tuple(value) if getattr(p, "is_array", False) \
                    else value
        return out
    return scalars(scene.render.image_settings, "")


os.makedirs(os.path.join(scratch, "test"), exist_ok=True)
scene = build_scene()
noisy = render_plain(scene, "noisy.exr", 4)
reference = render_plain(scene, "reference.exr", 256)

# The user's output format, which the add-on switches to multilayer EXR and back.
im = scene.render.image_settings
im.file_format, im.color_mode, im.color_depth, im.compression = "PNG", "RGB", "16", 90
im.color_management = "OVERRIDE"
im.view_settings.exposure = 0.5
formats = format_settings(scene)
for vl in scene.view_layers:
    vl.cycles.denoising_store_passes = False  # render_pre turns them on and says so

s = scene.zdenoise
s.enabled = True
for vl in scene.view_layers:
    vl.cycles.denoising_store_passes = False  # the checkbox turned them on: off again
s.status = ""
new = render_with_addon(scene)
print("status:", s.status)
check(not s.status_error and "denoised" in s.status, f"status says denoised: '{s.status}'")
check("Denoising Data" in s.status, "status says the Denoising Data passes were turned on")
check(all(vl.cycles.denoising_store_passes for vl in scene.view_layers if vl.use),
      "render_pre turned the Denoising Data passes on")
check(format_settings(scene) == formats, "the scene's output format settings are restored")
check(not new, f"no output path: no file written outside the temp dir ({sorted(new)})")
check(not leftovers_in_tmp(), f"temporary files deleted ({leftovers_in_tmp()})")

img = bpy.data.images.get("zdenoise")
check(img is not None, "image 'zdenoise' exists")
check(tuple(img.size) == (W, H), f"its size {tuple(img.size)} is the render's")
check(img.packed_file is not None and img.is_float, "its pixels are packed, float")
den = pixels(img)
check(np.isfinite(den).all() and (den[..., :3] >= 0).all(), "pixels finite and non-negative")
# Whole image: the error against 256 spp is dominated by what no filter of a 4-spp render
# removes (the checker's and the sphere's anti-aliasing, the soft contact shadow), so it
# must drop by 2x; on a flat lit region (the bottom-left corner: one square of the plane,
# 12x16 pixels, rows counted from the bottom as Blender stores them) by 3x.
PATCH = (slice(0, 16), slice(0, 12))


def errors(img):
    e = ((img[..., :3] - reference[..., :3]) ** 2).mean(axis=-1)
    return float(e.mean()), float(e[PATCH].mean())


mse_noisy, flat_noisy = errors(noisy)
mse_den, flat_den = errors(den)
mean_noisy, mean_den = float(noisy[..., :3].mean()), float(den[..., :3].mean())
print(f"MSE against 256 spp: noisy {mse_noisy:.3e}, denoised {mse_den:.3e} "
      f"({mse_noisy / mse_den:.1f}x lower); on the flat region: noisy {flat_noisy:.3e}, "
      f"denoised {flat_den:.3e} ({flat_noisy / flat_den:.1f}x lower); mean noisy "
      f"{mean_noisy:.4f}, denoised {mean_den:.4f} ({100 * (mean_den / mean_noisy - 1):+.2f} %)")
check(mse_den * 2 <= mse_noisy, "the denoised image is at least 2x closer to 256 spp")
check(flat_den * 3 <= flat_noisy, "on a flat lit region at least 3x closer")
check(abs(mean_den / mean_noisy - 1) < 0.05, "its mean is within 5 % of the noisy render's")

# An output path: that file and no other.
s.output_path = os.path.join(scratch, "out", "still_###")
new = render_with_addon(scene)
want = os.path.join(scratch, "out", "still_001.exr")
check(new == {want}, f"an output path: exactly {want} is written ({sorted(new)})")
check(not s.status_error and want in s.status, f"status names it: '{s.status}'")
check(not leftovers_in_tmp(), "temporary files deleted")

# The auxiliary albedo render (a second Blender on a copy of the file) and layers mode.
s.output_path = ""
s.use_aux = True
s.aux_samples = 8
s.mode = "layers"
new = render_with_addon(scene)
print("status:", s.status)
check(not s.status_error and "auxiliary" in s.status, f"with --aux: '{s.status}'")
check(not new, f"with --aux: nothing written outside the temp dir ({sorted(new)})")
check(not leftovers_in_tmp(), "temporary files deleted")
aux = pixels(bpy.data.images["zdenoise"])
mse_aux, flat_aux = errors(aux)
print(f"with --aux (8 samples) and --mode layers: MSE {mse_aux:.3e} "
      f"({mse_noisy / mse_aux:.1f}x lower), on the flat region {flat_aux:.3e} "
      f"({flat_noisy / flat_aux:.1f}x lower), mean {aux[..., :3].mean():.4f}")
check(mse_aux * 2 <= mse_noisy, "with --aux the image is at least 2x closer to 256 spp")
check(flat_aux * 3 <= flat_noisy, "with --aux on the flat region at least 3x closer")
check(abs(aux[..., :3].mean() / mean_noisy - 1) < 0.05, "with --aux the mean is within 5 %")
s.use_aux = False
s.mode = "beauty"

# The aux box gives what the README's two commands give on the same scene and render:
# `blender -b shot.blend -P zdenoise_aux.py -- -o aux.exr` and `zdenoise --in render.exr
# --aux aux.exr` (here with the box's samples and mode). The Render Result still holds the
# render the add-on denoised; the add-on's own writer saves it as the command's input.
import subprocess  # noqa: E402
import zdenoise_addon  # noqa: E402
cmd_dir = os.path.join(scratch, "command")
os.makedirs(cmd_dir)
zdenoise_addon.save_render_result(scene, os.path.join(cmd_dir, "render.exr"))
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(cmd_dir, "shot.blend"), copy=True)
aux_script = zdenoise_addon.find_aux_script(None)[0]
subprocess.run([bpy.app.binary_path, "-b", "--factory-startup", "-noaudio",
                os.path.join(cmd_dir, "shot.blend"), "--python-exit-code", "1", "-P",
                aux_script, "--", "-o", os.path.join(cmd_dir, "aux.exr"),
                "--samples", "8"], check=True, stdout=subprocess.DEVNULL)
subprocess.run([os.environ["ZDENOISE_EXECUTABLE"], "--in", os.path.join(cmd_dir, "render.exr"),
                "--mode", "layers", "--aux", os.path.join(cmd_dir, "aux.exr"), "-o",
                os.path.join(cmd_dir, "denoised.exr")], check=True, stdout=subprocess.DEVNULL)
planes = zdenoise_addon.read_exr_channels(
    os.path.join(cmd_dir, "denoised.exr"), [f"ViewLayer.Combined.{c}" for c in "RGB"])
command = np.stack([planes[f"ViewLayer.Combined.{c}"] for c in "RGB"], axis=-1)[::-1]
gap = float(np.abs(command - aux[..., :3]).max() / max(float(command.max()), 1e-6))
print(f"the aux box against the two commands: largest difference {gap:.2e} of the peak")
check(gap < 1e-4, "the aux box gives the commands' result")

# The compositor on (its 'Composite' layer comes first in the EXR) and a second view layer
# ('Another', which EXR's sorted layers also put first): zdenoise denoises 'Another', the
# first with a Denoising Albedo, and the status says so.
scene.use_nodes = True
extra = scene.view_layers.new("Another")
render_with_addon(scene)
check(not s.status_error and "view layer 'Another'" in s.status,
      f"compositor and two view layers: '{s.status}'")
check(bpy.data.images["zdenoise"].get("zdenoise_layer") == "Another", "the image says its layer")
scene.view_layers.remove(extra)
scene.use_nodes = False

# Errors go to the status line; the render goes on.
executable = os.environ["ZDENOISE_EXECUTABLE"]
os.environ["ZDENOISE_EXECUTABLE"] = "/bin/false"
render_with_addon(scene)
check(s.status_error and "zdenoise failed (exit 1)" in s.status, f"exit code: '{s.status}'")
os.environ["ZDENOISE_EXECUTABLE"] = os.path.join(scratch, "no-such-zdenoise")
render_with_addon(scene)
check(s.status_error and "not an executable" in s.status, f"missing: '{s.status}'")
os.environ["ZDENOISE_EXECUTABLE"] = executable
check(not leftovers_in_tmp(), "temporary files deleted after errors")

# For the shell: frames 1-2 with '#' in the output path, rendered with -f and -a.
s.output_path = os.path.join(scratch, "frames", "f_####.exr")
scene.frame_start, scene.frame_end = 1, 2
im.file_format = "PNG"
scene.render.filepath = os.path.join(scratch, "frames", "render_")
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(scratch, "scene.blend"))
print("blender_addon_test.py: all checks passed")
