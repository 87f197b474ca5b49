"""sun_blinds_low: sun_blinds' room in a lower (28 instead of 45 degrees), warmer afternoon sun
shining more squarely through the window (azimuth 15 instead of 25 degrees), with the blind's
slats tilted less (20 instead of 30 degrees).  The stripes on the floor are about 1.7 times
as far apart and reach further into the room, where the longer way from the slats widens the
penumbra, so that they go from sharp by the window to soft; the patch runs as a diagonal band
along the back wall.  A variant, so that the blind benchmarks are not tuned to one sun angle.

blender -b --factory-startup -noaudio --python sun_blinds_low.py -- --spp 16 --seed 1 --out x.exr
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sun_blinds  # noqa: E402

sun_blinds.main(sun_elevation=28.0, sun_azimuth=15.0, sun_colour=(1.0, 0.84, 0.66), slat_tilt=20.0)
