"""interior_low_sun: interior_window's room in a low, warm afternoon sun (elevation about 12
degrees instead of 20, shining more squarely through the window): the sun patch, cut by the
mullion and transom shadows, lies on the floor in the foreground, nearer the camera, and
reaches no wall; the plank floor is satin (roughness 0.3) instead of glossy.  A variant, so
that the interior benchmarks are not tuned to one frame.

blender -b --factory-startup -noaudio --python interior_low_sun.py -- --spp 16 --seed 1 --out x.exr
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interior_window  # noqa: E402

interior_window.main(sun_direction=(0.9, 0.22, -0.2), sun_colour=(1.0, 0.82, 0.62),
                     floor_roughness=0.3)
