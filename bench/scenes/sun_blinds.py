"""sun_blinds: hard, thin sun shadows on a textured floor.  A room lit by a sun lamp (0.5 deg,
45 deg up) through a wide, low-silled window (5 m x 2.1 m, from 25 cm above the floor) fitted
with a horizontal venetian blind: 44 slats, 5 cm deep, 4.5 cm pitch, sloping down into the
room by 30 deg (open, but not wide open).  The sun, shining in past the slats, lays a pattern
of thin parallel light and shadow stripes (about 1-3 px each at 384x384; sharp by the window,
softer further in, where the penumbra grows) across a finely grained oak plank floor (90 x 11
cm planks running across the stripes, satin, roughness 0.35) and up the back wall, and the
blind's 3 mm ladder cords add faint lines across them.  In the sun stand a wooden chair with
2.5 cm legs and 1.5 cm spindles (thin leg shadows over the stripes), a clear glass sphere
(Principled, transmission 1; it focuses a small caustic into its shadow) and a small standing
mirror (Principled, metallic 1, roughness 0).  The sky (constant world colour, ~1.4-2.9
linear) is seen only between the slats (~8% of the pixels); the rest of the room, a bookcase
in the far corner included, is lit only indirectly.

The camera looks along the window wall, so that the stripes, which run parallel to the
window, recede into the frame with their spacing across it.  main() takes the sun's elevation
and azimuth and the slats' tilt; sun_blinds_low.py is the same room in a lower sun.

blender -b --factory-startup -noaudio --python sun_blinds.py -- --spp 16 --seed 1 --out x.exr
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def main(sun_elevation=45.0, sun_azimuth=25.0, sun_colour=(1.0, 0.94, 0.84), slat_tilt=30.0):
    """Build and render the room.  sun_elevation: degrees above the horizon; sun_azimuth: degrees
    from +x (straight in through the window, which faces -x) towards +y (the back wall);
    slat_tilt: degrees the slats slope down into the room.  The variants (sun_blinds_low.py)
    change these."""
    args = C.start()

    # --- materials -------------------------------------------------------------------------
    # floor: 90 x 11 cm oak planks running along x (across the stripes), staggered, fine
    # distorted grain, per-plank tone, dark 2 mm joints; satin finish (roughness 0.35)
    m = C.Mat('floor_oak', 1)
    uv = m.uv2('xy', 1.0)                           # planks run along x
    br = m.n('ShaderNodeTexBrick', {'Vector': uv, 'Scale': 1.0, 'Color1': (1.0, 1.0, 1.0),
                                    'Color2': (0.62, 0.62, 0.62), 'Mortar': (0.0, 0.0, 0.0),
                                    'Mortar Size': 0.002, 'Mortar Smooth': 0.0, 'Bias': 0.0},
             offset=0.41, offset_frequency=1, squash=1.0)
    br.inputs['Brick Width'].default_value = 0.9
    br.inputs['Row Height'].default_value = 0.11
    grain = m.n('ShaderNodeTexWave', {'Vector': m.coord('Object'), 'Scale': 14.0, 'Distortion': 6.0,
                                      'Detail': 3.0, 'Detail Scale': 2.0}, wave_type='BANDS', bands_direction='Y')
    wood = m.ramp(grain.outputs['Fac'], [(0.0, (0.36, 0.20, 0.08)), (0.55, (0.62, 0.40, 0.19)),
                                         (1.0, (0.45, 0.27, 0.11))])
    col = m.mix(1.0, wood, br.outputs['Color'], 'MULTIPLY')
    col = m.mix(br.outputs['Fac'], col, (0.04, 0.025, 0.012))
    mat_floor = m.out(m.principled(base=col, rough=0.35, spec=0.5))

    # walls: off-white plaster with low-contrast noise; plain ceiling
    mat_wall = C.plaster_mat('walls_plaster', 2, (0.64, 0.61, 0.56), (0.80, 0.77, 0.71))
    mat_ceil = C.diffuse_mat('ceiling', 3, (0.78, 0.78, 0.76))

    # window frame, skirting, blind slats and rails: white paint / lacquered aluminium
    m = C.Mat('white_paint', 4)
    mat_paint = m.out(m.principled(base=(0.80, 0.80, 0.78), rough=0.35, spec=0.5))
    m = C.Mat('blind_slats', 5)
    mat_slat = m.out(m.principled(base=(0.78, 0.77, 0.72), rough=0.3, spec=0.5))
    mat_cord = C.diffuse_mat('blind_cords', 6, (0.70, 0.68, 0.62))

    # chair: dark stained beech, satin
    m = C.Mat('chair_wood', 7)
    wv = m.n('ShaderNodeTexWave', {'Vector': m.coord('Object'), 'Scale': 20.0, 'Distortion': 3.0,
                                   'Detail': 2.0}, wave_type='BANDS', bands_direction='Z')
    mat_chair = m.out(m.principled(base=m.ramp(wv.outputs['Fac'], [(0.0, (0.10, 0.05, 0.025)),
                                                                   (1.0, (0.20, 0.11, 0.05))]),
                                   rough=0.4, spec=0.5))

    # glass (Principled, full transmission) and mirror (Principled, metallic, roughness 0)
    m = C.Mat('glass_clear', 8)
    mat_glass = m.out(m.principled(base=(1.0, 1.0, 1.0), rough=0.0, ior=1.45, trans=1.0))
    m = C.Mat('mirror', 9)
    mat_mirror = m.out(m.principled(base=(0.92, 0.92, 0.92), rough=0.0, metal=1.0))
    m = C.Mat('mirror_frame', 10)
    mat_mframe = m.out(m.principled(base=(0.55, 0.40, 0.16), rough=0.3, metal=1.0))

    # books on the shelves of a bookcase against the back wall (out of the sun): spines in blue,
    # beige and red, from a constant-interpolated ramp over noise along x
    m = C.Mat('books', 11)
    sep = m.n('ShaderNodeSeparateXYZ', {0: m.coord('Object')})
    vx = m.n('ShaderNodeCombineXYZ', {0: m.math('MULTIPLY', sep.outputs[0], 30.0), 1: 0.5, 2: 0.5}).outputs[0]
    band = m.n('ShaderNodeTexNoise', {'Vector': vx, 'Scale': 1.0, 'Detail': 0.0})
    mat_books = m.out(m.diffuse(m.ramp(band.outputs['Fac'], [(0.3, (0.10, 0.14, 0.35)), (0.5, (0.55, 0.50, 0.40)),
                                                              (0.7, (0.45, 0.08, 0.06))], 'CONSTANT')))

    # --- room: x in [-3,3], y in [-3,3], z in [0,2.7]; 15 cm walls -------------------------
    X, Y, H, T = 3.0, 3.0, 2.7, 0.15
    C.box('floor', (-X - T, -Y - T, -T), (X + T, Y + T, 0), mat_floor)
    C.box('ceiling', (-X - T, -Y - T, H), (X + T, Y + T, H + T), mat_ceil)
    C.box('back_wall', (-X, Y, 0), (X, Y + T, H), mat_wall)
    C.box('front_wall', (-X, -Y - T, 0), (X, -Y, H), mat_wall)
    C.box('right_wall', (X, -Y, 0), (X + T, Y, H), mat_wall)
    # left wall with a wide, low-silled window opening y in [-2.2, 2.85], z in [0.25, 2.35]
    wy0, wy1, wz0, wz1 = -2.2, 2.85, 0.25, 2.35
    C.boxes('left_wall', [((-X - T, -Y, 0), (-X, Y, wz0)), ((-X - T, -Y, wz1), (-X, Y, H)),
                          ((-X - T, -Y, wz0), (-X, wy0, wz1)), ((-X - T, wy1, wz0), (-X, Y, wz1))], mat_wall)
    # window frame (4 cm, outer part of the reveal) and an inner sill
    fx0, fx1, b = -X - T, -X - T + 0.05, 0.04
    C.boxes('window_frame', [((fx0, wy0, wz0), (fx1, wy1, wz0 + b)), ((fx0, wy0, wz1 - b), (fx1, wy1, wz1)),
                             ((fx0, wy0, wz0), (fx1, wy0 + b, wz1)), ((fx0, wy1 - b, wz0), (fx1, wy1, wz1)),
                             ((-X - 0.02, wy0 - 0.04, wz0 - 0.025), (-X + 0.05, wy1 + 0.04, wz0 + 0.005))], mat_paint)
    # skirting boards along the back and right walls
    C.boxes('skirting', [((-X, Y - 0.02, 0), (X, Y, 0.10)), ((X - 0.02, -Y, 0), (X, Y, 0.10))], mat_paint)

    # --- venetian blind in the window reveal: slats along y, 5 cm deep, 3 mm thick, 4.5 cm pitch,
    # sloping down into the room by slat_tilt; head rail at the top, bottom rail, ladder cords ---
    sw, st, pitch = 0.05, 0.003, 0.045
    bx = -X - 0.05                                   # x of the slats' centres (inside the reveal)
    by0, by1 = wy0 + 0.005, wy1 - 0.005
    ca, sa = math.cos(math.radians(slat_tilt)), math.sin(math.radians(slat_tilt))
    V, F = [], []
    z = wz1 - 0.09
    while z > wz0 + 0.05:
        # cross-section: a thin rectangle sw x st, rotated about y (room-side edge lower)
        sec = [(-sw / 2, -st / 2), (sw / 2, -st / 2), (sw / 2, st / 2), (-sw / 2, st / 2)]
        sec = [(bx + u * ca + w * sa, z - u * sa + w * ca) for u, w in sec]
        base = len(V)
        V += [(x_, by0, z_) for x_, z_ in sec] + [(x_, by1, z_) for x_, z_ in sec]
        F += [(base + i, base + (i + 1) % 4, base + 4 + (i + 1) % 4, base + 4 + i) for i in range(4)]
        F += [(base + 3, base + 2, base + 1, base), (base + 4, base + 5, base + 6, base + 7)]
        z -= pitch
    C.mesh_obj('blind_slats', V, F, mat_slat)
    C.boxes('blind_rails', [((bx - 0.03, by0, wz1 - 0.06), (bx + 0.03, by1, wz1)),
                            ((bx - 0.025, by0, wz0 + 0.01), (bx + 0.025, by1, wz0 + 0.03))], mat_slat)
    # ladder cords: 3 mm, in front of and behind the slats, at three places along the blind
    cords = []
    for yc in (wy0 + 0.25, (wy0 + wy1) / 2, wy1 - 0.25):
        for xc in (bx - sw / 2 * ca - 0.002, bx + sw / 2 * ca + 0.002):
            cords.append(((xc - 0.0015, yc - 0.0015, wz0 + 0.03), (xc + 0.0015, yc + 0.0015, wz1 - 0.06)))
    C.boxes('blind_cords', cords, mat_cord)

    # --- furniture in the sun ----------------------------------------------------------------
    # Objects standing on the floor start E = 0.5 mm above it (no coplanar faces, so that renders
    # do not depend on the BVH's ordering of ties)
    E = 0.0005
    # chair: 42 x 42 cm seat at 45 cm, 2.5 cm legs, backrest (on the +y side) with a top rail
    # and four 1.5 cm spindles, stretchers 25 cm up.  The seat overhangs the legs by 2 mm and
    # the rail and stretchers stop 2 mm inside them, so that no two faces are coplanar
    cx, cy, s, lg = -2.05, 0.55, 0.21, 0.0125
    c = s - 0.002 - lg                               # legs' centres from the seat's centre
    parts = [((cx - s, cy - s, 0.43), (cx + s, cy + s, 0.46))]
    for sx in (-1, 1):
        for sy in (-1, 1):
            top = 0.94 if sy > 0 else 0.4295
            parts.append(((cx + sx * c - lg, cy + sy * c - lg, E), (cx + sx * c + lg, cy + sy * c + lg, top)))
    parts.append(((cx - c, cy + c - lg + 0.002, 0.85), (cx + c, cy + c + lg - 0.002, 0.93)))     # top rail
    for k in range(4):
        xs = cx - c + 2 * c * (k + 1) / 5
        parts.append(((xs - 0.0075, cy + c - 0.0075, 0.455), (xs + 0.0075, cy + c + 0.0075, 0.85)))
    for sx in (-1, 1):                                                               # stretchers
        parts.append(((cx + sx * c - 0.008, cy - c, 0.24), (cx + sx * c + 0.008, cy + c, 0.26)))
    C.boxes('chair', parts, mat_chair)

    # clear glass sphere (r 10 cm) on the floor nearer the camera, in the sun
    C.sphere('glass_sphere', (-2.3, -0.9, 0.10 + E), 0.10, mat_glass, seg=96, rings=48)

    # small standing mirror (30 x 40 cm, thin brass frame) beyond the chair, leaning back 10 deg,
    # facing the camera and turned a little towards the window; it reflects the blind and the sky
    mw, mh = 0.30, 0.40
    mir = C.quad('mirror', (-mw / 2, 0, 0.03), (mw / 2, 0, 0.03), (mw / 2, 0, 0.03 + mh), (-mw / 2, 0, 0.03 + mh),
                 mat_mirror)
    frm = C.boxes('mirror_frame', [((-mw / 2 - 0.015, 0.001, E), (mw / 2 + 0.015, 0.025, 0.03)),
                                   ((-mw / 2 - 0.015, 0.001, 0.03 + mh), (mw / 2 + 0.015, 0.025, 0.045 + mh)),
                                   ((-mw / 2 - 0.015, 0.001, 0.03), (-mw / 2, 0.025, 0.03 + mh)),
                                   ((mw / 2, 0.001, 0.03), (mw / 2 + 0.015, 0.025, 0.03 + mh))], mat_mframe)
    for ob in (mir, frm):
        ob.location = (-1.5, 1.5, 0.0)
        ob.rotation_euler = (math.radians(-10), 0, math.radians(-15))

    # bookcase against the back wall, x in [-1.1, 0.1], right of the sun patch (lit indirectly)
    bk0, bk1 = -1.1, 0.1
    bd = Y - 0.35                                    # front of the bookcase
    C.boxes('bookcase', [((bk0, bd, 0.0), (bk1, Y - 0.01, 0.05)), ((bk0, bd, 1.75), (bk1, Y - 0.01, 1.8)),
                         ((bk0, bd, 0.0), (bk0 + 0.03, Y - 0.01, 1.8)), ((bk1 - 0.03, bd, 0.0), (bk1, Y - 0.01, 1.8)),
                         ((bk0, bd, 0.6), (bk1, Y - 0.01, 0.63)), ((bk0, bd, 1.18), (bk1, Y - 0.01, 1.21))], mat_chair)
    C.boxes('books', [((bk0 + 0.05, Y - 0.30, zb + E), (bk1 - 0.08, Y - 0.05, zb + 0.26)) for zb in (0.05, 0.63, 1.21)],
            mat_books)

    # --- light: sun through the blind + blue sky seen between the slats ----------------------
    e, a = math.radians(sun_elevation), math.radians(sun_azimuth)
    C.sun_light('sun', (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), -math.sin(e)), 10.0, 0.5, sun_colour)
    C.world_color((0.45, 0.62, 0.95), 3.0)

    C.camera((-0.8, -2.8, 1.6), (-1.95, 0.6, 0.1), 50.0)
    C.render(args)


if __name__ == '__main__':
    main()
