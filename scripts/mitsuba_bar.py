"""The bar's side of Mitsuba 3, shared by `bar-vs-mitsuba.py` and `device/stage.py`: its setup, the cached 1024-spp
reference, and its 16-spp render at its most efficient sampler, timed after a warm-up.

Mitsuba is never a mislab dependency: these scripts run from a scratch venv (`pip install mitsuba==3.9.1 numpy`,
Debian's libllvm19).
"""
import os
import pathlib
import time

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

REF_SPP = 1024


def setup(threads):
    """The variant the bar compares with (`llvm_ad_rgb`) on `threads` threads."""
    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(threads)


def relmse(x, r):
    """The bar's relative MSE (ε = 0.01, as `mislab compare`)."""
    return float(np.mean((x - r) ** 2 / (r * r + 0.01)))


def reference(xml, w, h, cache, spp=REF_SPP):
    """Mitsuba's reference of the scene file `xml` at w × h: its independent sampler, `spp` samples in 64-spp runs
    seeded 1000 + k, cached as .npy in `cache` under the scene's folder name."""
    xml = pathlib.Path(xml)
    path = pathlib.Path(cache) / f"{xml.parent.name}-{w}x{h}-{spp}spp.npy"
    if path.exists():
        return np.load(path)
    scene = mi.load_file(str(xml), width=w, height=h, max_depth=8, spp=16)
    acc, done, k = None, 0, 0
    while done < spp:
        n = min(64, spp - done)
        img = np.array(mi.render(scene, spp=n, seed=1000 + k), dtype=np.float64)[:, :, :3]
        acc = img * n if acc is None else acc + img * n
        done, k = done + n, k + 1
    ref = acc / done
    path.parent.mkdir(parents=True, exist_ok=True)
    np.save(path, ref)
    return ref


def best_16spp(xml, w, h, sampler="multijitter"):
    """Mitsuba's 16-spp render with `sampler` in place of the file's independent one, after a warm-up render (the
    JIT compiles then): (image, seconds)."""
    xml = pathlib.Path(xml)
    mi.file_resolver().prepend(str(xml.parent))
    text = xml.read_text().replace('<sampler type="independent">', f'<sampler type="{sampler}">')
    scene = mi.load_string(text, width=w, height=h, max_depth=8, spp=16)
    np.array(mi.render(scene, spp=16, seed=7))
    t0 = time.perf_counter()
    img = np.array(mi.render(scene, spp=16, seed=11), dtype=np.float64)[:, :, :3]
    return img, time.perf_counter() - t0
