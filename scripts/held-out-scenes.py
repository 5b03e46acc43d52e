#!/usr/bin/env python3
"""Makes grey held-out scenes by the bench-scene recipe, for `scripts/bar-vs-mitsuba.py` (docs/performance.md,
"Held-out scenes").

The recipe is ../shared/bench-scenes/make_large_scenes.py: one merged mesh, one grey Lambert material, a constant
white sky, and the scene as Mitsuba XML + PLY and as mislab TOML + glTF. This script only registers sources it
does not know and calls it. Nothing it writes is committed: two of the models state no licence.

  scripts/held-out-scenes.py --models DIR --out /tmp/heldout

DIR holds the Khronos glTF-Binary files 2CylinderEngine.glb, ReciprocatingSaw.glb, BrainStem.glb, VC.glb and
CesiumMilkTruck.glb (`git show HEAD:2.0/NAME/glTF-Binary/NAME.glb` in a clone of github:sbtron/glTF-Sample-Models,
54e8526), and the glTF files with their .bin of Suzanne, Lantern and Corset (`2.0/NAME/glTF/`).
material-testball comes from ../shared/testdata. A missing source is skipped with a message. Needs numpy.
"""
import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "shared"))

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("--models", required=True, help="folder holding the Khronos .glb sources")
p.add_argument("--out", required=True, help="output folder (one sub-folder per scene)")
a = p.parse_args()

sys.path.insert(0, os.path.join(SHARED, "bench-scenes"))
import make_large_scenes as m  # noqa: E402

khronos = "Khronos glTF-Sample-Models 2.0/%s (github:sbtron/glTF-Sample-Models@54e8526)"
orbit = {"auto": True, "azimuth": 30.0, "elevation": 20.0, "vfov": 35.0, "fill": 0.95}
scenes = {
    "2cylinderengine": dict(m.MODELS["2cylinderengine"], src=os.path.join(a.models, "2CylinderEngine.glb")),
    "reciprocatingsaw": {"src": os.path.join(a.models, "ReciprocatingSaw.glb"),
                         "origin": khronos % "ReciprocatingSaw", "licence": "none stated (test-only)",
                         "camera": orbit},
    "brainstem": {"src": os.path.join(a.models, "BrainStem.glb"), "origin": khronos % "BrainStem",
                  "camera": dict(orbit, elevation=10.0, fill=0.9)},
    # Faces seen from their geometric back with normals leaning away: docs/materials.md, "A shading normal that
    # faces away from the viewer".
    "vc": {"src": os.path.join(a.models, "VC.glb"), "origin": khronos % "VC", "camera": dict(orbit, elevation=35.0)},
    "milktruck": {"src": os.path.join(a.models, "CesiumMilkTruck.glb"), "origin": khronos % "CesiumMilkTruck",
                  "camera": orbit},
}
for name, file in (("suzanne", "Suzanne"), ("lantern", "Lantern"), ("corset", "Corset")):
    scenes[name] = {"src": os.path.join(a.models, file + ".gltf"), "origin": khronos % file, "camera": orbit}
testball = m.bitterli("material-testball", "Material Testball", "Wig42", "blendswap", [640, 360])
testball["src"] = os.path.join(SHARED, "testdata", "scenes", "bitterli", "material-testball", "pbrt-v4",
                               "scene-v4.pbrt")
scenes["testball"] = testball

for name, spec in scenes.items():
    m.make(name, spec, a.out)
