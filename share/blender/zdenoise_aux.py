"""zdenoise_aux.py - render the auxiliary image of a Blender scene for zdenoise --aux.

    blender -b SCENE.blend -P zdenoise_aux.py -- -o AUX.exr [--samples N]

Renders, with Cycles, the scene's camera at its resolution and current frame (--frame to
choose another), with no light transport: no diffuse bounces, the lights that nothing sees
hidden, the world and the lights a camera or mirror sees kept but lighting nothing. What is
left is what Cycles' Denoising passes record: the albedo of the first non-specular surface
each pixel sees (through sharp mirrors and glass, as Cycles' Denoising Albedo defines it:
glossy, transmission and transparent bounces are kept for that), or the world's colour or
an emitter's emission where a pixel sees those (docs/AUX.md lists each case), its normal and
depth,
the lobe colours (DiffCol, GlossCol, TransCol) and the Cryptomatte object ids. The samples
only anti-alias edges and textures, so few suffice (docs/AUX.md has the measurements behind
the default). Cycles' adaptive sampling measures the noise of Combined only, which holds
no lighting here, so it is off: every pixel gets N samples.

The output is a Cycles multilayer EXR (float, ZIP) with the view layer's passes:
<layer>.Denoising Albedo.R/G/B, Denoising Normal.X/Y/Z, Denoising Depth.Z,
DiffCol/GlossCol/TransCol.R/G/B, CryptoObject00.. and Combined (what the camera sees
directly: no lighting). zdenoise finds them
by name with no flags. The .blend is not changed (nothing is saved).

Options (after Blender's `--`):
  -o, --output FILE   the EXR to write (required)
  --samples N         samples per pixel (default 24: docs/AUX.md)
  --frame F           the frame to render (default: the scene's current frame)
  --percent P         resolution percentage (default: the scene's)
  --threads T         render threads (default: the scene's setting)
  --view-layer NAME   the view layer to render (default: the first one used for rendering)
"""
import argparse
import sys
import time

import bpy

DEFAULT_SAMPLES = 24
# Added to the scene's Cycles seed (any value far from the seeds renders use).
AUX_SEED_OFFSET = 104729


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender -b SCENE.blend -P zdenoise_aux.py --")
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--samples", type=int, default=DEFAULT_SAMPLES)
    p.add_argument("--frame", type=int, default=None)
    p.add_argument("--percent", type=int, default=None)
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--view-layer", default=None)
    a = p.parse_args(argv)
    if a.samples < 1:
        p.error("--samples must be at least 1")
    return a


def fail(message):
    print(f"zdenoise_aux.py: {message}", file=sys.stderr)
    sys.exit(1)


def no_light(scene):
    """Take the light transport away but keep what Cycles' Denoising Albedo records.

    Cycles adds to the Denoising Albedo the emission a camera ray (or a sharp mirror or
    glass after it) reaches: the world's colour where the sky is seen, an emitter's
    emission, a light seen directly (integrate_background / integrate_surface_emission /
    integrate_light in Cycles 3.4's kernel; docs/AUX.md). So the world stays, with no
    importance sampling (then nothing samples it as a light, and its value reaches the
    albedo whole), and so do the lights a camera or a mirror can see, with no diffuse
    visibility; a light that nothing sees directly only lights, and is hidden."""
    for ob in scene.objects:
        if ob.type != "LIGHT":
            continue
        seen = ob.visible_camera or ob.visible_glossy or ob.visible_transmission
        if ob.hide_render or not seen:
            ob.hide_render = True
            continue
        ob.visible_diffuse = False
        ob.visible_volume_scatter = False
    world = scene.world
    if world is not None:
        world.cycles.sampling_method = "NONE"
        world.cycles_visibility.diffuse = False
        world.cycles_visibility.scatter = False


def configure(scene, args):
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.samples = args.samples
    cy.use_adaptive_sampling = False  # measures Combined, which has no lighting here
    cy.use_denoising = False
    cy.use_guiding = False
    cy.use_fast_gi = False
    # The Denoising Albedo follows sharp glossy, transmission and transparent bounces to the
    # first non-specular surface, as far as the beauty's bounce limits let it: those stay as
    # the scene has them. Diffuse and volume bounces only carry light (the albedo is written
    # before them), of which there is none.
    cy.diffuse_bounces = 0
    cy.volume_bounces = 0
    # Samples of their own: with the beauty's seed, Cycles would place the aux's N samples
    # where the beauty placed its first N, and the two albedos' noise would be one noise;
    # zdenoise pools them as independent estimates (docs/AUX.md).
    cy.use_animated_seed = False
    cy.seed = (cy.seed + AUX_SEED_OFFSET) % (2 ** 31)
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.time_limit = 0.0
    if args.frame is not None:
        scene.frame_set(args.frame)
    if args.percent is not None:
        scene.render.resolution_percentage = args.percent
    if args.threads is not None:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = args.threads
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    im = scene.render.image_settings
    im.file_format = "OPEN_EXR_MULTILAYER"
    im.color_depth = "32"
    im.exr_codec = "ZIP"
    im.color_mode = "RGBA"
    scene.render.filepath = args.output
    scene.render.use_file_extension = False

    layers = [vl for vl in scene.view_layers if vl.use]
    if args.view_layer is not None:
        layers = [vl for vl in scene.view_layers if vl.name == args.view_layer]
        if not layers:
            fail(f"no view layer '{args.view_layer}' (the scene has "
                 f"{', '.join(vl.name for vl in scene.view_layers)})")
    if not layers:
        fail("the scene has no view layer used for rendering")
    keep = layers[0]
    for vl in scene.view_layers:
        vl.use = vl == keep
    # With a transparent film the world reaches the albedo only when the Environment pass
    # is written (Cycles 3.4): keep it as the beauty has it.
    keep_passes = ("use_pass_combined", "use_pass_environment")
    for name in dir(keep):
        if name.startswith("use_pass_") and name not in keep_passes:
            try:
                setattr(keep, name, False)
            except (AttributeError, TypeError):
                pass
    for name in ("diffuse_color", "glossy_color", "transmission_color",
                 "cryptomatte_object"):
        setattr(keep, "use_pass_" + name, True)
    keep.pass_cryptomatte_depth = max(keep.pass_cryptomatte_depth, 2)
    keep.cycles.denoising_store_passes = True
    return keep


def main():
    args = parse_args()
    scene = bpy.context.scene
    if scene.camera is None:
        fail("the scene has no camera")
    no_light(scene)
    layer = configure(scene, args)
    start = time.time()
    bpy.ops.render.render(write_still=True, scene=scene.name, layer=layer.name)
    r = scene.render
    print(f"zdenoise_aux.py: wrote '{args.output}' ({r.resolution_x * r.resolution_percentage // 100}"
          f"x{r.resolution_y * r.resolution_percentage // 100}, frame {scene.frame_current}, "
          f"{args.samples} samples) in {time.time() - start:.2f} s")


main()
