#!/usr/bin/env python3
"""Render a Mitsuba 3 XML scene with Mitsuba 3 itself, for `mislab compare` (scripts/compare-references.sh).

Mitsuba is never a mislab dependency: run this from a scratch venv (`pip install mitsuba==3.9.1 numpy`,
Debian's libllvm19, DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so). Variant llvm_ad_rgb.
The image is the mean of chunks rendered with distinct seeds (bounded memory), written as linear EXR.
"""
import argparse
import os
import sys
import time

p = argparse.ArgumentParser(description=__doc__)
p.add_argument("scene")
p.add_argument("output")
p.add_argument("--spp", type=int, default=256)
p.add_argument("--chunk", type=int, default=64, help="spp per mi.render call")
p.add_argument("--width", type=int, required=True)
p.add_argument("--height", type=int, required=True)
p.add_argument("--max-depth", type=int, default=65, help="Mitsuba's max_depth (2 = direct lighting only)")
p.add_argument("--integrator", default="path")
p.add_argument("--threads", type=int, default=2)
p.add_argument("--seed", type=int, default=1)
a = p.parse_args()

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(a.threads)
scene = mi.load_file(a.scene, resx=a.width, resy=a.height, max_depth=a.max_depth, integrator=a.integrator,
                     spp=a.chunk)
t = time.time()
acc, done, k = None, 0, 0
while done < a.spp:
    n = min(a.chunk, a.spp - done)
    img = np.array(mi.render(scene, spp=n, seed=a.seed * 100003 + k), dtype=np.float64)[:, :, :3]
    acc = img * n if acc is None else acc + img * n
    done += n
    k += 1
img = (acc / done).astype(np.float32)
bad = int((~np.isfinite(img)).sum())
mi.Bitmap(img).write(a.output)
print(f"{a.scene}: {done} spp at {a.width}x{a.height}, max_depth {a.max_depth}, {time.time() - t:.1f} s, "
      f"mean {img.reshape(-1, 3).mean(0)}, {bad} non-finite values; wrote {a.output}", file=sys.stderr)
