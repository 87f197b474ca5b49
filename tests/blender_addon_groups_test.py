"""The Blender side of tests/blender_addon_groups.sh: light groups and the compositor.

    blender -b --factory-startup -noaudio --addons zdenoise_addon \
        -P blender_addon_groups_test.py -- SCRATCH

A tiny Cycles scene (48x48, 16 samples, fixed seed: a plane, a cube, an area light in the
light group 'key', a point light and the world in 'fill', opaque film) rendered with the
add-on on. Checks the images 'zdenoise key' and 'zdenoise fill' (float, the render's size,
less noisy than the rendered groups on a flat part of the plane, adding up to the image
'zdenoise'), then the compositor: no node tree made without use_nodes; with it, one Image
node per image in the frame 'zdenoise' after two renders, the user's nodes untouched; a
group gone takes its image and node along; a scene with use_nodes off keeps its tree.
"""
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_addon_common import check, empty_cycles_scene, fail  # noqa: E402

import zdenoise_addon

scratch = sys.argv[sys.argv.index("--") + 1]
W = H = 48
GROUPS = ("fill", "key")
# A flat part of the plane lit by both lights, away from the cube and its shadows (the
# bottom middle, 12x12; rows counted from the bottom, as Blender stores pixels).
PATCH = (slice(2, 14), slice(18, 30))


def build_scene():
    scene = empty_cycles_scene(W, H, samples=16, seed=3)
    scene.render.film_transparent = False

    grey = bpy.data.materials.new("grey")
    grey.use_nodes = True
    grey.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.6, 0.6, 0.55, 1)
    grey.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.9
    bpy.ops.mesh.primitive_plane_add(size=8.0)
    bpy.context.object.data.materials.append(grey)
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.4, 0.6, 0.5))
    bpy.context.object.data.materials.append(grey)

    vl = scene.view_layers[0]
    for g in GROUPS:
        vl.lightgroups.add(name=g)
    bpy.ops.object.light_add(type="AREA", location=(2.0, -1.5, 3.0))
    key = bpy.context.object
    key.data.energy, key.data.size = 300.0, 0.5
    key.lightgroup = "key"
    bpy.ops.object.light_add(type="POINT", location=(-2.5, -1.0, 2.0))
    fill = bpy.context.object
    fill.data.energy, fill.data.shadow_soft_size = 120.0, 0.3
    fill.lightgroup = "fill"
    bpy.ops.object.camera_add(location=(0.0, -4.5, 3.2))
    cam = bpy.context.object
    cam.rotation_euler = (Vector((0, 0.3, 0.3)) - cam.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam
    world = bpy.data.worlds.new("dim")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.05, 0.06, 1)
    world.lightgroup = "fill"  # so that the groups hold all the light
    scene.world = world
    return scene


def pixels(img):
    a = np.empty(len(img.pixels), np.float32)
    img.pixels.foreach_get(a)
    return a.reshape(img.size[1], img.size[0], 4)


def noisy_groups(scene):
    """The groups' pixels as rendered: the Render Result still holds the render the add-on
    denoised; the add-on's own writer saves it."""
    path = os.path.join(scratch, "test", "render.exr")
    zdenoise_addon.save_render_result(scene, path)
    names = {g: [f"ViewLayer.Combined_{g}.{c}" for c in "RGB"] for g in GROUPS}
    planes = zdenoise_addon.read_exr_channels(path, sum(names.values(), []))
    os.remove(path)
    return {g: np.stack([planes[n] for n in names[g]], axis=-1)[::-1] for g in GROUPS}


def residual_variance(rgb):
    """The variance over PATCH of the mean of R, G, B less its best quadratic fit (the
    lights' falloff): the noise."""
    y = rgb[PATCH][..., :3].mean(axis=-1)
    rows, cols = np.mgrid[0:y.shape[0], 0:y.shape[1]]
    r, c = rows.ravel(), cols.ravel()
    a = np.stack([np.ones(y.size), r, c, r * r, c * c, r * c], axis=-1)
    fit, *_ = np.linalg.lstsq(a, y.ravel(), rcond=None)
    return float(np.var(y.ravel() - a @ fit))


def image_nodes(tree, name):
    return [n for n in tree.nodes if n.bl_idname == "CompositorNodeImage"
            and n.image is not None and n.image.name == name]


def frames(tree):
    return [n for n in tree.nodes if n.bl_idname == "NodeFrame" and n.label == "zdenoise"]


def check_nodes(tree, names, user):
    """One Image node per image in `names` and no other of the add-on's, in its frame, left
    of the user's nodes; the user's nodes as `user`."""
    frame = frames(tree)
    check(len(frame) == 1, f"  one frame 'zdenoise' ({len(frame)})")
    for name in names:
        nodes = image_nodes(tree, name)
        check(len(nodes) == 1 and nodes[0].parent == frame[0],
              f"  one Image node of '{name}' ({len(nodes)}), in the frame")
    ours = [n for n in tree.nodes if n.get("zdenoise") and n.bl_idname != "NodeFrame"]
    check(len(ours) == len(names), f"  no other Image node of the add-on's ({len(ours)})")
    check(not any(l.from_node in ours or l.to_node in ours for l in tree.links),
          "  the add-on's nodes are not linked")
    right = max(zdenoise_addon._view_location(n)[0] + n.width for n in ours)
    left = min(zdenoise_addon._view_location(n)[0] for n in tree.nodes
               if not n.get("zdenoise") and n.bl_idname != "NodeFrame")
    check(right < left, f"  left of the user's nodes (right edge {right:.0f}, theirs {left:.0f})")
    check(user_snapshot(tree) == user, "  the user's nodes and links are untouched")


def user_snapshot(tree):
    """The user's nodes (those without the add-on's mark) and links, as comparable values."""
    nodes = sorted((n.name, n.bl_idname, tuple(n.location), n.parent.name if n.parent else "")
                   for n in tree.nodes if not n.get("zdenoise"))
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name,
                    l.to_socket.identifier) for l in tree.links)
    return nodes, links


def tree_snapshot(tree):
    nodes = sorted((n.name, n.bl_idname, tuple(n.location), n.parent.name if n.parent else "",
                    n.image.name if getattr(n, "image", None) else "") for n in tree.nodes)
    return nodes, user_snapshot(tree)[1]


os.makedirs(os.path.join(scratch, "test"), exist_ok=True)
scene = build_scene()
# An image of a group's name that the add-on did not make is replaced; one of another name
# is left alone.
bpy.data.images.new("zdenoise key", 4, 4)
bpy.data.images.new("zdenoise old", 4, 4)
s = scene.zdenoise
s.enabled = True
scene.use_nodes = False
check(scene.node_tree is None, "the factory scene has no compositor node tree")

bpy.ops.render.render()
print("status:", s.status)
check(not s.status_error and "light groups fill, key" in s.status,
      f"status names the light groups: '{s.status}'")
check(scene.node_tree is None and not scene.use_nodes,
      "use_nodes off: no node tree made, the compositor stays off")
noisy = noisy_groups(scene)
beauty = pixels(bpy.data.images["zdenoise"])
for g in GROUPS:
    img = bpy.data.images.get(f"zdenoise {g}")
    check(img is not None, f"image 'zdenoise {g}' exists")
    check(img.is_float and img.packed_file is not None, "  float, packed")
    check(tuple(img.size) == (W, H), f"  the render's size {tuple(img.size)}")
    den = pixels(img)
    check(np.isfinite(den).all() and (den[..., :3] >= 0).all(), "  finite, non-negative")
    check(np.array_equal(den[..., 3], beauty[..., 3]), "  its alpha is the beauty's")
    v_noisy, v_den = residual_variance(noisy[g]), residual_variance(den)
    print(f"{g}: on the flat patch residual variance noisy {v_noisy:.3e}, denoised "
          f"{v_den:.3e} ({v_noisy / v_den:.1f}x lower); mean noisy {noisy[g].mean():.4f}, "
          f"denoised {den[..., :3].mean():.4f}")
    check(v_den * 4 <= v_noisy, "  at least 4x less noise on the flat patch")
total = sum(pixels(bpy.data.images[f"zdenoise {g}"])[..., :3] for g in GROUPS)
opaque = beauty[..., 3] == 1
gap = np.abs(total - beauty[..., :3])[opaque]
print(f"key + fill against 'zdenoise' on {opaque.sum()} of {W * H} pixels (alpha 1): at most "
      f"{gap.max() / beauty[..., :3][opaque].mean():.2e} of its mean")
check(opaque.mean() > 0.99, "the film is opaque")
check(gap.max() <= 0.01 * beauty[..., :3][opaque].mean(), "key + fill within 1 % of the beauty")
check(bpy.data.images["zdenoise key"].get("zdenoise"), "the user's 'zdenoise key' was replaced")

# The compositor on, with the user's own nodes: a Blur in a frame between Render Layers and
# Composite.
scene.use_nodes = True
tree = scene.node_tree
rl, composite = tree.nodes["Render Layers"], tree.nodes["Composite"]
user_frame = tree.nodes.new("NodeFrame")
user_frame.name, user_frame.location = "My frame", (120, 700)
blur = tree.nodes.new("CompositorNodeBlur")
blur.name, blur.parent = "My blur", user_frame
blur.location = (30, -60)
tree.links.new(rl.outputs["Image"], blur.inputs["Image"])
tree.links.new(blur.outputs["Image"], composite.inputs["Image"])
tree.links.new(rl.outputs["Alpha"], composite.inputs["Alpha"])
user = user_snapshot(tree)
all_images = ["zdenoise", "zdenoise fill", "zdenoise key"]
for i in (1, 2):
    bpy.ops.render.render()
    check(not s.status_error, f"render {i} with use_nodes: '{s.status}'")
    check_nodes(tree, all_images, user)

# A group gone: its image and node go (a copy the user made of the image stays); a render
# with no light group keeps the beauty's.
kept = bpy.data.images["zdenoise fill"].copy()
vl = scene.view_layers[0]
vl.active_lightgroup_index = vl.lightgroups.find("fill")
bpy.ops.scene.view_layer_remove_lightgroup()
check([g.name for g in vl.lightgroups] == ["key"], "the light group 'fill' is removed")
bpy.ops.render.render()
check(not s.status_error and "light groups key)" in s.status, f"status: '{s.status}'")
check("zdenoise fill" not in bpy.data.images, "the image 'zdenoise fill' is gone")
check(kept.name in bpy.data.images, f"the user's copy '{kept.name}' stays")
check_nodes(tree, ["zdenoise", "zdenoise key"], user)
s.mode = "layers"  # the groups are split from the sum of the denoised layers
bpy.ops.render.render()
check(not s.status_error and "layers, light groups key)" in s.status,
      f"layers mode: '{s.status}'")
check("zdenoise key" in bpy.data.images, "the group's image in layers mode")
check_nodes(tree, ["zdenoise", "zdenoise key"], user)
check("zdenoise old" in bpy.data.images, "the user's image 'zdenoise old' is still there")
s.mode = "beauty"

# 'Compositor nodes' off, then use_nodes off: the tree is left as it is.
s.compositor_nodes = False
before = tree_snapshot(tree)
bpy.ops.render.render()
check(not s.status_error and "zdenoise key" in bpy.data.images, f"status: '{s.status}'")
check(tree_snapshot(tree) == before, "'Compositor nodes' off: the node tree is unchanged")
s.compositor_nodes = True
scene.use_nodes = False
bpy.ops.render.render()
check(not s.status_error, f"status: '{s.status}'")
check(tree_snapshot(tree) == before and not scene.use_nodes,
      "use_nodes off: the node tree is unchanged, the compositor stays off")
print("blender_addon_groups_test.py: all checks passed")
