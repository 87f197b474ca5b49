"""Shared helpers for the procedural Blender 3.4 / Cycles test scenes.
(Copy of the public scene set's helpers, /work/shared/scenes/common.py, so that bench/scenes is self-contained;
start(), plaster_mat() and striped_paper() are added.)

Every scene script does:  sys.path.insert(0, <its dir>); import common
and then builds geometry/materials/lights with these helpers and calls
common.render(args, camera).  Everything is deterministic (fixed Python RNG
seeds, fixed Cycles seed from the command line).

Command line (after Blender's `--`):
  --spp N --seed S --out FILE.exr [--res W H] [--depth 16|32] [--codec ZIP|PIZ]
  [--threads 2] [--save-blend FILE.blend]
"""
import argparse
import math
import os
import sys

import bmesh
import bpy
from mathutils import Vector


def parse_args():
    argv = sys.argv[sys.argv.index('--') + 1:] if '--' in sys.argv else []
    p = argparse.ArgumentParser(prog='blender -b --factory-startup -noaudio --python SCENE.py --')
    p.add_argument('--spp', type=int, default=16)
    p.add_argument('--seed', type=int, default=1)
    p.add_argument('--out', required=True)
    p.add_argument('--res', type=int, nargs=2, default=[384, 384], metavar=('W', 'H'))
    p.add_argument('--depth', choices=['16', '32'], default='16')
    p.add_argument('--codec', default='ZIP')
    p.add_argument('--threads', type=int, default=2)
    p.add_argument('--save-blend', default=None)
    return p.parse_args(argv)


def start():
    """The command line parsed and the scene cleared. --out and --save-blend are made absolute,
    so that a saved .blend renders to the same place."""
    args = parse_args()
    args.out = os.path.abspath(args.out)
    if args.save_blend:
        args.save_blend = os.path.abspath(args.save_blend)
    clear_scene()
    return args


def clear_scene():
    for coll in (bpy.data.objects, bpy.data.meshes, bpy.data.lights, bpy.data.cameras,
                 bpy.data.materials, bpy.data.worlds):
        for item in list(coll):
            coll.remove(item)


# ----------------------------------------------------------------------------- geometry
_OB_INDEX = [0]


def _link(name, data, pass_index=None):
    ob = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(ob)
    _OB_INDEX[0] += 1
    ob.pass_index = _OB_INDEX[0] if pass_index is None else pass_index
    return ob


def mesh_obj(name, verts, faces, mat=None, smooth=False, location=(0, 0, 0)):
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(v) for v in verts], [], [tuple(f) for f in faces])
    me.validate()
    me.update()
    for poly in me.polygons:
        poly.use_smooth = smooth
    if mat is not None:
        me.materials.append(mat)
    ob = _link(name, me)
    ob.location = location
    return ob


def bm_obj(name, bm, mat=None, smooth=False, location=(0, 0, 0)):
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    for poly in me.polygons:
        poly.use_smooth = smooth
    if mat is not None:
        me.materials.append(mat)
    ob = _link(name, me)
    ob.location = location
    return ob


def box_geom(lo, hi, vbase=0):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
         (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    f = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    return v, [tuple(i + vbase for i in q) for q in f]


def box(name, lo, hi, mat=None):
    v, f = box_geom(lo, hi)
    return mesh_obj(name, v, f, mat)


def boxes(name, los_his, mat=None):
    """Several axis-aligned boxes merged into one object."""
    V, F = [], []
    for lo, hi in los_his:
        v, f = box_geom(lo, hi, len(V))
        V += v
        F += f
    return mesh_obj(name, V, F, mat)


def quad(name, p0, p1, p2, p3, mat=None):
    return mesh_obj(name, [p0, p1, p2, p3], [(0, 1, 2, 3)], mat)


def sphere(name, loc, r, mat=None, seg=64, rings=32):
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=seg, v_segments=rings, radius=r)
    return bm_obj(name, bm, mat, smooth=True, location=loc)


def cylinder(name, loc, r, h, mat=None, seg=48, r2=None):
    """Cylinder (or cone if r2 given) standing on loc (loc = centre of the bottom cap)."""
    bm = bmesh.new()
    bmesh.ops.create_cone(bm, cap_ends=True, cap_tris=False, segments=seg,
                          radius1=r, radius2=r if r2 is None else r2, depth=h)
    bmesh.ops.translate(bm, vec=Vector((0, 0, h / 2)), verts=bm.verts)
    ob = bm_obj(name, bm, mat, smooth=False, location=loc)
    # smooth only the side faces
    for poly in ob.data.polygons:
        poly.use_smooth = abs(poly.normal.z) < 0.5
    return ob


def torus(name, loc, R, r, mat=None, nu=64, nv=24):
    V, F = [], []
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            w = 2 * math.pi * j / nv
            V.append(((R + r * math.cos(w)) * math.cos(u), (R + r * math.cos(w)) * math.sin(u), r * math.sin(w)))
    for i in range(nu):
        for j in range(nv):
            a, b = i * nv + j, ((i + 1) % nu) * nv + j
            c, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
            F.append((a, b, c, d))
    return mesh_obj(name, V, F, mat, smooth=True, location=loc)


# ----------------------------------------------------------------------------- materials
class Mat:
    """Tiny node-graph builder: m = Mat('name', idx); m.out(shader_socket)."""

    def __init__(self, name, pass_index):
        self.mat = bpy.data.materials.new(name)
        self.mat.use_nodes = True
        self.mat.pass_index = pass_index
        self.nt = self.mat.node_tree
        self.nt.nodes.clear()
        self._out = self.nt.nodes.new('ShaderNodeOutputMaterial')
        self._tc = None

    def n(self, typ, inputs=None, **props):
        node = self.nt.nodes.new(typ)
        for k, v in props.items():
            setattr(node, k, v)
        for k, v in (inputs or {}).items():
            self.set(node.inputs[k], v)
        return node

    def set(self, sock, v):
        if isinstance(v, bpy.types.NodeSocket):
            self.nt.links.new(v, sock)
        elif isinstance(v, bpy.types.Node):
            self.nt.links.new(v.outputs[0], sock)
        else:
            if isinstance(v, (tuple, list)) and len(v) == 3 and len(sock.default_value) == 4:
                v = tuple(v) + (1.0,)
            sock.default_value = v

    def coord(self, space='Object'):
        if self._tc is None:
            self._tc = self.n('ShaderNodeTexCoord')
        return self._tc.outputs[space]

    def uv2(self, axes='xy', scale=1.0, offset=(0.0, 0.0), space='Object'):
        """2D texture coordinates from two object-space axes (third component fixed at 0.5,
        so 3D textures such as Checker never flicker on axis-aligned planes)."""
        sep = self.n('ShaderNodeSeparateXYZ', {0: self.coord(space)})
        idx = {'x': 0, 'y': 1, 'z': 2}
        a = self.math('MULTIPLY_ADD', sep.outputs[idx[axes[0]]], scale, offset[0])
        b = self.math('MULTIPLY_ADD', sep.outputs[idx[axes[1]]], scale, offset[1])
        return self.n('ShaderNodeCombineXYZ', {0: a, 1: b, 2: 0.5}).outputs[0]

    def math(self, op, a, b=0.0, c=0.0):
        node = self.n('ShaderNodeMath', operation=op)
        self.set(node.inputs[0], a)
        self.set(node.inputs[1], b)
        self.set(node.inputs[2], c)
        return node.outputs[0]

    def mix(self, fac, c1, c2, blend='MIX'):
        node = self.n('ShaderNodeMixRGB', blend_type=blend)
        self.set(node.inputs['Fac'], fac)
        self.set(node.inputs['Color1'], c1)
        self.set(node.inputs['Color2'], c2)
        return node.outputs[0]

    def ramp(self, fac, stops, interp='LINEAR'):
        node = self.n('ShaderNodeValToRGB')
        node.color_ramp.interpolation = interp
        els = node.color_ramp.elements
        while len(els) < len(stops):
            els.new(0.5)
        for el, (pos, col) in zip(els, stops):
            el.position = pos
            el.color = tuple(col) + (1.0,) if len(col) == 3 else tuple(col)
        self.set(node.inputs[0], fac)
        return node.outputs[0]

    def diffuse(self, color, roughness=0.0):
        return self.n('ShaderNodeBsdfDiffuse', {'Color': color, 'Roughness': roughness}).outputs[0]

    def principled(self, **kw):
        names = {'base': 'Base Color', 'rough': 'Roughness', 'metal': 'Metallic',
                 'spec': 'Specular', 'ior': 'IOR', 'trans': 'Transmission'}
        return self.n('ShaderNodeBsdfPrincipled', {names.get(k, k): v for k, v in kw.items()}).outputs[0]

    def out(self, shader):
        self.set(self._out.inputs['Surface'], shader)
        return self.mat


def diffuse_mat(name, idx, color):
    m = Mat(name, idx)
    return m.out(m.diffuse(color))


def plaster_mat(name, idx, dark, light):
    """Matte plaster: low-contrast noise (scale 9) between the colours dark and light."""
    m = Mat(name, idx)
    nz = m.n('ShaderNodeTexNoise', {'Vector': m.coord('Object'), 'Scale': 9.0, 'Detail': 4.0})
    return m.out(m.diffuse(m.ramp(nz.outputs['Fac'], [(0.35, dark), (0.65, light)])))


def striped_paper(name, idx, pitch, width, row, size, dark, light, diamond):
    """Wallpaper of vertical stripes along object x: every pitch metres a light stripe width
    wide, with a diamond (half-diagonal size) in its middle every row metres up z."""
    m = Mat(name, idx)
    M = m.math
    sep = m.n('ShaderNodeSeparateXYZ', {0: m.coord('Object')})
    X, Z = sep.outputs[0], sep.outputs[2]
    stripe = M('LESS_THAN', M('MODULO', M('ADD', X, 10.0), pitch), width)
    dia = M('LESS_THAN', M('ADD', M('ABSOLUTE', M('SUBTRACT', M('MODULO', M('ADD', X, 10.0), pitch), width / 2)),
                           M('ABSOLUTE', M('SUBTRACT', M('MODULO', M('ADD', Z, 10.0), row), row / 2))), size)
    col = m.mix(stripe, dark, light)
    col = m.mix(M('MULTIPLY', stripe, dia), col, diamond)
    return m.out(m.diffuse(col))


def emission_mat(name, idx, color, strength):
    m = Mat(name, idx)
    return m.out(m.n('ShaderNodeEmission', {'Color': color, 'Strength': strength}).outputs[0])


# ----------------------------------------------------------------------------- lights / world / camera
def area_light(name, loc, target, size, size_y, energy, color=(1, 1, 1)):
    ld = bpy.data.lights.new(name, 'AREA')
    ld.shape = 'RECTANGLE'
    ld.size, ld.size_y, ld.energy, ld.color = size, size_y, energy, color
    ob = _link(name, ld)
    ob.location = loc
    look_at(ob, target)
    return ob


def sun_light(name, direction, strength, angle_deg, color=(1, 1, 1)):
    """direction: vector the light travels along (from sun towards the scene)."""
    ld = bpy.data.lights.new(name, 'SUN')
    ld.energy, ld.angle, ld.color = strength, math.radians(angle_deg), color
    ob = _link(name, ld)
    d = Vector(direction).normalized()
    ob.rotation_euler = d.to_track_quat('-Z', 'Y').to_euler()
    return ob


def world_color(color, strength):
    w = bpy.data.worlds.new('World')
    w.use_nodes = True
    bg = w.node_tree.nodes['Background']
    bg.inputs['Color'].default_value = tuple(color) + (1.0,)
    bg.inputs['Strength'].default_value = strength
    bpy.context.scene.world = w
    return w


def world_sky(strength, sun_elevation_deg, sun_rotation_deg, sun_disc=False, air=1.0, dust=1.0):
    """Nishita sky (sun disc off by default; use a Sun lamp for the direct sun)."""
    w = bpy.data.worlds.new('World')
    w.use_nodes = True
    nt = w.node_tree
    bg = nt.nodes['Background']
    sky = nt.nodes.new('ShaderNodeTexSky')
    sky.sky_type = 'NISHITA'
    sky.sun_disc = sun_disc
    sky.sun_elevation = math.radians(sun_elevation_deg)
    sky.sun_rotation = math.radians(sun_rotation_deg)
    sky.air_density, sky.dust_density = air, dust
    nt.links.new(sky.outputs['Color'], bg.inputs['Color'])
    bg.inputs['Strength'].default_value = strength
    bpy.context.scene.world = w
    return w


def look_at(ob, target):
    d = Vector(target) - Vector(ob.location)
    ob.rotation_euler = d.to_track_quat('-Z', 'Y').to_euler()


def camera(loc, target, vfov_deg):
    """Perspective camera with a fixed *vertical* field of view, so wider aspect ratios
    (e.g. 1920x1080) keep the vertical framing and extend horizontally."""
    cd = bpy.data.cameras.new('Camera')
    cd.sensor_fit = 'VERTICAL'
    cd.sensor_height = 24.0
    cd.sensor_width = 24.0
    cd.lens = 12.0 / math.tan(math.radians(vfov_deg) / 2)
    cd.clip_start, cd.clip_end = 0.01, 1000.0
    ob = bpy.data.objects.new('Camera', cd)
    bpy.context.scene.collection.objects.link(ob)
    ob.location = loc
    look_at(ob, target)
    bpy.context.scene.camera = ob
    return ob


# ----------------------------------------------------------------------------- render
def configure(args):
    sc = bpy.context.scene
    sc.render.engine = 'CYCLES'
    cy = sc.cycles
    cy.device = 'CPU'
    cy.feature_set = 'SUPPORTED'
    cy.samples = args.spp
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.seed = args.seed
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
    cy.use_guiding = False
    cy.use_fast_gi = False
    sc.render.threads_mode = 'FIXED'
    sc.render.threads = args.threads
    sc.render.resolution_x, sc.render.resolution_y = args.res
    sc.render.resolution_percentage = 100
    sc.render.film_transparent = False
    sc.render.use_compositing = False
    sc.render.use_sequencer = False
    sc.view_settings.view_transform = 'Standard'
    sc.view_settings.look = 'None'
    sc.view_settings.exposure = 0.0
    sc.view_settings.gamma = 1.0
    im = sc.render.image_settings
    im.file_format = 'OPEN_EXR_MULTILAYER'
    im.color_depth = args.depth
    im.exr_codec = args.codec
    im.color_mode = 'RGBA'
    vl = sc.view_layers[0]
    vl.name = 'ViewLayer'
    for p in ('combined', 'z', 'normal', 'object_index', 'material_index',
              'diffuse_direct', 'diffuse_indirect', 'diffuse_color',
              'glossy_direct', 'glossy_indirect', 'glossy_color',
              'transmission_direct', 'transmission_indirect', 'transmission_color',
              'emit', 'environment', 'cryptomatte_object'):
        setattr(vl, 'use_pass_' + p, True)
    vl.pass_cryptomatte_depth = 2
    vl.cycles.denoising_store_passes = True
    sc.render.filepath = args.out
    sc.render.use_file_extension = False


def render(args):
    configure(args)
    if args.save_blend:
        bpy.ops.wm.save_as_mainfile(filepath=args.save_blend)
    bpy.ops.render.render(write_still=True)
