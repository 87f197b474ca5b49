"""interior_indirect: a closed room lit only by bounced light (issue 45, the low-sample
blotches).  No sun and no window: two strip area lights lie on a cove ledge 35 cm below the
ceiling along the left and back walls, facing up, hidden behind the ledge's upstand.  They
light the ceiling; every other surface the camera sees (off-white walls, a white cabinet, a
grey sofa, a rug with a fine pattern, an oak floor, a picture with a 2.5 cm checker) is lit
only by light that has bounced at least once, so at 4 spp their light is a few noisy paths
per pixel, which is where a filter leaves large low-frequency blotches.

blender -b --factory-startup -noaudio --python interior_indirect.py -- --spp 16 --seed 1 --out x.exr
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

args = C.start()

# --- materials -------------------------------------------------------------------------
# floor: 1.2 m x 15 cm oak planks, satin
m = C.Mat('floor_oak', 1)
br = m.n('ShaderNodeTexBrick', {'Vector': m.uv2('yx', 1.0), 'Scale': 1.0, 'Color1': (1.0, 1.0, 1.0),
                                'Color2': (0.6, 0.6, 0.6), 'Mortar': (0.0, 0.0, 0.0),
                                'Mortar Size': 0.003, 'Mortar Smooth': 0.0, 'Bias': 0.0},
         offset=0.37, offset_frequency=1, squash=1.0)
br.inputs['Brick Width'].default_value = 1.2
br.inputs['Row Height'].default_value = 0.15
grain = m.n('ShaderNodeTexWave', {'Vector': m.coord('Object'), 'Scale': 9.0, 'Distortion': 5.0,
                                  'Detail': 2.0}, wave_type='BANDS', bands_direction='X')
wood = m.ramp(grain.outputs['Fac'], [(0.0, (0.34, 0.19, 0.08)), (1.0, (0.55, 0.34, 0.15))])
col = m.mix(br.outputs['Fac'], m.mix(1.0, wood, br.outputs['Color'], 'MULTIPLY'), (0.03, 0.02, 0.01))
mat_floor = m.out(m.principled(base=col, rough=0.4, spec=0.5))

# walls: off-white plaster with low-contrast noise; white ceiling
mat_wall = C.plaster_mat('walls_plaster', 2, (0.66, 0.64, 0.60), (0.80, 0.78, 0.74))
mat_ceil = C.diffuse_mat('ceiling', 3, (0.82, 0.82, 0.80))

# white cabinet (satin paint), grey fabric sofa
m = C.Mat('white_cabinet', 4)
mat_cab = m.out(m.principled(base=(0.80, 0.80, 0.78), rough=0.35, spec=0.5))
mat_sofa = C.diffuse_mat('sofa_fabric', 5, (0.30, 0.31, 0.33))

# rug: 3 cm checker of two warm tones with 1 cm border stripes
m = C.Mat('rug', 6)
ck = m.n('ShaderNodeTexChecker', {'Vector': m.uv2('xy', 1.0), 'Scale': 33.0,
                                  'Color1': (0.55, 0.20, 0.12), 'Color2': (0.78, 0.64, 0.42)})
mat_rug = m.out(m.diffuse(ck.outputs['Color']))

# picture: fine checker; dark frame
m = C.Mat('picture_checker', 7)
ck = m.n('ShaderNodeTexChecker', {'Vector': m.uv2('xz', 1.0), 'Scale': 40.0,
                                  'Color1': (0.80, 0.74, 0.55), 'Color2': (0.08, 0.12, 0.30)})
mat_pic = m.out(m.diffuse(ck.outputs['Color']))
mat_frame = C.diffuse_mat('frame', 8, (0.08, 0.05, 0.03))

# --- room: x in [-3,3], y in [-2.5,2.5], z in [0,2.7]; 15 cm walls -----------------------
X, Y, H, T = 3.0, 2.5, 2.7, 0.15
C.box('floor', (-X - T, -Y - T, -T), (X + T, Y + T, 0), mat_floor)
C.box('ceiling', (-X - T, -Y - T, H), (X + T, Y + T, H + T), mat_ceil)
C.box('back_wall', (-X, Y, 0), (X, Y + T, H), mat_wall)
C.box('front_wall', (-X, -Y - T, 0), (X, -Y, H), mat_wall)
C.box('left_wall', (-X - T, -Y, 0), (-X, Y, H), mat_wall)
C.box('right_wall', (X, -Y, 0), (X + T, Y, H), mat_wall)

# cove: a 30 cm ledge at z = 2.35 along the left and back walls with an 8 cm upstand that hides
# the strip lights lying on it (the lights face the ceiling)
zc = H - 0.35
C.boxes('cove', [((-X, -Y, zc - 0.04), (-X + 0.30, Y, zc)), ((-X + 0.28, -Y, zc), (-X + 0.30, Y, zc + 0.08)),
                 ((-X, Y - 0.30, zc - 0.04), (X, Y, zc)), ((-X, Y - 0.30, zc), (X, Y - 0.28, zc + 0.08))],
        mat_cab)
C.area_light('cove_left', (-X + 0.14, 0.0, zc + 0.02), (-X + 0.14, 0.0, H), 0.12, 2 * Y - 0.4, 80.0,
             (1.0, 0.88, 0.72))
C.area_light('cove_back', (0.0, Y - 0.14, zc + 0.02), (0.0, Y - 0.14, H), 2 * X - 0.4, 0.12, 90.0,
             (1.0, 0.88, 0.72))

# white cabinet against the back wall (doors split by 3 mm gaps), sofa, rug, picture
cx0, cx1 = -1.9, -0.3
C.boxes('cabinet', [((cx0, Y - 0.45, 0.10), (cx1, Y - 0.01, 0.95)),
                    ((cx0 + 0.05, Y - 0.40, 0.0), (cx1 - 0.05, Y - 0.05, 0.10))], mat_cab)
C.boxes('cabinet_gaps', [((x - 0.0015, Y - 0.452, 0.12), (x + 0.0015, Y - 0.449, 0.93))
                         for x in (cx0 + 0.4, cx0 + 0.8, cx0 + 1.2)], mat_frame)
C.boxes('sofa', [((0.6, 0.9, 0.0), (2.6, 1.8, 0.42)), ((0.6, 1.55, 0.42), (2.6, 1.8, 0.85)),
                 ((0.6, 0.9, 0.42), (0.8, 1.55, 0.62)), ((2.4, 0.9, 0.42), (2.6, 1.55, 0.62))], mat_sofa)
C.box('rug', (-1.0, -1.2, 0.0), (1.6, 0.6, 0.008), mat_rug)
px0, px1 = 0.9, 2.3
C.boxes('picture_frame', [((px0 - 0.05, Y - 0.04, 1.15), (px1 + 0.05, Y, 1.20)),
                          ((px0 - 0.05, Y - 0.04, 1.95), (px1 + 0.05, Y, 2.00)),
                          ((px0 - 0.05, Y - 0.04, 1.20), (px0, Y, 1.95)), ((px1, Y - 0.04, 1.20), (px1 + 0.05, Y, 1.95))],
        mat_frame)
C.quad('picture', (px0, Y - 0.02, 1.20), (px1, Y - 0.02, 1.20), (px1, Y - 0.02, 1.95), (px0, Y - 0.02, 1.95), mat_pic)

C.world_color((0.0, 0.0, 0.0), 0.0)
C.camera((2.5, -2.2, 1.5), (-0.8, 1.6, 1.0), 62.0)
C.render(args)
