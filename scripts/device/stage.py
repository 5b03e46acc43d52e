#!/usr/bin/env python3
"""Packs what `scripts/device/gpu_table.py` needs on a lent GPU machine into `.device/` (ignored by git), so that a
session that is lent one spends its few minutes of device time measuring, not preparing (issue 44: "when a GPU device
is lent to a task, the same table there").

A device machine reaches nothing outside itself and gets only the checkout's files and the paths a call carries
(64 MiB in all), never `../shared`. So this copies there:
- `mislab.gz`: the release binary, stripped and gzipped (build it first: `cargo build --release`);
- `scenes/<stem>/`: each bench scene's `.toml` and `.glb`;
- `refs/<stem>.exr`: Mitsuba's 1024-spp reference at the bar's size (`scripts/bar-vs-mitsuba.py` makes the same
  one and caches it as .npy; it is made here if missing);
- `mitsuba.json`: per scene the size, and Mitsuba's 16-spp time T and error E with its `multijitter` sampler, measured
  here on the CPU (what the bar's table compares against).

It also downloads Debian's Vulkan loader packages into `.gl/` (the device's image may have no libvulkan; the device
README's recipe). Run it from the checkout's root with the Mitsuba scratch venv (never a mislab dependency):

  /tmp/mivenv/bin/python scripts/device/stage.py ../shared/bench-scenes

Then, on the device (one `run` call; `carry` [".device", ".gl"]):

  for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; python3 scripts/device/gpu_table.py --dir .device --out $OUT
"""
import argparse
import gzip
import json
import os
import pathlib
import shutil
import subprocess
import sys

# The bar's scenes and sizes (docs/performance.md, "Time to Mitsuba's error").
SCENES = {
    "damagedhelmet_grey": (512, 512),
    "staircase2_grey": (512, 512),
    "scaling_1k": (512, 512),
    "scaling_10k": (512, 512),
    "scaling_100k": (512, 512),
    "livingroom_grey": (640, 360),
    "diningroom_grey": (640, 360),
}

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("bench", help="the bench-scene folder (../shared/bench-scenes)")
p.add_argument("--out", default=".device")
p.add_argument("--mislab", default="target/release/mislab")
p.add_argument("--cache", default="/tmp/mislab-bar", help="the bar's cache of references (.npy)")
p.add_argument("--threads", type=int, default=2)
p.add_argument("--no-loader", action="store_true", help="skip downloading the Vulkan loader packages")
a = p.parse_args()

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))
import mitsuba_bar as mb  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mb.setup(a.threads)
out = pathlib.Path(a.out)
(out / "refs").mkdir(parents=True, exist_ok=True)
(out / "scenes").mkdir(exist_ok=True)

table = {}
for stem, (w, h) in SCENES.items():
    d = pathlib.Path(a.bench) / stem
    xml = d / f"{stem}.xml"
    ref = mb.reference(xml, w, h, a.cache)
    mi.Bitmap(ref.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(str(out / "refs" / f"{stem}.exr"))
    # Mitsuba at its most efficient sampler, as the bar measures it.
    m16, T = mb.best_16spp(xml, w, h)
    table[stem] = {"width": w, "height": h, "T": T, "E": mb.relmse(m16, ref)}
    dst = out / "scenes" / stem
    dst.mkdir(exist_ok=True)
    for ext in ("toml", "glb"):
        shutil.copy(d / f"{stem}.{ext}", dst / f"{stem}.{ext}")
    print(f"{stem} {w}x{h}: Mitsuba T {T:.2f} s, E {table[stem]['E']:.3e}", flush=True)
(out / "mitsuba.json").write_text(json.dumps({"cpu": f"{os.cpu_count()} cores, {a.threads} threads", "scenes": table},
                                             indent=1))

stripped = out / "mislab"
subprocess.run(["strip", "-o", str(stripped), a.mislab], check=True)
with open(stripped, "rb") as f, gzip.open(out / "mislab.gz", "wb", compresslevel=6) as g:
    shutil.copyfileobj(f, g)
stripped.unlink()

if not a.no_loader:
    # The device README's recipe: Debian's loader packages, unpacked over / there before the first Vulkan call.
    gl = pathlib.Path(".gl")
    gl.mkdir(exist_ok=True)
    opts = ["-oAPT::Architecture=amd64", "-oAPT::Architectures=amd64", "-oDir::State::Lists=/tmp/amd64",
            "-oAPT::Sandbox::User=root"]
    pathlib.Path("/tmp/amd64/partial").mkdir(parents=True, exist_ok=True)
    subprocess.run(["apt-get", *opts, "update", "-qq"], check=True)
    subprocess.run(["apt-get", *opts, "download", "-qq", "libvulkan1"], check=True, cwd=gl)

size = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
print(f"{out}: {size / 2**20:.1f} MiB (a device call carries 64 MiB in all)")
