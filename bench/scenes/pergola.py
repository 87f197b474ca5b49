"""pergola: an outdoor shot of a stone-tiled patio under a timber pergola in a high sun lamp
(60 deg elevation, 0.5 deg, hard shadows) with a matching Nishita sky (no sun disc, strength
0.4, so that the sun is about 3x the sky on the patio) seen above the garden in the top ~15%
of the frame, partly through the pergola's roof.  The open roof, 4 x 8 cm rafters every 40 cm
under 3 x 2.5 cm laths every 22 cm, 2.6-2.7 m up, lays a grid of thin shadow lines (about 1-3 px
at 384x384 in the middle distance, up to ~5 px in the foreground; at 2.6 m the sun's penumbra
is already ~2.5 cm, as wide as a lath) over the patio's stone tiles (40 cm, laid diagonally,
7 mm joints, per-tile tone, grain and speckles).  The 9 cm posts, a slatted garden chair and a
small round table with 1.6 cm metal legs add more thin shadows, and a clear glass vase
(Principled, transmission 1) stands on the table in the sun.  Lawn and a clipped hedge behind.

The camera, 2.2 m up, looks diagonally across the patio, so that neither set of grid lines
(nor the tile joints) runs along the pixel rows.  main() takes the sun's elevation and azimuth.

blender -b --factory-startup -noaudio --python pergola.py -- --spp 16 --seed 1 --out x.exr
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def lathe(name, profile, mat, loc, seg=48):
    """Solid of revolution about z from a closed (r, z) profile whose first and last points lie
    on the axis (r = 0), e.g. a hollow vase: up the outside, over the rim, down the inside."""
    V, F, rings = [], [], []
    for r, z in profile:
        if r == 0.0:
            rings.append([len(V)])
            V.append((0.0, 0.0, z))
        else:
            rings.append(list(range(len(V), len(V) + seg)))
            V += [(r * math.cos(2 * math.pi * k / seg), r * math.sin(2 * math.pi * k / seg), z) for k in range(seg)]
    for a, b in zip(rings[:-1], rings[1:]):
        for k in range(seg):
            k1 = (k + 1) % seg
            if len(a) == 1:
                F.append((a[0], b[k1], b[k]))
            elif len(b) == 1:
                F.append((a[k], a[k1], b[0]))
            else:
                F.append((a[k], a[k1], b[k1], b[k]))
    return C.mesh_obj(name, V, F, mat, smooth=True, location=loc)


def main(sun_elevation=60.0, sun_azimuth=200.0, sun_colour=(1.0, 0.95, 0.88)):
    """Build and render the patio.  sun_elevation: degrees above the horizon; sun_azimuth: the
    direction the sunlight travels, degrees from +x towards +y (200: towards -x and a little
    towards the camera, from a sun above the frame, in front and to the right, so that the
    shadow grid lies left of the pergola's footprint and reaches the foreground; near -x the
    rafters' depth hardly widens their shadows)."""
    args = C.start()

    # --- materials -------------------------------------------------------------------------
    # patio: 40 cm square sandstone tiles (brick texture, no offset) laid diagonally, 7 mm grey
    # joints, per-tile tone, fine grain noise and a few darker speckles
    m = C.Mat('patio_tiles', 1)
    sep = m.n('ShaderNodeSeparateXYZ', {0: m.coord('Object')})
    d45 = math.sqrt(0.5)                            # laid diagonally: u, v = (x +- y) / sqrt 2
    uv = m.n('ShaderNodeCombineXYZ', {0: m.math('MULTIPLY', m.math('ADD', sep.outputs[0], sep.outputs[1]), d45),
                                      1: m.math('MULTIPLY', m.math('SUBTRACT', sep.outputs[0], sep.outputs[1]), d45),
                                      2: 0.5}).outputs[0]
    br = m.n('ShaderNodeTexBrick', {'Vector': uv, 'Scale': 1.0, 'Color1': (0.50, 0.44, 0.35),
                                    'Color2': (0.33, 0.30, 0.26), 'Mortar': (0.16, 0.16, 0.15),
                                    'Mortar Size': 0.0035, 'Mortar Smooth': 0.0, 'Bias': 0.0},
             offset=0.0, offset_frequency=1, squash=1.0)
    br.inputs['Brick Width'].default_value = 0.4
    br.inputs['Row Height'].default_value = 0.4
    nz = m.n('ShaderNodeTexNoise', {'Vector': uv, 'Scale': 60.0, 'Detail': 6.0, 'Roughness': 0.6})
    grain = m.ramp(nz.outputs['Fac'], [(0.3, (0.70, 0.70, 0.70)), (0.7, (1.0, 1.0, 1.0))])
    vo = m.n('ShaderNodeTexVoronoi', {'Vector': uv, 'Scale': 45.0})
    speck = m.ramp(vo.outputs['Distance'], [(0.0, (0.35, 0.33, 0.30)), (0.12, (1.0, 1.0, 1.0))], 'CONSTANT')
    col = m.mix(1.0, br.outputs['Color'], grain, 'MULTIPLY')
    col = m.mix(br.outputs['Fac'], m.mix(1.0, col, speck, 'MULTIPLY'), (0.16, 0.16, 0.15))
    mat_patio = m.out(m.principled(base=col, rough=0.7, spec=0.4))

    # lawn: two noise scales over a green ramp (as exterior_foliage)
    m = C.Mat('lawn', 2)
    uv = m.uv2('xy', 1.0)
    nz = m.n('ShaderNodeTexNoise', {'Vector': uv, 'Scale': 3.0, 'Detail': 4.0, 'Roughness': 0.6})
    nf = m.n('ShaderNodeTexNoise', {'Vector': uv, 'Scale': 90.0, 'Detail': 2.0})
    g = m.ramp(nz.outputs['Fac'], [(0.3, (0.06, 0.13, 0.03)), (0.7, (0.20, 0.26, 0.06))])
    mat_lawn = m.out(m.diffuse(m.mix(0.6, m.mix(0.5, g, nf.outputs['Fac'], 'MULTIPLY'), g)))

    # hedge: dark green, blotchy
    m = C.Mat('hedge', 3)
    nz = m.n('ShaderNodeTexNoise', {'Vector': m.coord('Object'), 'Scale': 12.0, 'Detail': 5.0})
    mat_hedge = m.out(m.diffuse(m.ramp(nz.outputs['Fac'], [(0.35, (0.02, 0.06, 0.015)), (0.65, (0.09, 0.16, 0.04))])))

    # pergola timber: weathered larch, grain along the member (bands across all three axes'
    # object coordinates at a low scale look like grain on every face)
    m = C.Mat('pergola_timber', 4)
    wv = m.n('ShaderNodeTexWave', {'Vector': m.coord('Object'), 'Scale': 4.0, 'Distortion': 8.0,
                                   'Detail': 3.0}, wave_type='RINGS', rings_direction='SPHERICAL')
    mat_timber = m.out(m.principled(base=m.ramp(wv.outputs['Fac'], [(0.0, (0.30, 0.22, 0.14)),
                                                                    (1.0, (0.48, 0.37, 0.25))]),
                                    rough=0.6, spec=0.4))

    # garden furniture: dark green painted metal frames, teak slats, and the glass vase
    m = C.Mat('painted_metal', 5)
    mat_metal = m.out(m.principled(base=(0.03, 0.09, 0.05), rough=0.35, metal=0.5, spec=0.5))
    m = C.Mat('teak', 6)
    wv = m.n('ShaderNodeTexWave', {'Vector': m.coord('Object'), 'Scale': 25.0, 'Distortion': 4.0,
                                   'Detail': 2.0}, wave_type='BANDS', bands_direction='Y')
    mat_teak = m.out(m.principled(base=m.ramp(wv.outputs['Fac'], [(0.0, (0.28, 0.15, 0.07)),
                                                                  (1.0, (0.45, 0.27, 0.13))]),
                                  rough=0.45, spec=0.5))
    m = C.Mat('glass_clear', 7)
    mat_glass = m.out(m.principled(base=(1.0, 1.0, 1.0), rough=0.0, ior=1.45, trans=1.0))

    # --- ground: lawn everywhere, the patio a slab 2 cm above it; hedge beyond -----------------
    C.quad('lawn', (-300, -300, 0), (300, -300, 0), (300, 300, 0), (-300, 300, 0), mat_lawn)
    C.box('patio', (-4.2, -3.0, 0.0), (4.2, 7.4, 0.02), mat_patio)
    C.boxes('hedge', [((-12.0, 10.5, 0.0), (12.0, 11.6, 1.7)), ((7.0, -6.0, 0.0), (8.1, 10.5, 1.7))], mat_hedge)

    # --- pergola over x in [-2.6, 2.6], y in [0.6, 5.4]; everything from the patio top F ------
    F = 0.02
    E = 0.0005                  # objects on the patio start 0.5 mm above it (no coplanar faces)
    parts = []
    px, py = (-2.55, 2.55), (0.65, 3.0, 5.35)
    for x in px:                                                              # 9 cm posts
        for y in py:
            parts.append(((x - 0.045, y - 0.045, F + E), (x + 0.045, y + 0.045, F + 2.40)))
    for x in px:                                                              # beams along y
        parts.append(((x - 0.035, 0.3, F + 2.40), (x + 0.035, 5.7, F + 2.56)))
    y = 0.45
    while y < 5.6:                                                            # rafters along x
        parts.append(((-2.9, y - 0.02, F + 2.56), (2.9, y + 0.02, F + 2.64)))
        y += 0.40
    x = -2.75
    while x < 2.8:                                                            # laths along y
        parts.append(((x - 0.015, 0.35, F + 2.64), (x + 0.015, 5.65, F + 2.665)))
        x += 0.22
    C.boxes('pergola', parts, mat_timber)

    # --- garden chair: 1.6 cm tube legs, teak seat of five 5 cm slats, back of three slats ----
    cx, cy, s = 0.6, 1.8, 0.21
    C.boxes('chair_slats', [((cx - s, cy - s + k * 0.088, F + 0.44), (cx + s, cy - s + k * 0.088 + 0.05, F + 0.46))
                            for k in range(5)] +
            [((cx - s, cy + s - 0.01, F + 0.58 + k * 0.1), (cx + s, cy + s + 0.005, F + 0.64 + k * 0.1))
             for k in range(3)], mat_teak)
    for sx in (-1, 1):
        for sy in (-1, 1):
            h = 0.86 if sy > 0 else 0.44
            C.cylinder('chair_leg', (cx + sx * (s - 0.01), cy + sy * (s - 0.01), F + E), 0.008, h, mat_metal, seg=12)
    C.boxes('chair_frame', [((cx - s, cy - s, F + 0.425), (cx + s, cy - s + 0.012, F + 0.44)),
                            ((cx - s, cy + s - 0.012, F + 0.425), (cx + s, cy + s, F + 0.44)),
                            ((cx - s, cy - s, F + 0.2), (cx - s + 0.012, cy + s, F + 0.212)),
                            ((cx + s - 0.012, cy - s, F + 0.2), (cx + s, cy + s, F + 0.212))], mat_metal)

    # --- small table: 60 cm round teak top at 72 cm, three 1.6 cm legs, glass vase on it -------
    tx, ty = -1.1, 1.5
    C.cylinder('table_top', (tx, ty, F + 0.70), 0.30, 0.025, mat_teak, seg=64)
    for k in range(3):
        t = 2 * math.pi * k / 3 + 0.3
        C.cylinder('table_leg', (tx + 0.2 * math.cos(t), ty + 0.2 * math.sin(t), F + E), 0.008, 0.70, mat_metal,
                   seg=12)
    C.torus('table_ring', (tx, ty, F + 0.30), 0.2, 0.006, mat_metal, nu=48, nv=8)
    # hollow vase, 35 cm tall: up the outside, over the rim, down the inside (6-7 mm walls, 2 cm base)
    lathe('glass_vase', [(0.000, 0.000), (0.063, 0.000), (0.087, 0.056), (0.095, 0.140), (0.077, 0.238), (0.056, 0.308),
                         (0.062, 0.350), (0.056, 0.350), (0.050, 0.308), (0.070, 0.238), (0.088, 0.140),
                         (0.080, 0.056), (0.056, 0.020), (0.000, 0.020)],
          mat_glass, (tx - 0.05, ty + 0.05, F + 0.725 + E), seg=64)

    # --- light: high sun (hard shadows) + matching Nishita sky --------------------------------
    e, a = math.radians(sun_elevation), math.radians(sun_azimuth)
    sun_dir = (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), -math.sin(e))   # travel direction
    C.sun_light('sun', sun_dir, 5.0, 0.5, sun_colour)
    rot = math.degrees(math.atan2(-sun_dir[1], -sun_dir[0])) - 90.0   # Nishita sun azimuth = rotation + 90 deg
    C.world_sky(0.4, sun_elevation, rot % 360.0, sun_disc=False)

    C.camera((-4.4, -2.2, 2.2), (0.2, 3.5, 0.0), 55.0)
    C.render(args)


if __name__ == '__main__':
    main()
