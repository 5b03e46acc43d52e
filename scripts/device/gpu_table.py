#!/usr/bin/env python3
"""Issue 44's table on whatever Vulkan device the machine has: start-up (first and repeated) and samples/s at 1080p,
and the time to Mitsuba's 16-spp error. Written for a lent GPU machine, which reaches nothing outside itself: it needs
only Python's standard library and what `scripts/device/stage.py` packed into `.device/`.

For each bench scene:
- **1080p**: `mislab render` at 1920×1080, 16 spp, twice with one fresh cache directory (a first run, then a repeated
  one). Each run's start-up line and its samples/s.
- **Time to error**: at the bar's size, an spp ladder (1, 2, 4, … `--max-spp`) with a warm cache, each image compared
  with Mitsuba's 1024-spp reference by `mislab compare --block 1` (the bar's relMSE). The render time at which
  mislab reaches Mitsuba's error E is interpolated log-log between the rungs around it, as the bar does, and given
  as a multiple of Mitsuba's time T. T and E were measured on the CPU machine that ran `stage.py` (mitsuba.json
  says which): a GPU's time against a 2-core CPU's, not against Mitsuba on the same GPU.

All settings as the bar's: path tracing, depth 8, MIS with the power heuristic, Sobol. Prints a markdown table and
writes it, with every run's stderr, to `--out`.

  python3 scripts/device/gpu_table.py --dir .device --out $OUT
"""
import argparse
import gzip
import json
import math
import os
import pathlib
import re
import shutil
import stat
import subprocess
import sys
import tempfile
import time

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("--dir", default=".device", help="what stage.py packed")
p.add_argument("--out", required=True, help="where the table and the logs go")
p.add_argument("--mislab", help="a mislab binary to use instead of the packed one")
p.add_argument("--scenes", help="comma-separated stems (default: every packed scene)")
p.add_argument("--hd", default="1920x1080", help="the size of the start-up and samples/s runs")
p.add_argument("--hd-spp", type=int, default=16)
p.add_argument("--max-spp", type=int, default=256, help="the ladder's last rung")
p.add_argument("--timeout", type=float, default=120.0, help="seconds one render may take")
a = p.parse_args()

pack = pathlib.Path(a.dir)
out = pathlib.Path(a.out)
out.mkdir(parents=True, exist_ok=True)
work = pathlib.Path(tempfile.mkdtemp(prefix="mislab-gpu-"))
if a.mislab:
    mislab = a.mislab
else:
    mislab = str(work / "mislab")
    with gzip.open(pack / "mislab.gz", "rb") as g, open(mislab, "wb") as f:
        shutil.copyfileobj(g, f)
    os.chmod(mislab, os.stat(mislab).st_mode | stat.S_IXUSR)
mitsuba = json.loads((pack / "mitsuba.json").read_text())
stems = a.scenes.split(",") if a.scenes else list(mitsuba["scenes"])
log = open(out / "runs.log", "w")
SETTINGS = ["--mode", "path", "--max-depth", "8", "--strategy", "mis", "--heuristic", "power", "--sampler", "sobol"]


def run(args, cache, name):
    """One mislab process; its stderr goes to the log. Exits on failure: a table with a hole would mislead."""
    env = dict(os.environ, XDG_CACHE_HOME=str(cache))
    t0 = time.perf_counter()
    r = subprocess.run([mislab, *args], capture_output=True, text=True, env=env, timeout=a.timeout)
    wall = time.perf_counter() - t0
    log.write(f"=== {name} ({wall:.2f} s wall): mislab {' '.join(args)}\n{r.stderr}{r.stdout}\n")
    log.flush()
    if r.returncode != 0:
        sys.exit(f"{name}: mislab exited {r.returncode}:\n{r.stderr}")
    return r.stderr + r.stdout, wall


def render(stem, w, h, spp, cache, name, exr):
    toml = pack / "scenes" / stem / f"{stem}.toml"
    text, wall = run(["render", str(toml), *SETTINGS, "--width", str(w), "--height", str(h), "--spp", str(spp),
                      "-o", str(exr), "--force"], cache, name)
    startup = re.search(r"start-up: ([0-9.]+) s", text)
    done = re.search(r"(\d+) spp in ([0-9.]+) s: ([0-9.]+) M samples/s", text)
    if not (startup and done):
        sys.exit(f"{name}: no start-up or render line in:\n{text}")
    return {"startup": float(startup.group(1)), "seconds": float(done.group(2)),
            "msps": float(done.group(3)), "wall": wall, "text": text}


def relmse(exr, ref, name):
    text, _ = run(["compare", str(exr), str(ref), "--block", "1", "--json"], work, name)
    return json.loads(text[text.index("{"):])["block_relmse_all"]


hw, hh = (int(v) for v in a.hd.split("x"))
adapter = None
rows = []
for stem in stems:
    m = mitsuba["scenes"][stem]
    cache = work / f"cache-{stem}"
    first = render(stem, hw, hh, a.hd_spp, cache, f"{stem} {a.hd} first", work / "hd.exr")
    again = render(stem, hw, hh, a.hd_spp, cache, f"{stem} {a.hd} repeated", work / "hd.exr")
    adapter = adapter or re.search(r"adapter: (.*)", first["text"]).group(1)
    ladder = []
    spp = 1
    while spp <= a.max_spp:
        exr = work / f"{stem}-{spp}.exr"
        r = render(stem, m["width"], m["height"], spp, cache, f"{stem} {spp} spp", exr)
        ladder.append((r["seconds"], relmse(exr, pack / "refs" / f"{stem}.exr", f"{stem} {spp} spp compare"), spp))
        if ladder[-1][1] <= m["E"] and len(ladder) > 1:
            break
        spp *= 2
    # Time to E, log-log between the rungs around it (the bar's rule).
    to_e = None
    for (t1, e1, _), (t2, e2, _) in zip(ladder, ladder[1:]):
        if e1 > m["E"] >= e2 and t2 > t1 > 0 and e2 > 0:
            slope = math.log(e2 / e1) / math.log(t2 / t1)
            to_e = t1 * (m["E"] / e1) ** (1 / slope)
    if ladder[0][1] <= m["E"]:
        to_e = ladder[0][0]
    rows.append((stem, m, first, again, ladder, to_e))
    print(f"{stem}: done", flush=True)

lines = [f"Device: {adapter}. {a.hd} at {a.hd_spp} spp, then the spp ladder at the bar's size; Mitsuba's T and E "
         f"from the CPU machine that staged the run ({mitsuba['cpu']}).", "",
         f"| scene | start-up first / repeated (s) | {a.hd} M samples/s | Mitsuba T (CPU), E | mislab relMSE by spp "
         "(render s) | mislab's time to E | ÷ T |", "|---|---|---|---|---|---|---|"]
for stem, m, first, again, ladder, to_e in rows:
    rungs = ", ".join(f"{s}: {e:.2e} ({t:.3f})" for t, e, s in ladder)
    reach = f"{to_e:.3f} s" if to_e else f"> {ladder[-1][0]:.3f} s"
    ratio = f"{to_e / m['T']:.3f}×" if to_e else "not reached"
    lines.append(f"| {stem} | {first['startup']:.2f} / {again['startup']:.2f} | {again['msps']:.1f} | "
                 f"{m['T']:.2f} s, {m['E']:.2e} | {rungs} | {reach} | {ratio} |")
table = "\n".join(lines) + "\n"
(out / "gpu-table.md").write_text(table)
print(table)
shutil.rmtree(work, ignore_errors=True)
