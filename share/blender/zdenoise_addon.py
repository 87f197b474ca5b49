"""zdenoise for Blender: denoise each Cycles render with the zdenoise command.

Install: Edit > Preferences > Add-ons > Install... and pick this file, or put it in a
scripts/addons folder and start `blender --addons zdenoise_addon`. The panel is in the
render properties; docs/BLENDER.md has the details.

After each render (each frame of an animation, in the UI and with `blender -b ... -f N` or
`-a`) it saves the Render Result as a multilayer float EXR in a temporary folder, runs

    zdenoise --in render.exr -o denoised.exr --mode path|beauty|layers [--aux aux.exr]

on it, and loads the denoised beauty of the view layer into the image "zdenoise" (its pixels
in memory and packed, so nothing refers to the temporary folder), which every open Image
Editor then shows, and each denoised light group into the image "zdenoise <group>". When
the scene uses the compositor, an Image node for each of these images is kept in a frame
"zdenoise" of its node tree. The temporary folder is deleted. Nothing else is written: only
the output path of the panel, when one is given.

How the work is split between threads: render handlers run in the render thread when the
render was started from the UI (F12, Render Animation), and in the main thread in background
mode or under bpy.ops.render.render() without INVOKE. The Render Result must be saved in the
handler itself (the next frame replaces it), so that is done there whichever the thread. The
rest touches Blender data (writing a copy of the scene for the auxiliary render, making the
image, the status line) and is done in the main thread: at once when the handler runs in it,
else by a timer that takes the frames from a queue, while the external programs run in a
worker thread so that the UI stays responsive.
"""

bl_info = {
    "name": "zdenoise",
    "author": "zdenoise",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > zdenoise",
    "description": "Denoise Cycles renders with the zdenoise command after each render",
    "category": "Render",
}

import os
import queue
import re
import shutil
import struct
import subprocess
import tempfile
import threading
import time
import zlib

import bpy
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, EnumProperty, IntProperty, PointerProperty, StringProperty

try:
    import numpy as np
except ImportError:  # Blender always bundles numpy; the error is reported when used
    np = None

ADDON_ID = __name__
IMAGE_NAME = "zdenoise"
# Custom property on what the add-on made: images ("zdenoise": True) and compositor nodes
# ("zdenoise": the image name, or FRAME_MARK on the frame holding them).
MARK = "zdenoise"
FRAME_MARK = "frame"
ENV_EXECUTABLE = "ZDENOISE_EXECUTABLE"
# Set in the environment of the Blender that renders the auxiliary image: there, an enabled
# copy of this add-on must not denoise that render (nor start another auxiliary render).
ENV_CHILD = "ZDENOISE_ADDON_CHILD"
AUX_SCRIPT = "zdenoise_aux.py"


def log(message):
    print(f"zdenoise: {message}", flush=True)


# ---------------------------------------------------------------------------------------
# Preferences and settings


def _which_zdenoise():
    return shutil.which("zdenoise") or ""


class ZDENOISE_AddonPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_ID

    executable: StringProperty(
        name="zdenoise executable",
        description="The zdenoise command (default: the one found on PATH). "
                    f"The environment variable {ENV_EXECUTABLE}, when set, overrides it",
        subtype="FILE_PATH",
        default=_which_zdenoise(),
    )
    aux_script: StringProperty(
        name="zdenoise_aux.py",
        description="The auxiliary render script (default: the one next to this add-on's "
                    "file, share/blender/zdenoise_aux.py of zdenoise)",
        subtype="FILE_PATH",
        default="",
    )

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "executable")
        exe, why = find_executable(self)
        if exe:
            layout.label(text=f"Runs: {exe}", icon="CHECKMARK")
        else:
            layout.label(text=why, icon="ERROR")
        layout.prop(self, "aux_script")
        script, why = find_aux_script(self)
        layout.label(text=f"Auxiliary script: {script}" if script else why,
                     icon="CHECKMARK" if script else "INFO")


def preferences():
    addon = bpy.context.preferences.addons.get(ADDON_ID)
    return addon.preferences if addon else None


def find_executable(prefs):
    """The zdenoise command to run, or None and why not."""
    env = os.environ.get(ENV_EXECUTABLE, "")
    if env:
        if os.path.isfile(env) and os.access(env, os.X_OK):
            return env, ""
        return None, f"{ENV_EXECUTABLE}='{env}' is not an executable file"
    path = bpy.path.abspath(prefs.executable) if prefs and prefs.executable else ""
    if path:
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path, ""
        found = shutil.which(path)
        if found:
            return found, ""
        return None, f"zdenoise executable '{path}' not found: set it in the add-on's preferences"
    found = _which_zdenoise()
    if found:
        return found, ""
    return None, ("zdenoise is not on PATH: set its path in Preferences > Add-ons > zdenoise")


def find_aux_script(prefs):
    """zdenoise_aux.py: the preference, else next to this file (symlinks followed)."""
    if prefs and prefs.aux_script:
        path = bpy.path.abspath(prefs.aux_script)
        if os.path.isfile(path):
            return path, ""
        return None, f"the auxiliary script '{path}' does not exist"
    for base in (os.path.dirname(os.path.abspath(__file__)),
                 os.path.dirname(os.path.realpath(__file__))):
        path = os.path.join(base, AUX_SCRIPT)
        if os.path.isfile(path):
            return path, ""
    return None, (f"{AUX_SCRIPT} is not next to the add-on: set its path in the "
                  "add-on's preferences")


def _enable_update(self, context):
    # Turning the add-on on in the UI turns on the passes it needs at once, in the main
    # thread; render_pre does the same for renders started otherwise (see there).
    if self.enabled and context.scene is not None:
        notes = ensure_passes(context.scene)
        if notes:
            self.status = "Turned on " + "; ".join(notes)
            self.status_error = False


class ZDENOISE_SceneSettings(bpy.types.PropertyGroup):
    enabled: BoolProperty(
        name="Denoise with zdenoise after each render",
        description="After each render (each frame of an animation) denoise the result "
                    "with zdenoise and show it in the image 'zdenoise'",
        default=False,
        update=_enable_update,
    )
    use_aux: BoolProperty(
        name="Use auxiliary albedo render",
        description="Also render a clean albedo with zdenoise_aux.py (a second, fast Blender "
                    "render of a copy of this file with no light) and give it to zdenoise "
                    "as --aux",
        default=False,
    )
    aux_samples: IntProperty(
        name="Auxiliary samples",
        description="Samples per pixel of the auxiliary render (zdenoise_aux.py's default "
                    "is 24: docs/AUX.md)",
        default=24, min=1, soft_max=256,
    )
    mode: EnumProperty(
        name="Mode",
        description="zdenoise --mode",
        items=(
            ("path", "Light by path", "Filter the diffuse direct light apart from the rest, "
                                      "keeping hard and thin shadows (zdenoise's default; "
                                      "turns on the Diffuse Direct and Color passes)"),
            ("beauty", "Beauty", "Denoise the beauty (Combined) as one, with the albedo"),
            ("layers", "Layers", "Denoise each lobe (diffuse, glossy, transmission) with its "
                                 "own colour and add the rest (turns on the lobe passes)"),
        ),
        default="path",
        update=_enable_update,
    )
    compositor_nodes: BoolProperty(
        name="Compositor nodes",
        description="When the scene uses the compositor, keep an Image node for the image "
                    "'zdenoise' and for each light group's image in a frame 'zdenoise' of "
                    "its node tree (the compositor is never turned on by the add-on)",
        default=True,
    )
    output_path: StringProperty(
        name="Output",
        description="Also write the denoised multilayer EXR here ('#' is the frame number, "
                    "'//' the .blend's folder; '.exr' is added when missing). Empty: write "
                    "nothing, only show the result in Blender",
        subtype="FILE_PATH",
        default="",
    )
    status: StringProperty(name="Status", default="")
    status_error: BoolProperty(name="Status is an error", default=False)


# ---------------------------------------------------------------------------------------
# Passes


LOBE_PASSES = tuple(f"use_pass_{lobe}_{part}" for lobe in ("diffuse", "glossy", "transmission")
                    for part in ("direct", "indirect", "color"))
# What --mode path needs: the diffuse direct light apart, and its colour.
PATH_PASSES = ("use_pass_diffuse_direct", "use_pass_diffuse_color")


def ensure_passes(scene):
    """Turn on what zdenoise needs in every view layer used for rendering; say what was.

    Decision: when the Denoising Data passes (Denoising Albedo, Normal, Depth) are off they
    are turned on, in the view layer's own settings, and the status says so. Without them
    zdenoise has no albedo and cannot denoise, and the user who ticked the add-on asked for
    the denoising; the passes change nothing in the Combined pass and are saved with the
    file like any other setting (turn them off again by hand). The same for the lobe passes
    (Diffuse, Glossy, Transmission Direct/Indirect/Color) in the layers mode, and the Diffuse
    Direct and Color passes in the path mode."""
    notes = []
    for vl in scene.view_layers:
        if not vl.use:
            continue
        cycles = getattr(vl, "cycles", None)
        if cycles is not None and not cycles.denoising_store_passes:
            cycles.denoising_store_passes = True
            notes.append(f"the Denoising Data passes of view layer '{vl.name}'")
        needed = {"layers": LOBE_PASSES, "path": PATH_PASSES}.get(scene.zdenoise.mode, ())
        off = [p for p in needed if not getattr(vl, p)]
        for p in off:
            setattr(vl, p, True)
        if off:
            notes.append(f"the {'Diffuse Direct/Color' if scene.zdenoise.mode == 'path' else 'Diffuse/Glossy/Transmission'} "
                         f"passes of view layer '{vl.name}'")
    return notes


# ---------------------------------------------------------------------------------------
# Saving the Render Result


_SCALAR = {"ENUM", "BOOLEAN", "INT", "FLOAT", "STRING"}


def _scalars(struct):
    values = {}
    for prop in struct.bl_rna.properties:
        if prop.identifier == "rna_type" or prop.is_readonly or prop.type not in _SCALAR:
            continue
        value = getattr(struct, prop.identifier)
        if isinstance(value, set):
            value = set(value)
        elif getattr(prop, "is_array", False):
            value = tuple(value)
        values[prop.identifier] = value
    return values


def _format_snapshot(settings):
    """The image format's settings: its own enums, numbers and flags, and those of the
    structs it holds (colour management override, stereo), as {(struct, name): value}."""
    values = {(None, n): v for n, v in _scalars(settings).items()}
    for prop in settings.bl_rna.properties:
        if prop.type == "POINTER" and prop.identifier != "rna_type":
            if prop.identifier == "linear_colorspace_settings" and not getattr(
                    settings, "has_linear_colorspace", True):
                continue  # unset for formats with no linear space (reading it warns)
            sub = getattr(settings, prop.identifier)
            if sub is not None:
                values.update({(prop.identifier, n): v for n, v in _scalars(sub).items()})
    return values


def _format_get(settings, key):
    struct, name = key
    return getattr(getattr(settings, struct) if struct else settings, name)


def _format_restore(settings, values):
    """Set file_format first (it resets the depth and colour mode it does not allow), then
    the rest; return the settings that did not come back."""
    keys = [(None, "file_format")] + [k for k in values if k != (None, "file_format")]
    for key in keys:
        struct, name = key
        try:
            if _format_get(settings, key) != values[key]:
                setattr(getattr(settings, struct) if struct else settings, name, values[key])
        except (AttributeError, TypeError, ValueError):
            pass
    return [".".join(k for k in key if k) for key in values
            if _format_get(settings, key) != values[key]]


def save_render_result(scene, path):
    """Save the Render Result as a multilayer float EXR at `path`.

    Image.save_render writes with the scene's image format settings and can only read the
    Render Result of that scene, so the scene's settings are switched to OPEN_EXR_MULTILAYER,
    32-bit float, ZIP, for the call and set back (every setting compared afterwards; one
    that did not come back is reported). In an animation this runs after the frame's own
    file was written."""
    image = bpy.data.images.get("Render Result")
    if image is None or image.type != "RENDER_RESULT":
        for im in bpy.data.images:
            if im.type == "RENDER_RESULT":
                image = im
                break
        else:
            raise RuntimeError("there is no Render Result")
    settings = scene.render.image_settings
    saved = _format_snapshot(settings)
    try:
        settings.file_format = "OPEN_EXR_MULTILAYER"
        settings.color_depth = "32"
        settings.exr_codec = "ZIP"
        settings.color_mode = "RGBA"
        if hasattr(settings, "use_preview"):
            settings.use_preview = False
        image.save_render(path, scene=scene)
    finally:
        lost = _format_restore(settings, saved)
        if lost:
            log(f"could not restore the scene's output format settings {lost}")
    if not os.path.isfile(path):
        raise RuntimeError("Blender wrote no Render Result file")


# ---------------------------------------------------------------------------------------
# Reading the denoised EXR (Blender's Python gives no pixels of a multilayer image's
# passes, so the add-on reads the beauty channels itself: single-part scanline files,
# uncompressed or ZIP/ZIPS, which is what zdenoise writes for a Blender file saved as
# above; it keeps the input's compression).


_EXR_LINES = {0: 1, 2: 1, 3: 16}  # NONE, ZIPS, ZIP: scanlines per chunk
_EXR_COMPRESSION = ["NONE", "RLE", "ZIPS", "ZIP", "PIZ", "PXR24", "B44", "B44A", "DWAA", "DWAB"]
_EXR_TYPES = {0: ("<u4", 4), 1: ("<f2", 2), 2: ("<f4", 4)}  # UINT, HALF, FLOAT


def _read_cstring(f):
    out = bytearray()
    while True:
        b = f.read(1)
        if not b:
            raise ValueError("truncated EXR header")
        if b == b"\0":
            return out.decode("utf-8", "replace")
        out += b


def read_exr_header(f):
    """Channels [(name, pixel type)], compression, data window; `f` is left at the end of
    the header (the chunk offset table)."""
    head = f.read(8)
    if len(head) < 8 or head[:4] != b"\x76\x2f\x31\x01":
        raise ValueError("not an OpenEXR file")
    flags = struct.unpack("<I", head[4:])[0]
    if flags & 0x200:
        raise ValueError("a tiled EXR (the add-on reads scanline files)")
    if flags & 0x1800:
        raise ValueError("a multi-part or deep EXR (the add-on reads single-part files)")
    header = {"channels": [], "compression": 0, "data_window": None}
    while True:
        # Attributes: name\0 type\0 size value; an empty name ends the header.
        name = _read_cstring(f)
        if not name:
            break
        kind = _read_cstring(f)
        size = struct.unpack("<i", f.read(4))[0]
        value = f.read(size)
        if len(value) != size:
            raise ValueError("truncated EXR header")
        if name == "channels" and kind == "chlist":
            p = 0
            while p < len(value) and value[p] != 0:
                end = value.index(b"\0", p)
                cname = value[p:end].decode("utf-8", "replace")
                ptype, _linear, xs, ys = struct.unpack("<iB3xii", value[end + 1:end + 17])
                p = end + 17
                if (xs, ys) != (1, 1):
                    raise ValueError(f"channel '{cname}' is subsampled")
                header["channels"].append((cname, ptype))
        elif name == "compression":
            header["compression"] = value[0]
        elif name == "dataWindow":
            header["data_window"] = struct.unpack("<iiii", value)
    if header["data_window"] is None:
        raise ValueError("the EXR has no dataWindow")
    return header


def read_exr_header_file(path):
    with open(path, "rb") as f:
        return read_exr_header(f)


def read_exr_channels(path, wanted):
    """{name: float32 array (height, width), top row first} for the channels in `wanted`."""
    with open(path, "rb") as f:
        header = read_exr_header(f)
        comp = header["compression"]
        if comp not in _EXR_LINES:
            name = _EXR_COMPRESSION[comp] if comp < len(_EXR_COMPRESSION) else str(comp)
            raise ValueError(f"EXR compression {name} (the add-on reads NONE, ZIP and ZIPS)")
        x0, y0, x1, y1 = header["data_window"]
        width, height = x1 - x0 + 1, y1 - y0 + 1
        channels = header["channels"]
        for name, ptype in channels:
            if ptype not in _EXR_TYPES:
                raise ValueError(f"channel '{name}' has pixel type {ptype}")
        out = {n: np.empty((height, width), np.float32) for n, _ in channels if n in wanted}
        missing = [n for n in wanted if n not in out]
        if missing:
            raise ValueError(f"no channel {', '.join(missing)}")
        lines = _EXR_LINES[comp]
        chunks = (height + lines - 1) // lines
        offsets = struct.unpack(f"<{chunks}Q", f.read(8 * chunks))
        row_bytes = sum(width * _EXR_TYPES[t][1] for _, t in channels)
        for offset in offsets:
            f.seek(offset)
            y, size = struct.unpack("<ii", f.read(8))
            n_lines = min(lines, y1 - y + 1)
            data = f.read(size)
            expected = n_lines * row_bytes
            if size < expected:  # compressed (else stored as it is)
                raw = np.frombuffer(zlib.decompress(data), np.uint8)
                if raw.size != expected:
                    raise ValueError("corrupt EXR chunk")
                # Undo the predictor (each byte stored as the difference to the previous,
                # plus 128) and the split of even and odd bytes into two halves.
                t = np.cumsum(raw.astype(np.int64) - 128) + 128
                t = (t & 0xFF).astype(np.uint8)
                half = (expected + 1) // 2
                data = np.empty(expected, np.uint8)
                data[0::2] = t[:half]
                data[1::2] = t[half:]
                data = data.tobytes()
            pos = 0
            for line in range(n_lines):
                row = y - y0 + line
                for name, ptype in channels:
                    dtype, nbytes = _EXR_TYPES[ptype]
                    n = width * nbytes
                    if name in out:
                        out[name][row] = np.frombuffer(data, dtype, width, pos)
                    pos += n
        return out


def cycles_layer(channel_names):
    """The layer prefix zdenoise denoises ('ViewLayer.'): the first with a Combined and a
    Denoising Albedo pass, else the first with a Combined pass (zdenoise's rule)."""
    first = None
    for n in channel_names:
        if n == "Combined.R":
            p = ""
        elif n.endswith(".Combined.R"):
            p = n[:-len("Combined.R")]
        else:
            continue
        if p + "Denoising Albedo.R" in channel_names:
            return p
        if first is None:
            first = p
    return first


def light_group_names(channel_names, layer):
    """The light groups of the layer, as zdenoise finds them: '<layer>Combined_<group>' with
    R, G and B; sorted."""
    prefix = layer + "Combined_"
    names = set(channel_names)
    return sorted(n[len(prefix):-2] for n in names
                  if n.startswith(prefix) and n.endswith(".R") and len(n) > len(prefix) + 2
                  and all(n[:-1] + c in names for c in "GB"))


# ---------------------------------------------------------------------------------------
# One frame's job


class Job:
    """One frame: what the handler captured, what the programs made."""

    def __init__(self, scene):
        s = scene.zdenoise
        prefs = preferences()
        self.scene_name = scene.name
        self.frame = scene.frame_current
        self.mode = s.mode
        self.use_aux = s.use_aux
        self.aux_samples = s.aux_samples
        self.output = output_path(s.output_path, self.frame) if s.output_path else ""
        self.executable, self.error = find_executable(prefs)
        if s.output_path.startswith("//") and not bpy.data.filepath and not self.error:
            self.error = ("the output path is relative to the .blend ('//'), which is not "
                          "saved yet: save it, or give an absolute path")
        self.aux_script = None
        if self.use_aux and not self.error:
            self.aux_script, self.error = find_aux_script(prefs)
        self.notes = list(_notes.pop(scene.name, []))
        self.view_layers = sum(1 for vl in scene.view_layers if vl.use)
        self.blender = bpy.app.binary_path
        self.tempdir = None
        self.render = self.aux = self.blend = self.denoised = None
        self.layer = None
        self.pixels = None
        self.groups = {}          # light group -> its denoised pixels, as self.pixels
        self.compositor_nodes = s.compositor_nodes
        self.size = (0, 0)
        self.seconds = 0.0

    def cleanup(self):
        if self.tempdir:
            shutil.rmtree(self.tempdir, ignore_errors=True)
            self.tempdir = None


def output_path(path, frame):
    """The output path of the frame: '//' is the .blend's folder, the last run of '#' is the
    frame number with as many digits (as Blender does), '.exr' is added when missing."""
    path = bpy.path.abspath(path)
    runs = list(re.finditer(r"#+", path))
    if runs:
        r = runs[-1]
        number = f"{abs(frame):0{len(r.group())}d}"
        path = path[:r.start()] + ("-" if frame < 0 else "") + number + path[r.end():]
    if not path.lower().endswith(".exr"):
        path += ".exr"
    return path


def capture(scene, force=False):
    """In the render handler (any thread): check, and save the Render Result. A Job, or
    None when the add-on is off for this render (`force`: the operator, on even when off)."""
    if os.environ.get(ENV_CHILD):
        return None
    settings = getattr(scene, "zdenoise", None)
    if settings is None or not (settings.enabled or force):
        return None
    job = Job(scene)
    if job.error:
        return job
    if scene.render.engine != "CYCLES":
        job.error = f"the render engine is {scene.render.engine}, not Cycles: not denoised"
        return job
    if scene.render.use_multiview:
        job.error = "stereo and multi-view renders are not supported: not denoised"
        return job
    if np is None:
        job.error = "Blender's Python has no numpy"
        return job
    try:
        job.tempdir = tempfile.mkdtemp(prefix="zdenoise-")
        job.render = os.path.join(job.tempdir, "render.exr")
        save_render_result(scene, job.render)
        names = [n for n, _ in read_exr_header_file(job.render)["channels"]]
        job.layer = cycles_layer(names)
        if job.layer is None:
            raise RuntimeError("the render has no Combined pass")
        if job.layer + "Denoising Albedo.R" not in names:
            raise RuntimeError("the render has no Denoising Albedo pass (turn on the view "
                               "layer's Denoising Data)")
    except Exception as e:  # noqa: BLE001 - reported, never raised into the render
        job.error = f"could not save the render: {e}"
    return job


def prepare(job):
    """Main thread: the copy of the scene that the auxiliary render opens.

    bpy.data.libraries.write writes the scene and every data-block it uses (objects,
    meshes, materials, images, worlds, node groups, linked libraries) and nothing else,
    paths made absolute so that they resolve from the temporary folder. Not
    bpy.ops.wm.save_as_mainfile(copy=True): in the UI that also renders and writes a
    thumbnail of the copy into the user's thumbnail cache (Preferences > Save & Load > File
    Preview Type), packs every file into the open .blend when Automatically Pack is on, and
    runs the save handlers of every add-on; none of which the user asked for."""
    if job.error or not job.use_aux:
        return
    try:
        scene = bpy.data.scenes[job.scene_name]
        job.blend = os.path.join(job.tempdir, "scene.blend")
        bpy.data.libraries.write(job.blend, {scene}, path_remap="ABSOLUTE", fake_user=False)
        if not os.path.isfile(job.blend):
            raise RuntimeError("nothing was written")
    except Exception as e:  # noqa: BLE001
        job.error = f"could not save a copy of the scene for the auxiliary render: {e}"


def _run(command, env=None):
    log("running " + " ".join(f"'{c}'" if " " in c else c for c in command))
    return subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          stdin=subprocess.DEVNULL, env=env, text=True, errors="replace")


def _last_lines(text, n=3):
    lines = [l for l in text.strip().splitlines() if l.strip()]
    return " | ".join(lines[-n:]) if lines else "no output"


def _rgba(planes, rgb, alpha):
    """Blender's pixel order (bottom row first, RGBA) of the planes `rgb` and `alpha`."""
    h, w = planes[rgb[0]].shape
    rgba = np.empty((h, w, 4), np.float32)
    for i, n in enumerate(rgb):
        rgba[:, :, i] = planes[n]
    rgba[:, :, 3] = alpha
    return np.ascontiguousarray(rgba[::-1]).reshape(-1)


def read_denoised(job):
    """The denoised beauty and light groups of the job's layer, in Blender's pixel order."""
    header = read_exr_header_file(job.denoised)
    channels = [n for n, _ in header["channels"]]
    beauty = [job.layer + f"Combined.{c}" for c in "RGB"]
    alpha = job.layer + "Combined.A"
    groups = light_group_names(channels, job.layer)
    rgb = {g: [job.layer + f"Combined_{g}.{c}" for c in "RGB"] for g in groups}
    wanted = beauty + ([alpha] if alpha in channels else []) + sum(rgb.values(), [])
    planes = read_exr_channels(job.denoised, wanted)
    a = planes[alpha] if alpha in planes else 1.0
    job.pixels = _rgba(planes, beauty, a)
    # A group's light is a share of the beauty pixel's, rendered over the same film: it is
    # as premultiplied as the beauty, so the beauty's alpha is the group's. Groups added up
    # with Mix nodes (which keep their first input's alpha) then composite as the beauty.
    job.groups = {g: _rgba(planes, names, a) for g, names in rgb.items()}
    h, w = planes[beauty[0]].shape
    job.size = (w, h)


def run(job):
    """Any thread, no Blender data: the auxiliary render, zdenoise, reading the result."""
    if job.error:
        return
    start = time.time()
    try:
        if job.use_aux:
            job.aux = os.path.join(job.tempdir, "aux.exr")
            env = dict(os.environ)
            env[ENV_CHILD] = "1"
            command = [job.blender, "-b", job.blend, "--scene", job.scene_name, "-noaudio",
                       "--python-exit-code", "1", "-P", job.aux_script, "--",
                       "-o", job.aux, "--frame", str(job.frame),
                       "--samples", str(job.aux_samples)]
            if job.layer:
                command += ["--view-layer", job.layer[:-1]]
            p = _run(command, env)
            if p.returncode != 0 or not os.path.isfile(job.aux):
                raise RuntimeError(f"the auxiliary render failed (exit {p.returncode}): "
                                   + _last_lines(p.stdout))
        job.denoised = job.output or os.path.join(job.tempdir, "denoised.exr")
        if job.output:
            os.makedirs(os.path.dirname(job.output) or ".", exist_ok=True)
        command = [job.executable, "--in", job.render, "-o", job.denoised]
        # Always named: zdenoise's own default depends on the passes and options.
        command += ["--mode", job.mode]
        if job.aux:
            command += ["--aux", job.aux]
        p = _run(command)
        if p.returncode != 0:
            raise RuntimeError(f"zdenoise failed (exit {p.returncode}): {_last_lines(p.stdout, 1)}")
        read_denoised(job)
    except FileNotFoundError as e:
        job.error = f"could not run {e.filename}: {e.strerror}"
    except Exception as e:  # noqa: BLE001
        job.error = str(e)
    job.seconds = time.time() - start


def group_image_name(group):
    return f"{IMAGE_NAME} {group}"


def store_image(job, name=IMAGE_NAME, pixels=None, group=None):
    """Main thread: the image `name` holds the denoised pixels (the beauty's by default),
    packed."""
    w, h = job.size
    image = bpy.data.images.get(name)
    if image is not None and (not image.get(MARK) or not image.is_float):
        # Not one this add-on made: replaced by a new one.
        bpy.data.images.remove(image)
        image = None
    if image is None:
        # A float buffer: its colour space is the scene linear one, as the EXR's.
        image = bpy.data.images.new(name, w, h, alpha=True, float_buffer=True)
        image[MARK] = True
    elif tuple(image.size) != (w, h):
        image.scale(w, h)
    image.alpha_mode = "STRAIGHT"
    image.pixels.foreach_set(job.pixels if pixels is None else pixels)
    image.update()
    # Packed: its pixels are kept in the .blend and survive a reload; nothing refers to the
    # temporary folder.
    image.pack()
    image["zdenoise_frame"] = job.frame
    image["zdenoise_layer"] = job.layer[:-1] if job.layer else ""
    if group is not None:
        image["zdenoise_group"] = group
    return image


def store_group_images(job):
    """Main thread: an image for each denoised light group; the add-on's images of groups
    this render has not (denoised) are removed. The image names, sorted.

    One the user renamed (or copied) is theirs now, and kept."""
    names = []
    for group, pixels in sorted(job.groups.items()):
        names.append(store_image(job, group_image_name(group), pixels, group).name)
    for image in list(bpy.data.images):
        group = image.get("zdenoise_group")
        if (image.get(MARK) and isinstance(group, str) and group not in job.groups
                and image.name == group_image_name(group)):
            bpy.data.images.remove(image)
    return names


# ---------------------------------------------------------------------------------------
# Compositor nodes


NODE_STEP = 340      # vertical distance of the Image nodes (with their preview)
NODE_WIDTH = 140     # an Image node's default width
NODE_GAP = 120       # between the frame and the user's leftmost node


def _view_location(node):
    """A node's location in the editor: a node in a frame is placed relative to it."""
    x, y = node.location
    parent = node.parent
    while parent is not None:
        x, y = x + parent.location.x, y + parent.location.y
        parent = parent.parent
    return x, y


def _place_frame(frame, user_nodes):
    """Left of the user's nodes, its top level with the highest of them."""
    spots = [_view_location(n) for n in user_nodes] or [(0.0, 0.0)]
    frame.location = (min(x for x, _ in spots) - NODE_GAP - NODE_WIDTH - 40,
                      max(y for _, y in spots))


def _our_frame(tree):
    """The add-on's frame, made (left of the user's nodes) when there is none. (frame, new)"""
    frame = next((n for n in tree.nodes if n.get(MARK) == FRAME_MARK), None)
    if frame is not None:
        return frame, False
    user_nodes = [n for n in tree.nodes if not n.get(MARK)]
    frame = tree.nodes.new("NodeFrame")
    frame.name = frame.label = IMAGE_NAME
    frame[MARK] = FRAME_MARK
    frame.shrink = True
    _place_frame(frame, user_nodes)
    return frame, True


def update_compositor(scene, image_names):
    """Main thread, only when the scene uses nodes: one Image node for each of the add-on's
    images (found again by its mark), in the frame 'zdenoise'; the add-on's nodes of images
    gone are removed. The user's nodes are not touched."""
    tree = scene.node_tree
    frame, changed = _our_frame(tree)
    found = {}
    for node in [n for n in tree.nodes if n.get(MARK) not in (None, FRAME_MARK)]:
        name = node.get(MARK)
        if name not in image_names:
            tree.nodes.remove(node)
            changed = True
        elif name not in found:  # (a copy the user made with Shift+D is left alone)
            found[name] = node
    for name in image_names:
        node = found.get(name)
        if node is None:
            node = found[name] = tree.nodes.new("CompositorNodeImage")
            node.name = name
            node[MARK] = name
            changed = True
        if node.image is None or node.image.name != name:
            node.image = bpy.data.images[name]
    if changed:
        # Laid out again only when the column changed, so that nodes the user moved
        # stay where they are otherwise.
        for i, name in enumerate(image_names):
            node = found[name]
            if node.parent != frame:
                node.parent = frame
            node.location = (20, -40 - i * NODE_STEP)


def show_image(image):
    wm = bpy.context.window_manager
    for window in (wm.windows if wm else []):
        for area in window.screen.areas:
            if area.type == "IMAGE_EDITOR":
                area.spaces.active.image = image
                area.tag_redraw()


def set_status(scene_name, text, error=False):
    scene = bpy.data.scenes.get(scene_name)
    if scene is not None and hasattr(scene, "zdenoise"):
        scene.zdenoise.status = text
        scene.zdenoise.status_error = error
    for window in (bpy.context.window_manager.windows if bpy.context.window_manager else []):
        for area in window.screen.areas:
            if area.type == "PROPERTIES":
                area.tag_redraw()


def finish(job):
    """Main thread: the image, the status line, the temporary files gone."""
    try:
        if not job.error:
            try:
                image = store_image(job)
                names = [image.name] + store_group_images(job)
                show_image(image)
            except Exception as e:  # noqa: BLE001
                job.error = f"could not make the image: {e}"
        if not job.error:
            scene = bpy.data.scenes.get(job.scene_name)
            try:
                if (scene is not None and scene.use_nodes and scene.node_tree is not None
                        and job.compositor_nodes):
                    update_compositor(scene, names)
            except Exception as e:  # noqa: BLE001
                job.error = f"could not update the compositor's nodes: {e}"
        notes = f" (turned on {'; '.join(job.notes)})" if job.notes else ""
        if job.error:
            text = f"Frame {job.frame}: {job.error}{notes}"
            log(text)
        else:
            where = f", written to {job.output}" if job.output else ""
            aux = " with the auxiliary albedo" if job.use_aux else ""
            if job.view_layers > 1 and job.layer:
                aux = f" (view layer '{job.layer[:-1]}')" + aux
            groups = ""
            if job.groups:
                groups = f", light groups {', '.join(sorted(job.groups))}"
            text = (f"Frame {job.frame} denoised{aux} in {job.seconds:.1f} s "
                    f"({job.size[0]}x{job.size[1]}, {job.mode}{groups}){where}{notes}")
            log(text)
        set_status(job.scene_name, text, bool(job.error))
        return text
    finally:
        job.cleanup()


def process_now(job):
    prepare(job)
    run(job)
    return finish(job)


# ---------------------------------------------------------------------------------------
# Render handlers and the main-thread queue


_notes = {}               # scene name -> what render_pre turned on
_queue = queue.Queue()    # jobs captured in the render thread, for the main thread
_worker = None            # (thread, job) running `run` for the main thread


def _in_main_thread():
    return threading.current_thread() is threading.main_thread()


@persistent
def on_render_pre(scene, *_args):
    if os.environ.get(ENV_CHILD):
        return
    settings = getattr(scene, "zdenoise", None)
    if settings is None or not settings.enabled:
        return
    if scene.render.engine != "CYCLES":
        return  # render_post reports it
    try:
        notes = ensure_passes(scene)
    except Exception as e:  # noqa: BLE001
        notes = [f"nothing: the passes could not be turned on ({e})"]
    if notes:
        log("turned on " + "; ".join(notes))
        _notes.setdefault(scene.name, []).extend(notes)


@persistent
def on_render_post(scene, *_args):
    try:
        job = capture(scene)
        if job is None:
            return
        if _in_main_thread():
            process_now(job)
        else:
            log(f"frame {job.frame} saved in the render thread, queued for the main thread")
            _queue.put(job)
    except Exception as e:  # noqa: BLE001 - never break the render
        log(f"unexpected error: {e}")


def _poll():
    """Main-thread timer (UI only): runs the queued frames one after the other."""
    global _worker
    try:
        if _worker is not None:
            thread, job = _worker
            if thread.is_alive():
                return 0.1
            _worker = None
            finish(job)
        try:
            job = _queue.get_nowait()
        except queue.Empty:
            return 0.25
        set_status(job.scene_name, f"Frame {job.frame}: denoising...")
        prepare(job)
        thread = threading.Thread(target=run, args=(job,), daemon=True)
        thread.start()
        _worker = (thread, job)
        return 0.1
    except Exception as e:  # noqa: BLE001 - a timer that raises is unregistered
        log(f"unexpected error: {e}")
        return 0.5


# ---------------------------------------------------------------------------------------
# UI


class ZDENOISE_OT_denoise_render_result(bpy.types.Operator):
    """Denoise the current Render Result with zdenoise (as after a render)"""
    bl_idname = "zdenoise.denoise_render_result"
    bl_label = "Denoise Render Result"

    def execute(self, context):
        scene = context.scene
        job = capture(scene, force=True)
        text = process_now(job)
        if job.error:
            self.report({"ERROR"}, text)
            return {"CANCELLED"}
        self.report({"INFO"}, text)
        return {"FINISHED"}


class ZDENOISE_PT_render(bpy.types.Panel):
    bl_label = "zdenoise"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        s = scene.zdenoise
        layout.prop(s, "enabled")
        exe, why = find_executable(preferences())
        if not exe:
            layout.label(text=why, icon="ERROR")
        if scene.render.engine != "CYCLES":
            layout.label(text=f"The render engine is {scene.render.engine}: zdenoise needs "
                              "Cycles' passes", icon="ERROR")
        else:
            off = [vl.name for vl in scene.view_layers if vl.use and hasattr(vl, "cycles")
                   and not vl.cycles.denoising_store_passes]
            if off and s.enabled:
                layout.label(text="Denoising Data passes are off in " + ", ".join(off)
                                  + ": they are turned on at the next render", icon="INFO")
            if scene.cycles.use_denoising:
                layout.label(text="Cycles' own denoiser is on: zdenoise then filters its "
                                  "output (Sampling > Render > Denoise)", icon="INFO")
        col = layout.column()
        col.active = s.enabled
        col.prop(s, "use_aux")
        if s.use_aux:
            sub = col.row()
            sub.prop(s, "aux_samples")
            script, why = find_aux_script(preferences())
            if not script:
                col.label(text=why, icon="ERROR")
        row = col.row()
        row.prop(s, "mode", expand=True)
        sub = col.row()
        sub.active = s.enabled and scene.use_nodes
        sub.prop(s, "compositor_nodes")
        col.prop(s, "output_path")
        if not s.output_path:
            col.label(text="No output path: the result is only shown (image 'zdenoise')")
        layout.operator(ZDENOISE_OT_denoise_render_result.bl_idname, icon="IMAGE")
        if s.status:
            box = layout.box()
            box.label(text=s.status, icon="ERROR" if s.status_error else "CHECKMARK")


classes = (
    ZDENOISE_AddonPreferences,
    ZDENOISE_SceneSettings,
    ZDENOISE_OT_denoise_render_result,
    ZDENOISE_PT_render,
)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.zdenoise = PointerProperty(type=ZDENOISE_SceneSettings)
    bpy.app.handlers.render_pre.append(on_render_pre)
    bpy.app.handlers.render_post.append(on_render_post)
    if not bpy.app.background:
        bpy.app.timers.register(_poll, first_interval=0.5, persistent=True)


def unregister():
    if bpy.app.timers.is_registered(_poll):
        bpy.app.timers.unregister(_poll)
    for handlers, fn in ((bpy.app.handlers.render_pre, on_render_pre),
                         (bpy.app.handlers.render_post, on_render_post)):
        while fn in handlers:
            handlers.remove(fn)
    del bpy.types.Scene.zdenoise
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)


if __name__ == "__main__":
    register()
