"""What the add-on's Blender-side tests share (blender_addon_test.py,
blender_addon_groups_test.py): their checks and the empty Cycles scene they build on."""
import sys

import bpy


def fail(message):
    print(f"FAIL: {message}", flush=True)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)
    print(f"ok: {message}", flush=True)


def empty_cycles_scene(width, height, samples, seed):
    """The current scene with its objects removed, rendering width x height with Cycles
    on the CPU: `samples` samples a pixel at a fixed `seed`, no adaptive sampling, no
    denoising, 4 bounces."""
    # (Not read_factory_settings: it would turn the add-on off again.)
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = samples
    cy.seed = seed
    cy.use_adaptive_sampling = False
    cy.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    cy.max_bounces = 4
    return scene
