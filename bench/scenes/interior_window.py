"""interior_window: a closed room lit by a sun lamp (0.5 deg) through a window with mullions
and a transom.  The sun patch, cut into hard-edged panes by the 6 cm mullions, falls on a
glossy wooden plank floor (Principled, roughness 0.15) and runs up the back wall; the
blue sky (constant world colour, ~1.4-2.9 linear) is seen through the window (~5-10% of the
frame).  A framed picture with a fine 2.5 cm checker hangs on the back wall, a low cabinet
stands under it; the other walls and the ceiling are lit only indirectly.

blender -b --factory-startup -noaudio --python interior_window.py -- --spp 16 --seed 1 --out x.exr
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

def main(sun_direction=(0.8, 0.5, -0.35), sun_colour=(1.0, 0.93, 0.82), floor_roughness=0.15):
    """Build and render the room; the variants (interior_low_sun.py) change the sun and the floor."""
    args = C.start()

    # --- materials -------------------------------------------------------------------------
    # floor: 1.2 m x 15 cm planks (staggered), wood grain from a distorted wave texture per plank,
    # per-plank tone, dark 3 mm joints; glossy varnish (Principled roughness 0.15)
    m = C.Mat('floor_wood_glossy', 1)
    uv = m.uv2('yx', 1.0)                           # planks run along y
    br = m.n('ShaderNodeTexBrick', {'Vector': uv, 'Scale': 1.0, 'Color1': (1.0, 1.0, 1.0),
                                    'Color2': (0.55, 0.55, 0.55), 'Mortar': (0.0, 0.0, 0.0),
                                    'Mortar Size': 0.003, 'Mortar Smooth': 0.0, 'Bias': 0.0},
             offset=0.37, offset_frequency=1, squash=1.0)
    br.inputs['Brick Width'].default_value = 1.2
    br.inputs['Row Height'].default_value = 0.15
    grain = m.n('ShaderNodeTexWave', {'Vector': m.coord('Object'), 'Scale': 9.0, 'Distortion': 5.0,
                                      'Detail': 2.0, 'Detail Scale': 1.5}, wave_type='BANDS', bands_direction='X')
    wood = m.ramp(grain.outputs['Fac'], [(0.0, (0.30, 0.14, 0.05)), (0.6, (0.50, 0.27, 0.11)),
                                         (1.0, (0.38, 0.19, 0.07))])
    col = m.mix(1.0, wood, br.outputs['Color'], 'MULTIPLY')
    col = m.mix(br.outputs['Fac'], col, (0.03, 0.02, 0.01))
    mat_floor = m.out(m.principled(base=col, rough=floor_roughness, spec=0.5))

    # walls: off-white plaster with low-contrast noise
    mat_wall = C.plaster_mat('walls_plaster', 2, (0.62, 0.60, 0.56), (0.80, 0.78, 0.73))
    mat_ceil = C.diffuse_mat('ceiling', 3, (0.78, 0.78, 0.76))

    # skirting boards / window frame: white paint, slightly glossy
    m = C.Mat('white_paint', 4)
    mat_paint = m.out(m.principled(base=(0.80, 0.80, 0.78), rough=0.35, spec=0.5))

    # picture: fine checker (2.5 cm squares) on the canvas, dark wooden frame
    m = C.Mat('picture_checker', 5)
    ck = m.n('ShaderNodeTexChecker', {'Vector': m.uv2('xz', 1.0), 'Scale': 40.0,
                                      'Color1': (0.80, 0.74, 0.55), 'Color2': (0.08, 0.12, 0.30)})
    mat_pic = m.out(m.diffuse(ck.outputs['Color']))
    m = C.Mat('picture_frame', 6)
    mat_frame = m.out(m.principled(base=(0.10, 0.05, 0.02), rough=0.3, spec=0.5))

    # cabinet: painted green, satin
    m = C.Mat('cabinet', 7)
    mat_cab = m.out(m.principled(base=(0.12, 0.28, 0.20), rough=0.4, spec=0.5))

    # --- room: x in [-3,3], y in [-3,3], z in [0,2.8]; 15 cm walls -------------------------
    X, Y, H, T = 3.0, 3.0, 2.8, 0.15
    C.box('floor', (-X - T, -Y - T, -T), (X + T, Y + T, 0), mat_floor)
    C.box('ceiling', (-X - T, -Y - T, H), (X + T, Y + T, H + T), mat_ceil)
    C.box('back_wall', (-X, Y, 0), (X, Y + T, H), mat_wall)
    C.box('front_wall', (-X, -Y - T, 0), (X, -Y, H), mat_wall)
    C.box('right_wall', (X, -Y, 0), (X + T, Y, H), mat_wall)
    # left wall with a window opening y in [-1.5, 1.5], z in [0.7, 2.5]
    wy0, wy1, wz0, wz1 = -1.5, 1.5, 0.7, 2.5
    C.boxes('left_wall', [((-X - T, -Y, 0), (-X, Y, wz0)), ((-X - T, -Y, wz1), (-X, Y, H)),
                          ((-X - T, -Y, wz0), (-X, wy0, wz1)), ((-X - T, wy1, wz0), (-X, Y, wz1))], mat_wall)
    # window: 6 cm frame, two 6 cm mullions, one transom (no glass: the sky is seen directly)
    fx0, fx1, b = -X - 0.10, -X - 0.04, 0.06
    win = [((fx0, wy0, wz0), (fx1, wy1, wz0 + b)), ((fx0, wy0, wz1 - b), (fx1, wy1, wz1)),
           ((fx0, wy0, wz0), (fx1, wy0 + b, wz1)), ((fx0, wy1 - b, wz0), (fx1, wy1, wz1))]
    for ym in (-0.5, 0.5):
        win.append(((fx0, ym - b / 2, wz0), (fx1, ym + b / 2, wz1)))
    win.append(((fx0, wy0, 1.95 - b / 2), (fx1, wy1, 1.95 + b / 2)))
    win.append(((-X - 0.02, wy0 - 0.05, wz0 - 0.03), (-X + 0.08, wy1 + 0.05, wz0)))      # sill
    C.boxes('window_frame', win, mat_paint)
    # skirting boards along the back and right walls
    C.boxes('skirting', [((-X, Y - 0.02, 0), (X, Y, 0.10)), ((X - 0.02, -Y, 0), (X, Y, 0.10))], mat_paint)

    # picture on the back wall, x in [-2.4, -1.0], z in [1.05, 2.05] (out of the sun)
    px0, px1 = -2.4, -1.0
    C.boxes('picture_frame', [((px0 - 0.05, Y - 0.04, 1.00), (px1 + 0.05, Y, 1.05)),
                              ((px0 - 0.05, Y - 0.04, 2.05), (px1 + 0.05, Y, 2.10)),
                              ((px0 - 0.05, Y - 0.04, 1.05), (px0, Y, 2.05)), ((px1, Y - 0.04, 1.05), (px1 + 0.05, Y, 2.05))],
            mat_frame)
    C.quad('picture', (px0, Y - 0.02, 1.05), (px1, Y - 0.02, 1.05), (px1, Y - 0.02, 2.05), (px0, Y - 0.02, 2.05), mat_pic)
    # low cabinet under the picture
    C.boxes('cabinet', [((px0 - 0.2, Y - 0.45, 0.08), (px1 + 0.2, Y - 0.01, 0.75)),
                        ((px0 - 0.15, Y - 0.40, 0.0), (px1 + 0.15, Y - 0.05, 0.08))], mat_cab)

    # --- light: sun through the window + blue sky seen through the opening ------------------
    C.sun_light('sun', sun_direction, 10.0, 0.5, sun_colour)
    C.world_color((0.45, 0.62, 0.95), 3.0)

    C.camera((2.4, -2.6, 1.55), (-1.2, 1.8, 0.9), 60.0)
    C.render(args)


if __name__ == '__main__':
    main()
