"""exterior_foliage: an outdoor shot, camera at 1.2 m looking slightly up, so that about 30% of
the frame is Nishita sky (no sun disc; sky ~1-5 linear).  A sun lamp (0.5 deg, hard shadows)
from behind the camera lights a brick facade on the left, a paved path and a grass ground
plane, a tree whose thin branches and ~4800 small leaf quads are seen against the sky, a
wrought-iron railing with 2 cm bars (sub-pixel to ~2 px at 384x384) against the sky on the
right, and a row of distant buildings on the horizon.

All geometry comes from a fixed-seed Python RNG: only the Cycles seed changes with --seed.

blender -b --factory-startup -noaudio --python exterior_foliage.py -- --spp 16 --seed 1 --out x.exr
"""
import math
import os
import random
import sys

from mathutils import Quaternion, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

args = C.start()
rng = random.Random(4242)                      # geometry only, never the --seed

# --- materials -------------------------------------------------------------------------
# grass: two noise scales over a green ramp, plus darker Voronoi clumps
m = C.Mat('grass', 1)
uv = m.uv2('xy', 1.0)
nz = m.n('ShaderNodeTexNoise', {'Vector': uv, 'Scale': 3.0, 'Detail': 4.0, 'Roughness': 0.6})
nf = m.n('ShaderNodeTexNoise', {'Vector': uv, 'Scale': 90.0, 'Detail': 2.0})
g = m.ramp(nz.outputs['Fac'], [(0.3, (0.06, 0.13, 0.03)), (0.7, (0.20, 0.26, 0.06))])
col = m.mix(0.5, g, nf.outputs['Fac'], 'MULTIPLY')
mat_grass = m.out(m.diffuse(m.mix(0.6, col, g)))

# paved path: 40 x 20 cm stone slabs, grey variation, dark joints
m = C.Mat('paving', 2)
uv = m.uv2('yx', 1.0)
br = m.n('ShaderNodeTexBrick', {'Vector': uv, 'Scale': 2.5, 'Color1': (0.42, 0.40, 0.37),
                                'Color2': (0.28, 0.27, 0.26), 'Mortar': (0.06, 0.06, 0.05),
                                'Mortar Size': 0.015, 'Bias': 0.0}, offset=0.5, squash=1.0)
nz = m.n('ShaderNodeTexNoise', {'Vector': uv, 'Scale': 40.0, 'Detail': 4.0})
col = m.mix(0.4, br.outputs['Color'], nz.outputs['Fac'], 'MULTIPLY')
mat_path = m.out(m.diffuse(col))

# brick facade: 24 x 7 cm bricks (on the y-z plane), light mortar, per-brick colour + grain
m = C.Mat('facade_brick', 3)
uv = m.uv2('yz', 1.0)
br = m.n('ShaderNodeTexBrick', {'Vector': uv, 'Scale': 4.0, 'Color1': (0.50, 0.22, 0.14),
                                'Color2': (0.34, 0.15, 0.10), 'Mortar': (0.62, 0.60, 0.55),
                                'Mortar Size': 0.012, 'Mortar Smooth': 0.0, 'Bias': 0.0},
         offset=0.5, squash=1.0)
br.inputs['Brick Width'].default_value = 0.96
br.inputs['Row Height'].default_value = 0.28
nz = m.n('ShaderNodeTexNoise', {'Vector': uv, 'Scale': 70.0, 'Detail': 3.0})
col = m.mix(0.3, br.outputs['Color'], nz.outputs['Fac'], 'MULTIPLY')
mat_brick = m.out(m.diffuse(col))
mat_stone = C.diffuse_mat('cornice_stone', 4, (0.62, 0.60, 0.55))

# bark: stretched noise bands
m = C.Mat('bark', 5)
sep = m.n('ShaderNodeSeparateXYZ', {0: m.coord('Object')})
v = m.n('ShaderNodeCombineXYZ', {0: m.math('MULTIPLY', sep.outputs[0], 25.0),
                                  1: m.math('MULTIPLY', sep.outputs[1], 25.0),
                                  2: m.math('MULTIPLY', sep.outputs[2], 4.0)})
nz = m.n('ShaderNodeTexNoise', {'Vector': v, 'Scale': 1.0, 'Detail': 3.0})
mat_bark = m.out(m.diffuse(m.ramp(nz.outputs['Fac'], [(0.35, (0.07, 0.05, 0.035)), (0.65, (0.22, 0.17, 0.12))])))

# leaves: per-leaf colour (random per-island via the leaf's own object-space position noise),
# a diffuse + translucent mix so that back-lit leaves glow a little
m = C.Mat('leaves', 6)
nz = m.n('ShaderNodeTexNoise', {'Vector': m.coord('Object'), 'Scale': 6.0, 'Detail': 1.0})
lc = m.ramp(nz.outputs['Fac'], [(0.3, (0.05, 0.16, 0.02)), (0.7, (0.22, 0.32, 0.04))])
mixs = m.n('ShaderNodeMixShader', {'Fac': 0.3})
m.set(mixs.inputs[1], m.diffuse(lc))
m.set(mixs.inputs[2], m.n('ShaderNodeBsdfTranslucent', {'Color': lc}).outputs[0])
mat_leaf = m.out(mixs.outputs[0])

m = C.Mat('railing_iron', 7)
mat_iron = m.out(m.principled(base=(0.03, 0.035, 0.03), rough=0.45, metal=0.6, spec=0.5))

# distant buildings: plain light plaster, slightly different per building by object position
m = C.Mat('far_buildings', 8)
nz = m.n('ShaderNodeTexNoise', {'Vector': m.coord('Object'), 'Scale': 0.15, 'Detail': 1.0})
mat_far = m.out(m.diffuse(m.ramp(nz.outputs['Fac'], [(0.3, (0.16, 0.15, 0.14)), (0.7, (0.34, 0.31, 0.27))])))

# --- ground: grass everywhere, a paved path along the facade ----------------------------
C.quad('grass', (-300, -300, 0), (300, -300, 0), (300, 300, 0), (-300, 300, 0), mat_grass)
C.quad('path', (-4.0, -30, 0.005), (-1.3, -30, 0.005), (-1.3, 60, 0.005), (-4.0, 60, 0.005), mat_path)

# --- brick facade on the left: x in [-4.6,-4], y in [-12, 40], 7.5 m high, stone cornice ----
C.box('facade', (-4.6, -12, 0), (-4.0, 40, 7.5), mat_brick)
C.boxes('cornice', [((-4.75, -12, 7.5), (-3.85, 40, 7.8)), ((-4.7, -12, 0), (-3.95, 40, 0.35))], mat_stone)

# --- wrought-iron railing on the right: x = 3.2, y in [-6, 30], 2 cm bars every 12 cm ---
bars = []
y = -6.0
while y <= 30.0:
    bars.append(((3.19, y - 0.01, 0.0), (3.21, y + 0.01, 1.95)))
    y += 0.12
rails = [((3.185, -6.0, z), (3.215, 30.0, z + 0.035)) for z in (0.12, 1.62, 1.88)]
posts = [((3.15, yp - 0.05, 0.0), (3.25, yp + 0.05, 2.05)) for yp in range(-6, 31, 4)]
C.boxes('railing', bars + rails + posts, mat_iron)

# --- the tree: trunk + 4 levels of tapered branches, leaf clusters at the tips -----------
TV, TF = [], []      # branches
LV, LF = [], []      # leaves


def prism(p0, p1, r0, r1, n=6):
    """n-sided tapered prism from p0 to p1 (open ends), appended to TV/TF."""
    d = (p1 - p0).normalized()
    a = d.orthogonal().normalized()
    b = d.cross(a)
    base = len(TV)
    for p, r in ((p0, r0), (p1, r1)):
        for k in range(n):
            t = 2 * math.pi * k / n
            TV.append(tuple(p + r * (math.cos(t) * a + math.sin(t) * b)))
    for k in range(n):
        k1 = (k + 1) % n
        TF.append((base + k, base + k1, base + n + k1, base + n + k))


def leaf(c):
    """one leaf: a 12 x 7 cm quad (a slightly folded pair of triangles) at c, random orientation"""
    q = Quaternion(Vector((rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1))).normalized(),
                   rng.uniform(0, 2 * math.pi))
    L, W = 0.12 * rng.uniform(0.8, 1.2), 0.07 * rng.uniform(0.8, 1.2)
    pts = [Vector((0, 0, 0)), Vector((L / 2, W / 2, 0.008)), Vector((L, 0, 0)), Vector((L / 2, -W / 2, 0.008))]
    base = len(LV)
    for p in pts:
        LV.append(tuple(c + q @ p))
    LF.append((base, base + 1, base + 2, base + 3))


def branch(p, d, length, radius, level):
    end = p + d * length
    prism(p, end, radius, radius * 0.7)
    if level >= 3:
        # leaves along the outer part of the twig and in a cluster around its tip
        for _ in range(14 if level == 3 else 40):
            t = rng.uniform(0.3, 1.0)
            off = Vector((rng.gauss(0, 1), rng.gauss(0, 1), rng.gauss(0, 1))) * (0.12 + 0.18 * t)
            leaf(p + d * length * t + off)
    if level == 4:
        return
    nchild = 3 if level > 0 else 4
    for k in range(nchild):
        axis = d.orthogonal().normalized()
        axis = Quaternion(d, 2 * math.pi * (k + rng.uniform(-0.25, 0.25)) / nchild) @ axis
        nd = Quaternion(axis, math.radians(rng.uniform(25, 45))) @ d
        nd = (nd + Vector((0, 0, 0.25))).normalized()          # phototropism
        branch(end, nd, length * rng.uniform(0.66, 0.78), radius * 0.6, level + 1)


TRUNK = Vector((1.1, 2.0, 0.0))
prism(TRUNK, TRUNK + Vector((0.05, 0.0, 2.6)), 0.17, 0.12, n=12)
branch(TRUNK + Vector((0.05, 0.0, 2.6)), Vector((0.05, 0.0, 1.0)).normalized(), 1.8, 0.11, 0)
C.mesh_obj('tree_branches', TV, TF, mat_bark)
C.mesh_obj('tree_leaves', LV, LF, mat_leaf)

# --- distant buildings along the horizon (y ~ 70-90 m) -----------------------------------
far = []
x = -60.0
while x < 60.0:
    w = rng.uniform(6.0, 14.0)
    h = rng.uniform(5.0, 13.0)
    y0 = rng.uniform(70.0, 80.0)
    far.append(((x, y0, 0.0), (x + w - 0.5, y0 + 10.0, h)))
    x += w
C.boxes('far_buildings', far, mat_far)

# --- light: sun from behind-right of the camera (hard shadows) + matching Nishita sky -----
sun_dir = Vector((-0.6, 0.45, -0.66))                  # direction the light travels
C.sun_light('sun', sun_dir, 4.0, 0.5, (1.0, 0.95, 0.88))
to_sun = -sun_dir.normalized()
elev = math.degrees(math.asin(to_sun.z))
rot = math.degrees(math.atan2(to_sun.y, to_sun.x)) - 90.0   # Nishita sun azimuth = rotation + 90 deg
C.world_sky(1.0, elev, rot % 360.0, sun_disc=False)

C.camera((0.3, -9.0, 1.2), (0.3, 0.0, 2.4), 55.0)
C.render(args)
