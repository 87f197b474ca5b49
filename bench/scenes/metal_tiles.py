"""metal_tiles: glossy reflections and rough metal (issue 45).  A studio corner with a floor of
40 cm tiles in a checker of mirror-finish steel (Principled, metallic 1, roughness 0.02) and
glossy dark-blue ceramic (roughness 0.12), 5 mm dark grout.  Textured objects stand on it and are
seen again in the mirror tiles: a box with a 1 cm checker, a striped wood-grain drum and a
patterned back wall.  Three metal spheres (r 18 cm) in a row: gold at roughness 0.05, copper at
0.2, steel at 0.4, so that a filter's treatment of a reflection can be read off against how
much the surface itself blurs it.  On the right, a clear glass sphere (Glass BSDF, roughness 0)
stands 12 cm in front of a board with fine text-like stripes, which it refracts upside down.
A large soft area light (key) above the left, a smaller fill from the right and a pale grey-blue
world (constant, ~0.6) seen past the open right side and in every reflection.

Material indices (IndexMA), for per-region measurement: 20 gold (0.05), 21 copper (0.2),
22 steel (0.4), 23 glass sphere, 1 floor, 5 text board.

blender -b --factory-startup -noaudio --python metal_tiles.py -- --spp 16 --seed 1 --out x.exr
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

args = C.start()

# --- materials -------------------------------------------------------------------------
# floor: 40 cm checker of mirror steel and glossy ceramic, 5 mm grout (a Brick texture's mortar)
m = C.Mat('floor_tiles', 1)
uv = m.uv2('xy', 1.0)
ck = m.n('ShaderNodeTexChecker', {'Vector': m.uv2('xy', 1.0, (0.001, 0.001)), 'Scale': 2.5,
                                  'Color1': (1.0, 1.0, 1.0), 'Color2': (0.0, 0.0, 0.0)})
br = m.n('ShaderNodeTexBrick', {'Vector': uv, 'Scale': 1.0, 'Color1': (1.0, 1.0, 1.0),
                                'Color2': (1.0, 1.0, 1.0), 'Mortar': (0.0, 0.0, 0.0),
                                'Mortar Size': 0.005, 'Mortar Smooth': 0.0, 'Bias': 0.0},
         offset=0.0, offset_frequency=1, squash=1.0)
br.inputs['Brick Width'].default_value = 0.4
br.inputs['Row Height'].default_value = 0.4
mirror_tile = m.principled(base=(0.90, 0.90, 0.92), rough=0.02, metal=1.0)
ceramic = m.principled(base=(0.05, 0.08, 0.16), rough=0.12, spec=0.5)
grout = m.diffuse((0.04, 0.04, 0.04))
tiles = m.n('ShaderNodeMixShader', {0: ck.outputs['Fac'], 1: ceramic, 2: mirror_tile}).outputs[0]
mat_floor = m.out(m.n('ShaderNodeMixShader', {0: br.outputs['Fac'], 1: tiles, 2: grout}).outputs[0])

# back wall: 6 cm stripes with a small diamond in the light ones (seen in the mirror tiles too)
mat_paper = C.striped_paper('back_wallpaper', 2, 0.06, 0.036, 0.05, 0.012, (0.16, 0.20, 0.34), (0.74, 0.68, 0.55),
                            (0.60, 0.14, 0.08))
mat_plaster = C.diffuse_mat('plaster', 3, (0.68, 0.67, 0.64))

# box with a 1 cm checker; drum with wood grain cut by 2 cm stripes
m = C.Mat('box_checker', 4)
ck = m.n('ShaderNodeTexChecker', {'Vector': m.coord('Object'), 'Scale': 100.0,
                                  'Color1': (0.82, 0.80, 0.72), 'Color2': (0.55, 0.10, 0.06)})
mat_box = m.out(m.diffuse(ck.outputs['Color']))

# text board: rows of short dark dashes of varying length (text-like), 2.2 cm line pitch
m = C.Mat('text_board', 5)
M = m.math
sep = m.n('ShaderNodeSeparateXYZ', {0: m.coord('Object')})
X, Z = sep.outputs[0], sep.outputs[2]
line = M('LESS_THAN', M('MODULO', M('ADD', Z, 10.0), 0.022), 0.012)
nz = m.n('ShaderNodeTexNoise', {'Vector': m.n('ShaderNodeCombineXYZ', {0: M('MULTIPLY', X, 1.0),
                                                                     1: M('FLOOR', M('MULTIPLY', Z, 45.4)), 2: 0.3}),
                                'Scale': 28.0, 'Detail': 0.0})
word = M('GREATER_THAN', nz.outputs['Fac'], 0.47)
ink = M('MULTIPLY', line, word)
mat_text = m.out(m.diffuse(m.mix(ink, (0.86, 0.84, 0.78), (0.05, 0.05, 0.06))))

m = C.Mat('drum_wood', 6)
wv = m.n('ShaderNodeTexWave', {'Vector': m.coord('Object'), 'Scale': 9.0, 'Distortion': 5.0,
                               'Detail': 2.0}, wave_type='BANDS', bands_direction='Z')
wood = m.ramp(wv.outputs['Fac'], [(0.0, (0.30, 0.15, 0.06)), (1.0, (0.58, 0.36, 0.16))])
sep = m.n('ShaderNodeSeparateXYZ', {0: m.coord('Object')})
band = m.math('LESS_THAN', m.math('MODULO', m.math('ADD', sep.outputs[2], 10.0), 0.04), 0.02)
mat_drum = m.out(m.principled(base=m.mix(band, wood, (0.85, 0.83, 0.78)), rough=0.45, spec=0.5))
mat_board_frame = C.diffuse_mat('board_frame', 7, (0.08, 0.07, 0.06))

# metals: the roughness series; glass
m = C.Mat('gold_r005', 20)
mat_gold = m.out(m.principled(base=(1.0, 0.76, 0.34), rough=0.05, metal=1.0))
m = C.Mat('copper_r02', 21)
mat_copper = m.out(m.principled(base=(0.95, 0.58, 0.44), rough=0.2, metal=1.0))
m = C.Mat('steel_r04', 22)
mat_steel = m.out(m.principled(base=(0.78, 0.78, 0.80), rough=0.4, metal=1.0))
m = C.Mat('glass_clear', 23)
mat_glass = m.out(m.n('ShaderNodeBsdfGlass', {'Color': (1.0, 1.0, 1.0), 'Roughness': 0.0, 'IOR': 1.5},
                      distribution='SHARP').outputs[0])

# --- the corner: floor z=0, back wall y=2.2, left wall x=-2.2; open right and front -----
C.quad('floor', (-2.2, -4.0, 0.0), (4.0, -4.0, 0.0), (4.0, 2.2, 0.0), (-2.2, 2.2, 0.0), mat_floor)
C.box('back_wall', (-2.2, 2.2, 0.0), (2.0, 2.3, 2.6), mat_paper)
C.box('left_wall', (-2.3, -4.0, 0.0), (-2.2, 2.3, 2.6), mat_plaster)

# Objects stand E = 0.5 mm above the floor (no coplanar faces: renders must not depend on the
# BVH's ordering of ties)
E = 0.0005
R = 0.18
for i, (name, mat) in enumerate((('gold_sphere', mat_gold), ('copper_sphere', mat_copper),
                                 ('steel_sphere', mat_steel))):
    C.sphere(name, (-0.72 + 0.52 * i, 0.35 - 0.15 * i, R + E), R, mat, seg=96, rings=48)

bx = C.box('checker_box', (-0.2, -0.2, E), (0.2, 0.2, 0.34), mat_box)
bx.location = (-1.25, 1.25, 0.0)
bx.rotation_euler = (0, 0, math.radians(25))
C.cylinder('drum', (0.35, 1.35, E), 0.22, 0.55, mat_drum, seg=64)

# text board, upright, facing the camera, with the glass sphere 12 cm in front of it
bw, bh = 0.60, 0.50
brd = C.quad('text_board', (-bw / 2, 0, 0.0), (bw / 2, 0, 0.0), (bw / 2, 0, bh), (-bw / 2, 0, bh), mat_text)
frm = C.boxes('board_frame', [((-bw / 2 - 0.02, 0.001, -0.02), (bw / 2 + 0.02, 0.03, 0.0)),
                              ((-bw / 2 - 0.02, 0.001, bh), (bw / 2 + 0.02, 0.03, bh + 0.02)),
                              ((-bw / 2 - 0.02, 0.001, 0.0), (-bw / 2, 0.03, bh)),
                              ((bw / 2, 0.001, 0.0), (bw / 2 + 0.02, 0.03, bh))], mat_board_frame)
for ob in (brd, frm):
    ob.location = (1.05, 0.55, 0.12)
    ob.rotation_euler = (0, 0, math.radians(-20))
C.cylinder('board_stand', (1.05, 0.62, E), 0.02, 0.12, mat_board_frame, seg=16)
C.sphere('glass_sphere', (0.98, 0.30, 0.16 + E), 0.16, mat_glass, seg=96, rings=48)

# --- lights: soft key above the left, small fill from the right, pale world ---------------
C.area_light('key', (-1.2, -0.8, 2.4), (-0.3, 0.6, 0.0), 1.6, 1.0, 260.0, (1.0, 0.95, 0.88))
C.area_light('fill', (2.6, -0.6, 1.2), (0.6, 0.6, 0.3), 0.5, 0.5, 40.0, (0.85, 0.9, 1.0))
C.world_color((0.55, 0.62, 0.75), 0.8)

C.camera((0.1, -2.5, 0.85), (0.05, 0.8, 0.2), 44.0)
C.render(args)
