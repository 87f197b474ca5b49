"""glass_cabin: glass in front of a dark interior (issue 62).  A car-like studio shot: a body of
glossy red paint (Principled, clearcoat) with a cabin whose windscreen and side windows are thin
slabs of clear glass (6 mm; a sharp Fresnel reflection over a Transparent BSDF) in front of a dark interior (charcoal seats,
a black dashboard and a steering wheel).  A large soft studio key above reflects in the glass
and the paint; a strip light to the right draws a highlight along the body, and a low
softbox in front shines into the cabin through the windscreen and the near window; a chrome trim
(metallic, roughness 0.1) runs under the windscreen and a brushed-steel wheel disc (roughness
0.35) stands on the side.  A dark studio (world ~0.03) and a grey floor.  Seen through the
glass, the interior is lit by what the glass lets in: dark, noisy light behind a sharp
reflection, the region where a denoiser leaves specks.

Material indices (IndexMA), for per-region measurement: 30 glass (windscreen and side windows),
31 paint, 32 chrome trim, 33 brushed-steel disc, 34 interior.

blender -b --factory-startup -noaudio --python glass_cabin.py -- --spp 16 --seed 1 --out x.exr
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

args = C.start()

# --- materials -------------------------------------------------------------------------
# Car glass as studios shade it: a sharp reflection over a clear, slightly green see-through
# (Transparent BSDF), so that the key light reaches the cabin through it (a Glass BSDF lets in only
# caustics: a 1024-spp reference of the cabin was still noise). Reflection by Fresnel at IOR 1.52.
m = C.Mat('glass_window', 30)
fresnel = m.n('ShaderNodeFresnel', {'IOR': 1.52})
clear = m.n('ShaderNodeBsdfTransparent', {'Color': (0.86, 0.92, 0.89)}).outputs[0]
mirror = m.n('ShaderNodeBsdfGlossy', {'Color': (1.0, 1.0, 1.0), 'Roughness': 0.0}, distribution='SHARP').outputs[0]
mat_glass = m.out(m.n('ShaderNodeMixShader', {0: fresnel.outputs[0], 1: clear, 2: mirror}).outputs[0])
m = C.Mat('paint_red', 31)
mat_paint = m.out(m.principled(base=(0.55, 0.03, 0.03), rough=0.25, spec=0.5, Clearcoat=1.0,
                               **{'Clearcoat Roughness': 0.03}))
m = C.Mat('chrome_trim', 32)
mat_chrome = m.out(m.principled(base=(0.9, 0.9, 0.92), rough=0.1, metal=1.0))
m = C.Mat('brushed_steel', 33)
mat_steel = m.out(m.principled(base=(0.75, 0.75, 0.77), rough=0.35, metal=1.0))
mat_seat = C.diffuse_mat('seat_charcoal', 34, (0.045, 0.045, 0.05))
mat_dash = C.diffuse_mat('dash_black', 34, (0.02, 0.02, 0.02))
mat_floor = C.diffuse_mat('studio_floor', 1, (0.30, 0.30, 0.31))
mat_wall = C.diffuse_mat('studio_wall', 2, (0.08, 0.08, 0.085))

# --- the studio ----------------------------------------------------------------------------
C.quad('floor', (-6.0, -6.0, 0.0), (6.0, -6.0, 0.0), (6.0, 6.0, 0.0), (-6.0, 6.0, 0.0), mat_floor)
C.box('back_wall', (-6.0, 4.0, 0.0), (6.0, 4.1, 4.0), mat_wall)

# --- the car: body, cabin frame, interior, glass ----------------------------------------------
E = 0.0005
C.box('body', (-1.3, -0.62, 0.25 + E), (1.3, 0.62, 0.80), mat_paint)
# roof and pillars (the cabin's frame), paint
C.boxes('cabin_frame', [((-0.75, -0.60, 1.22), (0.25, 0.60, 1.28)),       # roof
                        ((-0.80, -0.60, 0.80), (-0.72, -0.54, 1.22)),     # rear pillars
                        ((-0.80, 0.54, 0.80), (-0.72, 0.60, 1.22)),
                        ((0.62, -0.60, 0.80), (0.70, -0.54, 0.83)),       # windscreen foot
                        ((0.62, 0.54, 0.80), (0.70, 0.60, 0.83))], mat_paint)
# interior: two seats, a dashboard, a steering wheel
C.boxes('seats', [((-0.55, -0.45, 0.80), (-0.15, -0.08, 0.92)), ((-0.62, -0.45, 0.92), (-0.50, -0.08, 1.18)),
                  ((-0.55, 0.08, 0.80), (-0.15, 0.45, 0.92)), ((-0.62, 0.08, 0.92), (-0.50, 0.45, 1.18))],
        mat_seat)
C.box('dashboard', (0.25, -0.54, 0.80), (0.55, 0.54, 0.95), mat_dash)
wheel = C.torus('steering_wheel', (0.15, -0.26, 1.02), 0.16, 0.018, mat_dash)
wheel.rotation_euler = (0, math.radians(65), 0)

# windscreen: a 6 mm slab from the body's front (x 0.70, z 0.80) up to the roof (x 0.25, z 1.25)
ws = C.box('windscreen', (-0.0015, -0.54, 0.0), (0.0045, 0.54, 0.64), mat_glass)
ws.location = (0.70, 0.0, 0.80)
ws.rotation_euler = (0, math.radians(-44), 0)
# side windows: vertical slabs between the pillars
C.box('window_left', (-0.72, -0.605, 0.83), (0.55, -0.599, 1.22), mat_glass)
C.box('window_right', (-0.72, 0.599, 0.83), (0.55, 0.605, 1.22), mat_glass)

# chrome trim under the windscreen; brushed-steel wheel discs on the near side
C.box('trim', (0.70, -0.58, 0.80), (0.76, 0.58, 0.815), mat_chrome)
for i, x in enumerate((-0.85, 0.85)):
    disc = C.cylinder('wheel_disc_%d' % i, (x, -0.63, 0.33), 0.22, 0.02, mat_steel, seg=64)
    disc.rotation_euler = (math.radians(90), 0, 0)

# --- lights: a large softbox above, a strip to the right, a dark studio -------------------------
C.area_light('key', (0.4, -0.6, 3.4), (0.2, 0.0, 0.9), 3.0, 1.6, 450.0, (1.0, 0.97, 0.92))
C.area_light('strip', (1.8, -2.6, 1.2), (0.0, 0.0, 0.7), 0.25, 2.0, 160.0, (0.92, 0.95, 1.0))
# a low softbox in front, shining into the cabin through the windscreen and the near window
C.area_light('front', (3.2, -1.6, 1.6), (-0.2, 0.0, 0.95), 1.2, 0.8, 260.0, (1.0, 0.96, 0.9))
C.world_color((0.8, 0.85, 0.9), 0.03)

C.camera((3.6, -3.3, 1.7), (0.0, 0.0, 0.85), 30.0)
C.render(args)
