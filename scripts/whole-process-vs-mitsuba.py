#!/usr/bin/env python3
"""Whole processes side by side: a 16-spp render of a bench scene, process start to image written, by Mitsuba 3
(Python start, import, scene load, kernel JIT, render, EXR written) and by `mislab render`, each first with empty
caches and then again with what the first run left (issue 44's third goal). Rounds alternate the renderers.

Mitsuba is never a mislab dependency: run this from a scratch venv (`pip install mitsuba==3.9.1 numpy`, Debian's
libllvm19, DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so). Dr.Jit keeps its compiled kernels under
$HOME/.drjit, so a first Mitsuba run gets a fresh HOME; a first mislab run a fresh XDG_CACHE_HOME (Mesa's shader
cache, mislab's pipeline and BVH stores).

  scripts/whole-process-vs-mitsuba.py ../shared/bench-scenes/damagedhelmet_grey --width 512 --height 512
"""
import argparse
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import time

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("scene_dirs", nargs="+", help="bench-scene folders holding <stem>.xml and <stem>.toml")
p.add_argument("--width", type=int, required=True)
p.add_argument("--height", type=int, required=True)
p.add_argument("--spp", type=int, default=16)
p.add_argument("--rounds", type=int, default=1)
p.add_argument("--mislab", default="target/release/mislab")
p.add_argument("--threads", type=int, default=2)
a = p.parse_args()

MITSUBA = """
import sys, drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(int(sys.argv[5]))
xml, w, h, spp, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[6]
text = open(xml).read().replace('<sampler type="independent">', '<sampler type="multijitter">')
mi.file_resolver().prepend(sys.argv[7])
scene = mi.load_string(text, width=w, height=h, max_depth=8, spp=spp)
mi.Bitmap(mi.render(scene, spp=spp)).write(out)
"""


def timed(cmd, env):
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr}")
    return wall, r.stderr + r.stdout


def mitsuba(d, home, out):
    env = dict(os.environ, HOME=home)
    env.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
    xml = d / f"{d.name}.xml"
    cmd = [sys.executable, "-c", MITSUBA, str(xml), str(a.width), str(a.height), str(a.spp), str(a.threads), out, str(d)]
    return timed(cmd, env)[0]


def mislab(d, cache, out):
    cmd = [a.mislab, "render", str(d / f"{d.name}.toml"), "--mode", "path", "--max-depth", "8", "--strategy", "mis",
           "--heuristic", "power", "--sampler", "sobol", "--spp", str(a.spp), "--width", str(a.width), "--height",
           str(a.height), "-o", out, "--force"]
    wall, text = timed(cmd, dict(os.environ, XDG_CACHE_HOME=cache))
    start = re.search(r"start-up: ([0-9.]+) s", text)
    render = re.search(r"spp in ([0-9.]+) s", text)
    return wall, float(start.group(1)) if start else float("nan"), float(render.group(1)) if render else float("nan")


print(f"{a.width}x{a.height}, {a.spp} spp, path depth 8; seconds, process start to EXR written")
print("| scene | Mitsuba first | Mitsuba repeated | mislab first (start-up / render) | mislab repeated (start-up / render) |")
print("|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as tmp:
    for r in range(a.rounds):
        for d in map(pathlib.Path, a.scene_dirs):
            home, cache = tempfile.mkdtemp(dir=tmp), tempfile.mkdtemp(dir=tmp)
            out = os.path.join(tmp, f"{d.name}.exr")
            m1, m2 = mitsuba(d, home, out), mitsuba(d, home, out)
            l1, l2 = mislab(d, cache, out), mislab(d, cache, out)
            print(f"| {d.name} | {m1:.2f} | {m2:.2f} | {l1[0]:.2f} ({l1[1]:.2f} / {l1[2]:.2f}) | "
                  f"{l2[0]:.2f} ({l2[1]:.2f} / {l2[2]:.2f}) |", flush=True)
