#!/usr/bin/env python3
"""Time to Mitsuba's error on one bench scene, side by side in one run: Mitsuba 3 renders 16 spp with its sampler
(--mitsuba-sampler, default multijitter, its most efficient on every bench scene; time T, relMSE E against a
converged Mitsuba reference); mislab renders the same scene for --time 4T, 2T, T and T/2 (render time, as Mitsuba's
T: both exclude start-up); the table says which reach E.

Mitsuba is never a mislab dependency: run this from a scratch venv (`pip install mitsuba==3.9.1 numpy`,
Debian's libllvm19, DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so). The reference is cached
(--cache) because it takes 64× the 16-spp time. relMSE = mean of (x − r)² / (r² + 0.01) over pixels and
channels, as src/testkit/metrics.rs computes it.

  scripts/bar-vs-mitsuba.py ../shared/bench-scenes/damagedhelmet_grey --width 256 --height 256
"""
import argparse
import pathlib
import re
import subprocess
import sys

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("scene_dir", help="a bench-scene folder holding <stem>.xml and <stem>.toml")
p.add_argument("--width", type=int, required=True)
p.add_argument("--height", type=int, required=True)
p.add_argument("--ref-spp", type=int, default=1024)
p.add_argument("--mislab", default="target/release/mislab")
p.add_argument("--cache", default="/tmp/mislab-bar")
p.add_argument("--threads", type=int, default=2)
p.add_argument("--mitsuba-sampler", default="multijitter", help="Mitsuba's sampler for its 16 spp (the reference always uses independent)")
p.add_argument("--mislab-args", default="", help="extra mislab render arguments (an A/B of a setting), e.g. '--env-sampling importance'")
a = p.parse_args()

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import mitsuba_bar as mb  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mb.setup(a.threads)
d = pathlib.Path(a.scene_dir)
stem = d.name
xml, toml = d / f"{stem}.xml", d / f"{stem}.toml"
cache = pathlib.Path(a.cache)
cache.mkdir(parents=True, exist_ok=True)
relmse = mb.relmse
ref = mb.reference(xml, a.width, a.height, cache, a.ref_spp)
m16, T = mb.best_16spp(xml, a.width, a.height, a.mitsuba_sampler)
E = relmse(m16, ref)
rows = [(f"Mitsuba 3.9.1 llvm_ad_rgb, {a.mitsuba_sampler}, 16 spp", T, 16, E)]

for factor, label in ((4.0, "4T"), (2.0, "2T"), (1.0, "T"), (0.5, "T/2")):
    out = cache / f"{stem}-mislab-{label.replace('/', '_')}.exr"
    cmd = [a.mislab, "render", str(toml), "--mode", "path", "--max-depth", "8", "--strategy", "mis",
           "--heuristic", "power", "--sampler", "sobol", "--width", str(a.width), "--height", str(a.height),
           "--time", f"{factor * T:.3f}", "-o", str(out), "--force"] + a.mislab_args.split()
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"mislab failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr}")
    img = np.array(mi.Bitmap(str(out)), dtype=np.float64)[:, :, :3]
    m = re.search(r"(\d+) spp in ([0-9.]+) s", r.stderr + r.stdout)
    spp = f"{m.group(1)} ({m.group(2)} s)" if m else "?"
    rows.append((f"mislab --time {label}", factor * T, spp, relmse(img, ref)))

print(f"{stem} {a.width}x{a.height}, max depth 8, reference Mitsuba {a.ref_spp} spp; E = {E:.4e}")
print("| renderer | seconds | spp | relMSE | reaches E |\n|---|---|---|---|---|")
for name, sec, spp, err in rows:
    print(f"| {name} | {sec:.2f} | {spp} | {err:.4e} | {'yes' if err <= E else 'no'} |")
# Time to E, interpolated log-log between mislab's budgets (error ∝ time^slope).
pts = sorted((sec, err) for name, sec, spp, err in rows[1:])
ratio = None
for (t1, e1), (t2, e2) in zip(pts, pts[1:]):
    if e1 > E >= e2 and e1 > 0 and e2 > 0:
        slope = np.log(e2 / e1) / np.log(t2 / t1)
        ratio = t1 * (E / e1) ** (1 / slope) / T
if pts and pts[0][1] <= E:
    ratio = f"< {pts[0][0] / T:.2f}"
print(f"mislab reaches E in {ratio if isinstance(ratio, str) else (f'{ratio:.2f}' if ratio else '> 4')}× Mitsuba's time")
