"""light_groups_motion: issue 46's scene. A checker floor, a box and a torus moving fast to the
right (motion blur over the whole shutter) over transparent film, lit by three light groups:
`key` (a rectangular area light, hard-edged shadows), `fill` (a point light from the other
side) and `sky` (the world, a constant pale blue). The film is transparent, so the alpha is
fractional at the blurred edges and 0 where the world is seen.

blender -b --factory-startup -noaudio --python light_groups_motion.py -- --spp 16 --seed 1 --out x.exr
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

args = C.start()

m = C.Mat('checker', 1)
chk = m.n('ShaderNodeTexChecker', {'Vector': m.coord('Object'), 'Color1': (0.75, 0.72, 0.65, 1),
                                   'Color2': (0.12, 0.14, 0.2, 1), 'Scale': 6.0})
mat_floor = m.out(m.diffuse(chk.outputs['Color']))
mat_box = C.diffuse_mat('box_red', 2, (0.7, 0.15, 0.1))
mat_torus = C.diffuse_mat('torus_green', 3, (0.2, 0.6, 0.25))

C.quad('floor', (-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0), mat_floor)
box = C.box('box', (-0.35, -0.35, 0.0), (0.35, 0.35, 0.7), mat_box)
tor = C.torus('torus', (0.6, 0.9, 0.35), 0.35, 0.12, mat_torus)

# Motion: both move 0.6 units to the right over the shutter around frame 1.
scene = bpy.context.scene
for ob, dx in ((box, -0.9), (tor, 0.3)):
    ob.location.x = dx - 0.3
    ob.keyframe_insert('location', frame=0)
    ob.location.x = dx + 0.3
    ob.keyframe_insert('location', frame=2)
    for fc in ob.animation_data.action.fcurves:
        for kp in fc.keyframe_points:
            kp.interpolation = 'LINEAR'
scene.frame_set(1)

key = C.area_light('key', (-2.0, -1.5, 3.0), (0, 0, 0), 0.4, 0.4, 400.0, (1.0, 0.92, 0.8))
fill = bpy.data.lights.new('fill', 'POINT')
fill.energy, fill.color, fill.shadow_soft_size = 150.0, (0.7, 0.8, 1.0), 0.3
fill_ob = bpy.data.objects.new('fill', fill)
scene.collection.objects.link(fill_ob)
fill_ob.location = (2.5, 1.0, 2.0)
world = C.world_color((0.55, 0.65, 0.85), 0.6)
C.camera((0.0, -4.2, 0.55), (0.0, 0.3, 0.45), 40.0)

C.configure(args)
scene.render.film_transparent = True
scene.render.use_motion_blur = True
scene.render.motion_blur_shutter = 1.0
vl = scene.view_layers[0]
for name in ('key', 'fill', 'sky'):
    vl.lightgroups.add(name=name)
key.lightgroup = 'key'
fill_ob.lightgroup = 'fill'
world.lightgroup = 'sky'
if args.save_blend:
    bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save_blend))
bpy.ops.render.render(write_still=True)
