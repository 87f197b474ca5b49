"""sequence_scene.py - temporal (animation) benchmark sequences for zdenoise (Blender 3.4, Cycles CPU).

A small textured room (fine checker floor, brick back wall, noise / voronoi side walls), a
banded tall box, a striped cylinder, a checkered sphere and a rectangular area light.

  --motion static   camera and scene fixed; only the sampling seed changes per frame, so
                    the ideal output is the same image in every frame.
  --motion pan      the camera translates right and up and yaws slightly to the right
                    (background moves 3.7-5.3 px/frame left and 0.9-1.6 px/frame down in the
                    image) while the sphere flies right and up (about +7.1 px/frame in x and
                    -1.2 px/frame in y on screen), so there are disocclusions behind it.

Seed of frame f = f + --seed-offset (default 0).  Motion blur is off (the Vector pass needs it
off).  One multilayer float32 (ZIP) EXR per frame, layer `ViewLayer`, 27 channels: Combined
(RGBA), Depth (Z pass), Normal, Position, Vector (XYZW), IndexOB, Denoising Albedo/Normal/Depth,
CryptoObject00 (2 levels = one RGBA layer).  Object pass_index: floor 1, ceiling 2, back_wall 3,
left_wall 4, right_wall 5, tall_box 6, cylinder 7, sphere 8.  Vector convention: README.md.

blender -b --factory-startup -noaudio --python sequence_scene.py -- \
    --motion pan --frames 8 --first 1 --spp 16 --out-pattern /tmp/seq/pan.####.exr
    [--only-frame 4] [--seed-offset 0] [--size 384] [--threads 2] [--save-blend F.blend]
"""
import argparse
import math
import os
import re
import sys
import time

import bmesh
import bpy
from mathutils import Vector

# ----------------------------------------------------------------------------- arguments
argv = sys.argv[sys.argv.index('--') + 1:] if '--' in sys.argv else []
ap = argparse.ArgumentParser(prog='blender -b --factory-startup -noaudio --python sequence_scene.py --')
ap.add_argument('--motion', choices=['static', 'pan'], required=True)
ap.add_argument('--frames', type=int, default=8)
ap.add_argument('--first', type=int, default=1)
ap.add_argument('--spp', type=int, default=16)
ap.add_argument('--size', type=int, default=384)
ap.add_argument('--out-pattern', required=True, help='output path with a run of # for the frame number')
ap.add_argument('--only-frame', type=int, default=None, help='render just this frame')
ap.add_argument('--seed-offset', type=int, default=0, help='seed of frame f = f + offset')
ap.add_argument('--threads', type=int, default=2)
ap.add_argument('--save-blend', default=None)
args = ap.parse_args(argv)
if '#' not in args.out_pattern:
    ap.error('--out-pattern needs a run of # for the frame number')


def frame_path(pattern, f):
    return re.sub(r'#+', lambda m: '%0*d' % (len(m.group(0)), f), pattern, count=1)


# ----------------------------------------------------------------------------- scene helpers
for coll in (bpy.data.objects, bpy.data.meshes, bpy.data.lights, bpy.data.cameras,
             bpy.data.materials, bpy.data.worlds):
    for item in list(coll):
        coll.remove(item)
sc = bpy.context.scene


def link(name, data, pass_index):
    ob = bpy.data.objects.new(name, data)
    sc.collection.objects.link(ob)
    ob.pass_index = pass_index
    return ob


def mesh_object(name, me, mat, pass_index, smooth, location):
    """Link mesh `me` as object `name` with its material, shading and place."""
    for poly in me.polygons:
        poly.use_smooth = smooth
    me.materials.append(mat)
    ob = link(name, me, pass_index)
    ob.location = location
    return ob


def mesh_obj(name, verts, faces, mat, pass_index, smooth=False, location=(0, 0, 0)):
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(v) for v in verts], [], [tuple(f) for f in faces])
    me.validate()
    me.update()
    return mesh_object(name, me, mat, pass_index, smooth, location)


def bm_obj(name, bm, mat, pass_index, smooth, location):
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    return mesh_object(name, me, mat, pass_index, smooth, location)


class Mat:
    """Tiny node-graph builder."""

    def __init__(self, name, idx):
        self.mat = bpy.data.materials.new(name)
        self.mat.use_nodes = True
        self.mat.pass_index = idx
        self.nt = self.mat.node_tree
        self.nt.nodes.clear()
        self._out = self.nt.nodes.new('ShaderNodeOutputMaterial')
        self._tc = None

    def set(self, sock, v):
        if isinstance(v, bpy.types.NodeSocket):
            self.nt.links.new(v, sock)
        elif isinstance(v, bpy.types.Node):
            self.nt.links.new(v.outputs[0], sock)
        else:
            if isinstance(v, (tuple, list)) and len(v) == 3 and len(sock.default_value) == 4:
                v = tuple(v) + (1.0,)
            sock.default_value = v

    def n(self, typ, inputs=None, **props):
        node = self.nt.nodes.new(typ)
        for k, v in props.items():
            setattr(node, k, v)
        for k, v in (inputs or {}).items():
            self.set(node.inputs[k], v)
        return node

    def math(self, op, a, b=0.0, c=0.0):
        node = self.n('ShaderNodeMath', operation=op)
        for i, v in enumerate((a, b, c)):
            self.set(node.inputs[i], v)
        return node.outputs[0]

    def uv2(self, axes, scale=1.0):
        """2D texture coordinates from two object-space axes (third fixed at 0.5)."""
        if self._tc is None:
            self._tc = self.n('ShaderNodeTexCoord')
        sep = self.n('ShaderNodeSeparateXYZ', {0: self._tc.outputs['Object']})
        i = {'x': 0, 'y': 1, 'z': 2}
        a = self.math('MULTIPLY', sep.outputs[i[axes[0]]], scale)
        b = self.math('MULTIPLY', sep.outputs[i[axes[1]]], scale)
        return self.n('ShaderNodeCombineXYZ', {0: a, 1: b, 2: 0.5}).outputs[0]

    def obj(self):
        if self._tc is None:
            self._tc = self.n('ShaderNodeTexCoord')
        return self._tc.outputs['Object']

    def ramp(self, fac, stops):
        node = self.n('ShaderNodeValToRGB')
        els = node.color_ramp.elements
        while len(els) < len(stops):
            els.new(0.5)
        for el, (pos, col) in zip(els, stops):
            el.position = pos
            el.color = tuple(col) + (1.0,)
        self.set(node.inputs[0], fac)
        return node.outputs[0]

    def diffuse(self, color):
        bsdf = self.n('ShaderNodeBsdfDiffuse', {'Color': color, 'Roughness': 0.0})
        self.set(self._out.inputs['Surface'], bsdf)
        return self.mat


# ----------------------------------------------------------------------------- materials
m = Mat('floor_checker', 1)           # 4 cm checker
chk = m.n('ShaderNodeTexChecker', {'Vector': m.uv2('xy'), 'Scale': 25.0,
                                   'Color1': (0.75, 0.72, 0.68), 'Color2': (0.12, 0.12, 0.14)})
mat_floor = m.diffuse(chk.outputs['Color'])

m = Mat('back_brick', 2)              # 10 x 5 cm bricks, 1 cm mortar
br = m.n('ShaderNodeTexBrick', {'Vector': m.uv2('xz'), 'Scale': 10.0,
                                'Color1': (0.72, 0.46, 0.36), 'Color2': (0.50, 0.30, 0.24),
                                'Mortar': (0.85, 0.84, 0.80), 'Mortar Size': 0.1,
                                'Mortar Smooth': 0.0, 'Bias': 0.0, 'Brick Width': 1.0,
                                'Row Height': 0.5}, offset=0.5, squash=1.0)
mat_back = m.diffuse(br.outputs['Color'])

m = Mat('left_noise', 3)
nz = m.n('ShaderNodeTexNoise', {'Vector': m.uv2('yz'), 'Scale': 30.0, 'Detail': 8.0, 'Roughness': 0.65})
mat_left = m.diffuse(m.ramp(nz.outputs['Fac'], [(0.3, (0.25, 0.04, 0.03)), (0.7, (0.75, 0.12, 0.08))]))

m = Mat('right_voronoi', 4)
vo = m.n('ShaderNodeTexVoronoi', {'Vector': m.uv2('yz'), 'Scale': 18.0}, feature='DISTANCE_TO_EDGE')
mat_right = m.diffuse(m.ramp(vo.outputs['Distance'], [(0.0, (0.02, 0.08, 0.02)), (0.06, (0.10, 0.45, 0.08)),
                                                     (0.3, (0.25, 0.60, 0.15))]))

m = Mat('ceiling_white', 5)
mat_ceil = m.diffuse((0.78, 0.78, 0.78))

m = Mat('tallbox_bands', 6)
wv = m.n('ShaderNodeTexWave', {'Vector': m.obj(), 'Scale': 6.0, 'Distortion': 0.0},
         wave_type='BANDS', bands_direction='Z', wave_profile='SIN')
mat_box = m.diffuse(m.ramp(wv.outputs['Fac'], [(0.0, (0.45, 0.45, 0.50)), (1.0, (0.80, 0.80, 0.78))]))

m = Mat('cylinder_stripes', 7)
wv = m.n('ShaderNodeTexWave', {'Vector': m.obj(), 'Scale': 5.0, 'Distortion': 0.0},
         wave_type='BANDS', bands_direction='DIAGONAL', wave_profile='SAW')
mat_cyl = m.diffuse(m.ramp(wv.outputs['Fac'], [(0.0, (0.70, 0.62, 0.20)), (0.5, (0.70, 0.62, 0.20)),
                                              (0.51, (0.15, 0.12, 0.05)), (1.0, (0.15, 0.12, 0.05))]))

m = Mat('sphere_checker', 8)          # 3D checker in object space: moves rigidly with the sphere
chk = m.n('ShaderNodeTexChecker', {'Vector': m.obj(), 'Scale': 8.0,
                                   'Color1': (0.20, 0.35, 0.80), 'Color2': (0.85, 0.85, 0.80)})
mat_sphere = m.diffuse(chk.outputs['Color'])

# ----------------------------------------------------------------------------- geometry
# room [-1,1] x [-1,1] x [0,2], open towards -y where the camera is
mesh_obj('floor', [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [(0, 1, 2, 3)], mat_floor, 1)
mesh_obj('ceiling', [(-1, -1, 2), (-1, 1, 2), (1, 1, 2), (1, -1, 2)], [(0, 1, 2, 3)], mat_ceil, 2)
mesh_obj('back_wall', [(-1, 1, 0), (1, 1, 0), (1, 1, 2), (-1, 1, 2)], [(0, 1, 2, 3)], mat_back, 3)
mesh_obj('left_wall', [(-1, -1, 0), (-1, 1, 0), (-1, 1, 2), (-1, -1, 2)], [(0, 1, 2, 3)], mat_left, 4)
mesh_obj('right_wall', [(1, -1, 0), (1, -1, 2), (1, 1, 2), (1, 1, 0)], [(0, 1, 2, 3)], mat_right, 5)

x0, y0, z0, x1, y1, z1 = -0.25, -0.25, 0.0, 0.25, 0.25, 1.1
tb = mesh_obj('tall_box', [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
                           (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],
              [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
              mat_box, 6, location=(-0.15, 0.45, 0.0))
tb.rotation_euler = (0, 0, math.radians(25))

bm = bmesh.new()
bmesh.ops.create_cone(bm, cap_ends=True, cap_tris=False, segments=48, radius1=0.17, radius2=0.17, depth=0.6)
bmesh.ops.translate(bm, vec=Vector((0, 0, 0.3)), verts=bm.verts)
cyl = bm_obj('cylinder', bm, mat_cyl, 7, smooth=False, location=(0.55, 0.15, 0.0))
for poly in cyl.data.polygons:
    poly.use_smooth = abs(poly.normal.z) < 0.5

bm = bmesh.new()
bmesh.ops.create_uvsphere(bm, u_segments=64, v_segments=32, radius=0.26)
sphere = bm_obj('sphere', bm, mat_sphere, 8, smooth=True, location=(0.0, -0.2, 0.3))

ld = bpy.data.lights.new('area_light', 'AREA')
ld.shape, ld.size, ld.size_y, ld.energy, ld.color = 'RECTANGLE', 0.6, 0.5, 45.0, (1.0, 0.93, 0.82)
light = link('area_light', ld, 9)
light.location = (0.0, 0.05, 1.98)          # default orientation points down (-z)

w = bpy.data.worlds.new('World')
w.use_nodes = True
w.node_tree.nodes['Background'].inputs['Strength'].default_value = 0.0
sc.world = w

cd = bpy.data.cameras.new('Camera')
cd.sensor_fit = 'VERTICAL'
cd.sensor_height = cd.sensor_width = 24.0
cd.lens = 12.0 / math.tan(math.radians(40.0) / 2)   # 40 deg vertical FOV
cd.clip_start, cd.clip_end = 0.01, 1000.0
cam = bpy.data.objects.new('Camera', cd)
sc.collection.objects.link(cam)
cam.location = (0.0, -3.5, 1.0)
cam.rotation_euler = (Vector((0, 0, 1.0)) - Vector(cam.location)).to_track_quat('-Z', 'Y').to_euler()
sc.camera = cam

# ----------------------------------------------------------------------------- animation
# Keyframes at frames 0 and 10 with linear interpolation + linear extrapolation, so every
# frame (incl. first-1 and last+1, which Cycles evaluates for the Vector pass) is defined.
def animate(ob, path, v0, v10):
    for f, v in ((0, v0), (10, v10)):
        setattr(ob, path, v)
        ob.keyframe_insert(data_path=path, frame=f)
    for fc in ob.animation_data.action.fcurves:
        fc.extrapolation = 'LINEAR'
        for kp in fc.keyframe_points:
            kp.interpolation = 'LINEAR'


if args.motion == 'pan':
    # per frame: camera +2 cm right, +0.8 cm up, yaw 0.15 deg to the right
    cl, cr = Vector(cam.location), Vector(cam.rotation_euler)
    animate(cam, 'location', cl + Vector((-0.02, 0, -0.008)) * 4, cl + Vector((0.02, 0, 0.008)) * 6)
    animate(cam, 'rotation_euler', cr + Vector((0, 0, math.radians(0.15))) * 4,
            cr - Vector((0, 0, math.radians(0.15))) * 6)
    # per frame: sphere +7 cm right, +1.5 cm up; it passes in front of the tall box
    sl = Vector((-0.55, -0.2, 0.3))
    animate(sphere, 'location', sl + Vector((0.07, 0, 0.015)) * -1, sl + Vector((0.07, 0, 0.015)) * 9)

# ----------------------------------------------------------------------------- render settings
sc.render.engine = 'CYCLES'
cy = sc.cycles
cy.device = 'CPU'
cy.feature_set = 'SUPPORTED'
cy.samples = args.spp
cy.use_adaptive_sampling = False
cy.use_denoising = False
cy.use_animated_seed = False
cy.max_bounces = 8
cy.diffuse_bounces = 4
cy.glossy_bounces = 4
cy.transmission_bounces = 8
cy.volume_bounces = 0
cy.transparent_max_bounces = 8
cy.sample_clamp_direct = 0.0
cy.sample_clamp_indirect = 0.0
cy.time_limit = 0.0
sc.render.use_motion_blur = False
sc.render.threads_mode = 'FIXED'
sc.render.threads = args.threads
sc.render.resolution_x = sc.render.resolution_y = args.size
sc.render.resolution_percentage = 100
sc.render.film_transparent = False
sc.render.use_compositing = False
sc.render.use_sequencer = False
sc.render.use_file_extension = False
sc.view_settings.view_transform = 'Standard'
sc.view_settings.look = 'None'
im = sc.render.image_settings
im.file_format = 'OPEN_EXR_MULTILAYER'
im.color_depth = '32'
im.exr_codec = 'ZIP'
im.color_mode = 'RGBA'
vl = sc.view_layers[0]
vl.name = 'ViewLayer'
for p in ('combined', 'z', 'normal', 'position', 'vector', 'object_index', 'cryptomatte_object'):
    setattr(vl, 'use_pass_' + p, True)
vl.pass_cryptomatte_depth = 2
vl.cycles.denoising_store_passes = True

frames = [args.only_frame] if args.only_frame is not None else \
    list(range(args.first, args.first + args.frames))
sc.frame_start, sc.frame_end = min(frames), max(frames)
if args.save_blend:
    bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save_blend))

os.makedirs(os.path.dirname(os.path.abspath(frame_path(args.out_pattern, frames[0]))), exist_ok=True)
for f in frames:
    sc.frame_set(f)
    cy.seed = f + args.seed_offset
    sc.render.filepath = os.path.abspath(frame_path(args.out_pattern, f))
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    print('sequence_scene: %s frame %d seed %d spp %d -> %s  %.1f s'
          % (args.motion, f, cy.seed, args.spp, sc.render.filepath, time.time() - t0), flush=True)
