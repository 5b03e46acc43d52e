#!/usr/bin/env python3
"""The web page in a real headless Chromium (WebGPU on SwiftShader), driven over WebDriver by chromedriver: serves
target/web (scripts/web/build.sh), opens the page for a scene and estimator, waits until it has N spp, and checks
the image's mean radiance against the native renderer's (the `mislab` Python package, same scene, settings, seed and
size) within 3 %; then the same for a second estimator, whose image must differ from the first. Fails —
never skips — when the page reports no WebGPU adapter. Standard library only; a screenshot goes to --screenshot.

  python3 scripts/web/test_page.py --python target/ci-venv/bin/python
"""
import argparse
import base64
import json
import os
import re
import socket
import subprocess
import sys
import time
import urllib.request

p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
p.add_argument("--web", default="target/web", help="the built page")
p.add_argument("--python", default=sys.executable, help="a Python with the mislab package (for the native means)")
p.add_argument("--chromium", default="/usr/bin/chromium")
p.add_argument("--chromedriver", default="/usr/bin/chromedriver")
p.add_argument("--spp", type=int, default=64)
p.add_argument("--timeout", type=float, default=600, help="seconds a page may take to reach --spp")
p.add_argument("--screenshot", default="target/web-test.png")
p.add_argument("--scene", default="veach-mis")
a = p.parse_args()
CASES = ((a.scene, "mis"), (a.scene, "uniform"))

# Chromium's WebGPU on SwiftShader, headless (issue 45); no network, no first-run chores.
FLAGS = ["--headless=new", "--no-sandbox", "--enable-unsafe-webgpu", "--enable-features=Vulkan",
         "--use-vulkan=swiftshader", "--use-angle=swiftshader", "--disable-gpu-sandbox", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync", "--disable-quic",
         "--window-size=1200,700"]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def call(method, url, body=None):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, method=method, headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=120) as r:
        return json.loads(r.read())["value"]


def native_mean(scene, strategy):
    code = (
        "import mislab, numpy as np\n"
        f"img = mislab.render({scene!r}, strategy={strategy!r}, spp={a.spp}, width=320, height=240)\n"
        "print(float(np.asarray(img.mean).mean()))\n"
    )
    out = subprocess.run([a.python, "-c", code], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"FAIL: the native render failed:\n{out.stderr}")
    return float(out.stdout.split()[-1])


web_port, driver_port = free_port(), free_port()
server = subprocess.Popen([sys.executable, "-m", "http.server", str(web_port), "-d", a.web, "--bind", "127.0.0.1"],
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
driver = subprocess.Popen([a.chromedriver, f"--port={driver_port}"], stdout=subprocess.DEVNULL,
                          stderr=subprocess.DEVNULL)
base = f"http://127.0.0.1:{driver_port}"
failures = []
try:
    for _ in range(50):
        try:
            call("GET", f"{base}/status")
            break
        except OSError:
            time.sleep(0.2)
    caps = {"capabilities": {"alwaysMatch": {"browserName": "chrome", "goog:loggingPrefs": {"browser": "ALL"},
                                             "goog:chromeOptions": {
        "binary": a.chromium, "args": FLAGS + [f"--user-data-dir=/tmp/mislab-web-{os.getpid()}"]}}}}
    session = call("POST", f"{base}/session", caps)["sessionId"]
    s = f"{base}/session/{session}"
    results = {}
    for scene, strategy in CASES:
        url = f"http://127.0.0.1:{web_port}/?scene={scene}&strategy={strategy}&spp={a.spp}"
        call("POST", f"{s}/url", {"url": url})
        t0, status = time.time(), ""
        while time.time() - t0 < a.timeout:
            status = call("POST", f"{s}/execute/sync",
                          {"script": "return document.getElementById('status').textContent", "args": []})
            if status.startswith(("error", "mislab panicked")) or re.search(r"spp=(\d+)", status) and \
                    int(re.search(r"spp=(\d+)", status).group(1)) >= a.spp:
                break
            time.sleep(1)
        seconds = time.time() - t0
        print(f"{scene} {strategy}: '{status}' after {seconds:.1f} s")
        for entry in call("POST", f"{s}/se/log", {"type": "browser"}):
            if entry.get("level") in ("SEVERE", "WARNING") and "favicon" not in entry.get("message", ""):
                print(f"  browser console: {entry.get('message', '')[:2000]}")
        if status.startswith(("error", "mislab panicked")) or "spp=" not in status:
            failures.append(f"{scene} {strategy}: the page never rendered ({status!r}); no WebGPU adapter?")
            continue
        spp = int(re.search(r"spp=(\d+)", status).group(1))
        if spp < a.spp:
            failures.append(f"{scene} {strategy}: {spp} of {a.spp} spp in {a.timeout} s")
            continue
        web = float(re.search(r"mean=([0-9.eE+-]+)", status).group(1))
        native = native_mean(scene, strategy)
        results[strategy] = web
        rel = abs(web - native) / max(native, 1e-9)
        print(f"  mean radiance: web {web:.6f}, native {native:.6f} ({100 * rel:.2f} % apart); "
              f"{spp / seconds:.1f} spp/s at 320×240 in the browser")
        if rel > 0.03:
            failures.append(f"{scene} {strategy}: web mean {web} vs native {native}")
        png = call("GET", f"{s}/screenshot")
        with open(a.screenshot.replace(".png", f"-{strategy}.png"), "wb") as f:
            f.write(base64.b64decode(png))
    if len(results) == 2 and results["mis"] == results["uniform"]:
        # Switching the estimator must change the image (each matched its own native render above).
        failures.append(f"mis and uniform gave the same image: {results}")
    call("DELETE", s)
finally:
    driver.terminate()
    server.terminate()

if failures:
    sys.exit("FAIL:\n  " + "\n  ".join(failures))
print("web page: OK")
