#!/usr/bin/env python3
"""Samples per second of the web page in headless Chromium (WebGPU on SwiftShader, a CPU) against the native viewer
(`mislab view` under Xvfb, on this machine's Vulkan driver: lavapipe here), same scene, film size and settings, measured one after the other in one run. A benchmark, not a test: it prints a table (Markdown) and asserts
nothing about speed.

  python3 scripts/web/bench.py [--scenes veach-mis cornell-box] [--spp 24]

The page's rate counts from its first image after a (re)start to the last one it showed (so its shader compilation
is left out, as the viewer's is); the viewer's is the pixel samples of its rendering dispatches over their GPU time
(its own statistic, printed at --screenshot).
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from webdriver import Page  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("--web", default=os.path.join(ROOT, "target/web"))
p.add_argument("--mislab", default=os.path.join(ROOT, "target/release/mislab"))
p.add_argument("--scenes", nargs="+", default=["veach-mis", "cornell-box"])
p.add_argument("--strategy", default="mis")
p.add_argument("--width", type=int, default=320)
p.add_argument("--height", type=int, default=240)
p.add_argument("--spp", type=int, default=24, help="samples per pixel the page renders (its rate is over them)")
p.add_argument("--frames", type=int, default=60, help="viewer frames before its screenshot")
p.add_argument("--timeout", type=float, default=900)
a = p.parse_args()

rows = []
page = Page(a.web)
try:
    for scene in a.scenes:
        page.open(f"scene={scene}&strategy={a.strategy}&spp={a.spp}&width={a.width}&height={a.height}")
        t0 = time.time()
        f, secs = page.wait(scene, lambda f: int(f["spp"]) >= a.spp and float(f["samples_per_s"]) > 0, a.timeout)
        rows.append({"scene": scene, "web": float(f["samples_per_s"]), "web_first_s": secs, "web_spp": f["spp"]})
    page.console()
finally:
    page.close()

for row in rows:
    shot = os.path.join(tempfile.mkdtemp(prefix="mislab-bench-view-"), "view.png")
    cmd = ["xvfb-run", "-a", a.mislab, "view", row["scene"], "--width", str(a.width), "--height", str(a.height),
           "--strategy", a.strategy, "--screenshot", shot, "--frames", str(a.frames)]
    run = subprocess.run(cmd, capture_output=True, text=True)
    m = re.search(r"side A: .*? (\d+) spp · ([0-9.]+) M samples/s", run.stderr)
    if run.returncode != 0 or not m:
        sys.exit(f"FAIL: the native viewer: {' '.join(cmd)}\n{run.stderr[-3000:]}")
    row["native"] = float(m.group(2)) * 1e6
    row["native_spp"] = m.group(1)
    print(f"{row['scene']}: page {row['web'] / 1e6:.3f} M samples/s, native viewer {row['native'] / 1e6:.3f}",
          flush=True)

info = subprocess.run([a.mislab, "info"], capture_output=True, text=True).stdout
driver = re.search(r"chosen adapter: (.*)", info)
print(f"\n{a.width}×{a.height}, {a.strategy}, default settings; page: headless Chromium, WebGPU on SwiftShader; "
      f"viewer: Xvfb, {driver.group(1).strip() if driver else 'the default Vulkan driver'}; "
      f"{time.strftime('%Y-%m-%d')}\n")
print("| scene | page M samples/s | native viewer M samples/s | page / native | page: first open to "
      f"{a.spp} spp |")
print("|---|---|---|---|---|")
for r in rows:
    print(f"| {r['scene']} | {r['web'] / 1e6:.3f} | {r['native'] / 1e6:.3f} | {r['web'] / r['native']:.2f} | "
          f"{r['web_first_s']:.0f} s |")
