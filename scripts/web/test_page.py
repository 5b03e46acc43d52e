#!/usr/bin/env python3
"""The web page in a real headless Chromium (WebGPU on SwiftShader), used as a person would, over WebDriver
(scripts/web/webdriver.py): it serves target/web (scripts/web/build.sh) and

 1. opens a built-in scene, waits for N spp, saves the image with the panel's "Save PNG" and "Save EXR" (browser
    downloads) and compares the EXR in distribution with the native renderer's image of the same scene, settings
    and seed (the `mislab` Python package): no further from it than a second native render of another seed is, and
    the same mean;
 2. switches the strategy by clicking its radio button: the status says so, the samples restart, and the new image
    matches its own native render and differs from the first;
 3. turns on the A | B comparison (a click): side B renders with its strategy and its native mean;
 4. shows the standard-error view (a click);
 5. drops a glTF scene (.gltf + .bin) and a Mitsuba scene (its XML, included fragments and OBJ meshes, dropped
    without their folders) on the canvas: each renders with its native mean.
It fails — never skips — when the page reports no WebGPU adapter. Screenshots go to target/web-test-*.png.

  python3 scripts/web/test_page.py --python target/ci-venv/bin/python
"""
import argparse
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from webdriver import Page  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SHARED = os.path.join(ROOT, "..", "shared")

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("--web", default=os.path.join(ROOT, "target/web"), help="the built page")
p.add_argument("--python", default=sys.executable, help="a Python with the mislab package (for the native images)")
p.add_argument("--chromium", default="/usr/bin/chromium")
p.add_argument("--chromedriver", default="/usr/bin/chromedriver")
p.add_argument("--spp", type=int, default=8)
p.add_argument("--timeout", type=float, default=600, help="seconds a page may take to reach --spp")
p.add_argument("--screenshots", default=os.path.join(ROOT, "target/web-test"))
a = p.parse_args()

failures = []
# What the native side renders and compares, filled as the page goes: one dict per image.
checks = []


def at_least(key, n, **equal):
    return lambda f: int(f.get(key, 0)) >= n and all(f.get(k) == v for k, v in equal.items())


page = Page(a.web, a.chromium, a.chromedriver)
try:
    t_open = time.time()
    page.open(f"scene=veach-mis&strategy=mis&spp={a.spp}")
    f, secs = page.wait("veach-mis, MIS", at_least("spp", a.spp, strategy="mis"), a.timeout)
    print(f"1. veach-mis MIS: {f['spp']} spp after {secs:.1f} s (page opened to image), mean {f['mean']}, "
          f"{float(f['samples_per_s']) / 1e6:.3f} M samples/s")
    page.click("save-exr")
    exr = page.downloaded(f"veach-mis-mis-{f['spp']}spp.exr")
    checks.append({"what": "veach-mis MIS (downloaded EXR)", "scene": "veach-mis", "strategy": "mis",
                   "spp": int(f["spp"]), "web_mean": float(f["mean"]), "exr": exr})
    page.click("save-png")
    png = open(page.downloaded(f"veach-mis-mis-{f['spp']}spp.png"), "rb").read()
    width, height = int.from_bytes(png[16:20], "big"), int.from_bytes(png[20:24], "big")
    if png[:8] != b"\x89PNG\r\n\x1a\n" or (width, height) != (320, 240):
        failures.append(f"Save PNG: not a 320×240 PNG ({png[:8]!r}, {width}×{height})")
    page.screenshot(f"{a.screenshots}-mis.png")

    page.click("strategy:uniform")
    f, secs = page.wait("the click on 'uniform'", at_least("spp", a.spp, strategy="uniform"), a.timeout)
    print(f"2. clicked uniform: {f['spp']} spp after {secs:.1f} s, mean {f['mean']}")
    page.click("save-exr")
    exr_uniform = page.downloaded(f"veach-mis-uniform-{f['spp']}spp.exr")
    checks.append({"what": "veach-mis uniform (after a click)", "scene": "veach-mis", "strategy": "uniform",
                   "spp": int(f["spp"]), "web_mean": float(f["mean"]), "exr": exr_uniform, "differs_from": exr})

    page.click("compare")
    f, secs = page.wait("the A | B comparison", at_least("spp_b", a.spp, strategy_b="bsdf"), a.timeout)
    print(f"3. compare A | B: A {f['strategy']} mean {f['mean']}, B {f['strategy_b']} mean {f['mean_b']} "
          f"({secs:.1f} s)")
    checks.append({"what": "veach-mis side B (bsdf)", "scene": "veach-mis", "strategy": "bsdf",
                   "spp": int(f["spp_b"]), "web_mean": float(f["mean_b"])})
    page.screenshot(f"{a.screenshots}-compare.png")

    page.click("view:std-error")
    f, _ = page.wait("the std-error view", lambda f: f.get("view") == "std-error", 60)
    time.sleep(2)
    page.screenshot(f"{a.screenshots}-std-error.png")
    print(f"4. view {f['view']}")
    page.click("view:image")
    page.click("compare")

    cbox = os.path.join(SHARED, "scenes/cornell-box")
    page.drop([os.path.join(cbox, "cbox.gltf"), os.path.join(cbox, "cbox.bin")])
    f, secs = page.wait("the dropped glTF", at_least("spp", a.spp, scene="cbox.gltf"), a.timeout)
    print(f"5. dropped cbox.gltf + cbox.bin: {f['spp']} spp after {secs:.1f} s, mean {f['mean']}")
    checks.append({"what": "dropped glTF", "scene": os.path.join(cbox, "cbox.gltf"), "strategy": f["strategy"],
                   "spp": int(f["spp"]), "web_mean": float(f["mean"])})
    page.screenshot(f"{a.screenshots}-dropped-gltf.png")

    mitsuba = os.path.join(SHARED, "testdata/scenes/mitsuba-data/cbox")
    files = [os.path.join(mitsuba, "cbox-rgb.xml")]
    files += [os.path.join(mitsuba, "fragments", n) for n in ("base.xml", "bsdfs-rgb.xml", "shapes.xml")]
    files += [os.path.join(mitsuba, "meshes", n) for n in sorted(os.listdir(os.path.join(mitsuba, "meshes")))]
    page.drop(files)
    f, secs = page.wait("the dropped Mitsuba scene", at_least("spp", a.spp, scene="cbox-rgb.xml"), a.timeout)
    print(f"   dropped cbox-rgb.xml with {len(files) - 1} fragments and meshes: {f['spp']} spp after {secs:.1f} s, "
          f"mean {f['mean']}")
    checks.append({"what": "dropped Mitsuba XML", "scene": os.path.join(mitsuba, "cbox-rgb.xml"),
                   "strategy": f["strategy"], "spp": int(f["spp"]), "web_mean": float(f["mean"])})
    page.screenshot(f"{a.screenshots}-dropped-mitsuba.png")
    page.console()
finally:
    page.close()

# The native side: the same scenes, settings and seeds on this machine's Vulkan driver.
NATIVE = r"""
import json, sys, numpy as np, mislab
out = []
for c in json.loads(sys.argv[1]):
    kw = dict(strategy=c["strategy"], spp=c["spp"], width=320, height=240)
    native = mislab.render(c["scene"], **kw)
    r = {"native_mean": float(np.asarray(native.mean).mean())}
    if "exr" in c:
        other_seed = mislab.render(c["scene"], seed=7, **kw)
        r["web_vs_native"] = mislab.compare(c["exr"], native)["relmse"]
        r["seed_vs_native"] = mislab.compare(other_seed, native)["relmse"]
    if "differs_from" in c:
        r["vs_first"] = mislab.compare(c["exr"], c["differs_from"])["relmse"]
    out.append(r)
print(json.dumps(out))
"""
run = subprocess.run([a.python, "-c", NATIVE, json.dumps(checks)], capture_output=True, text=True)
if run.returncode != 0:
    sys.exit(f"FAIL: the native renders failed:\n{run.stderr}")
for c, r in zip(checks, json.loads(run.stdout.splitlines()[-1])):
    rel = abs(c["web_mean"] - r["native_mean"]) / max(r["native_mean"], 1e-9)
    line = f"{c['what']}: mean web {c['web_mean']:.6f}, native {r['native_mean']:.6f} ({100 * rel:.3f} % apart)"
    if rel > 0.02:
        failures.append(line)
    if "web_vs_native" in r:
        line += (f"; block relMSE web vs native {r['web_vs_native']:.2e}, "
                 f"another native seed vs native {r['seed_vs_native']:.2e}")
        if not r["web_vs_native"] <= r["seed_vs_native"]:
            failures.append(f"{c['what']}: the page's image is further from the native one than noise: {r}")
    if "vs_first" in r:
        line += f"; relMSE against the first estimator's image {r['vs_first']:.2e}"
        if not r["vs_first"] > r["web_vs_native"] * 10:
            failures.append(f"{c['what']}: switching the estimator did not change the image: {r}")
    print(line)

if failures:
    sys.exit("FAIL:\n  " + "\n  ".join(failures))
print("web page: OK")
