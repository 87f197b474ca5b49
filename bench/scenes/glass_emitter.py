"""glass_emitter: a tabletop in the corner of a room whose right side is open to a pale blue
world (constant colour, ~1.3-1.9 linear).  On a wooden table: a clear glass sphere and a glass
block (Glass BSDF, roughness 0) in front of a patterned wallpaper, which they refract; a
standing sharp mirror (Glossy BSDF, roughness 0) that reflects the table, the lamp and the open
side; a visible emissive lamp (an Emission-shader cylinder shade, strength 12) and a few
diffuse objects.  The key light is a rectangular area light above the table, out of frame.

blender -b --factory-startup -noaudio --python glass_emitter.py -- --spp 16 --seed 1 --out x.exr
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

args = C.start()

# --- materials -------------------------------------------------------------------------
# wallpaper: vertical stripes (4 cm pitch) with a small diamond pattern in the wide stripes
mat_paper = C.striped_paper('wallpaper', 1, 0.04, 0.026, 0.03, 0.008, (0.20, 0.32, 0.30), (0.72, 0.66, 0.52),
                            (0.55, 0.12, 0.10))

# table: wood grain
m = C.Mat('table_wood', 2)
wv = m.n('ShaderNodeTexWave', {'Vector': m.coord('Object'), 'Scale': 6.0, 'Distortion': 4.0,
                               'Detail': 2.0}, wave_type='BANDS', bands_direction='Y')
wood = m.ramp(wv.outputs['Fac'], [(0.0, (0.28, 0.15, 0.07)), (1.0, (0.46, 0.29, 0.14))])
mat_table = m.out(m.principled(base=wood, rough=0.35, spec=0.5))

# floor: large grey tiles; other walls: plain plaster
m = C.Mat('floor_tiles', 3)
ck = m.n('ShaderNodeTexChecker', {'Vector': m.uv2('xy', 1.0), 'Scale': 2.5,
                                  'Color1': (0.45, 0.44, 0.42), 'Color2': (0.25, 0.25, 0.26)})
mat_floor = m.out(m.diffuse(ck.outputs['Color']))
mat_plaster = C.diffuse_mat('plaster', 4, (0.70, 0.68, 0.64))

# glass and mirror
m = C.Mat('glass_clear', 5)
mat_glass = m.out(m.n('ShaderNodeBsdfGlass', {'Color': (1.0, 1.0, 1.0), 'Roughness': 0.0, 'IOR': 1.5},
                      distribution='SHARP').outputs[0])
m = C.Mat('mirror', 6)
mat_mirror = m.out(m.n('ShaderNodeBsdfGlossy', {'Color': (0.92, 0.92, 0.92), 'Roughness': 0.0},
                       distribution='SHARP').outputs[0])
m = C.Mat('dark_frame', 7)
mat_frame = m.out(m.principled(base=(0.06, 0.04, 0.03), rough=0.4, spec=0.5))

# lamp: glowing shade (emission only), brass-ish stand
mat_shade = C.emission_mat('lamp_shade_emit', 8, (1.0, 0.78, 0.50), 12.0)
m = C.Mat('brass', 9)
mat_brass = m.out(m.principled(base=(0.75, 0.55, 0.25), rough=0.3, metal=1.0))

# props: a checkered box and a red ball
m = C.Mat('box_checker', 10)
ck = m.n('ShaderNodeTexChecker', {'Vector': m.coord('Object'), 'Scale': 40.0,
                                  'Color1': (0.80, 0.78, 0.70), 'Color2': (0.10, 0.20, 0.45)})
mat_box = m.out(m.diffuse(ck.outputs['Color']))
mat_ball = C.diffuse_mat('ball_red', 11, (0.65, 0.06, 0.04))

# --- room corner: floor z=-0.75, back wall y=0.9 (x <= 0.55), left wall x=-1.4; open right side
C.quad('floor', (-1.4, -3.0, -0.75), (4.0, -3.0, -0.75), (4.0, 3.0, -0.75), (-1.4, 3.0, -0.75), mat_floor)
C.box('back_wall', (-1.4, 0.9, -0.75), (0.55, 1.0, 1.6), mat_paper)
C.box('left_wall', (-1.5, -3.0, -0.75), (-1.4, 1.0, 1.6), mat_plaster)

# table: 1.6 x 1.0 m top (4 cm), four legs.  Objects standing on it start E = 0.5 mm above it
# (no coplanar faces, so that renders do not depend on the BVH's ordering of ties)
E = 0.0005
C.boxes('table', [((-0.8, -0.5, -0.04), (0.8, 0.5, 0.0))] +
        [((sx * 0.74 - 0.03, sy * 0.44 - 0.03, -0.75), (sx * 0.74 + 0.03, sy * 0.44 + 0.03, -0.04))
         for sx in (-1, 1) for sy in (-1, 1)], mat_table)

# glass sphere and glass block in front of the wallpaper
C.sphere('glass_sphere', (-0.08, 0.05, 0.13 + E), 0.13, mat_glass, seg=96, rings=48)
blk = C.box('glass_block', (-0.07, -0.07, E), (0.07, 0.07, 0.16), mat_glass)
blk.location = (0.26, 0.18, 0.0)
blk.rotation_euler = (0, 0, math.radians(30))

# standing mirror on the left, turned towards the camera's right: it reflects the glass block,
# the lamp and the open side (world)
mw, mh = 0.42, 0.55
mir = C.quad('mirror', (-mw / 2, 0, 0.02), (mw / 2, 0, 0.02), (mw / 2, 0, 0.02 + mh), (-mw / 2, 0, 0.02 + mh),
             mat_mirror)
frm = C.boxes('mirror_frame', [((-mw / 2 - 0.02, 0.001, E), (mw / 2 + 0.02, 0.03, 0.02)),
                               ((-mw / 2 - 0.02, 0.001, 0.02 + mh), (mw / 2 + 0.02, 0.03, 0.04 + mh)),
                               ((-mw / 2 - 0.02, 0.001, 0.02), (-mw / 2, 0.03, 0.02 + mh)),
                               ((mw / 2, 0.001, 0.02), (mw / 2 + 0.02, 0.03, 0.02 + mh))], mat_frame)
for ob in (mir, frm):
    ob.location = (-0.52, 0.12, 0.0)
    ob.rotation_euler = (math.radians(-8), 0, math.radians(58))

# lamp: brass stand + emissive cylinder shade on the right of the table
C.cylinder('lamp_base', (0.55, 0.22, E), 0.06, 0.015, mat_brass, seg=32)
C.cylinder('lamp_stem', (0.55, 0.22, 0.015), 0.008, 0.20, mat_brass, seg=12)
C.cylinder('lamp_shade', (0.55, 0.22, 0.20), 0.075, 0.12, mat_shade, seg=48, r2=0.05)

# props
C.box('checker_box', (0.05, -0.33, E), (0.22, -0.20, 0.07), mat_box)
C.sphere('red_ball', (-0.30, -0.25, 0.045 + E), 0.045, mat_ball)

# --- lights: area light above the table (out of frame), world seen through the open side --
C.area_light('key_area', (0.25, -0.35, 1.45), (0.0, 0.05, 0.0), 0.6, 0.4, 15.0, (1.0, 0.96, 0.9))
C.world_color((0.62, 0.74, 0.95), 2.0)

C.camera((0.05, -1.35, 0.48), (0.05, 0.15, 0.08), 45.0)
C.render(args)
