#!/usr/bin/env python3
"""Where a render's time goes inside lavapipe's JIT-compiled shader (docs/profile-bvh.md, "The JIT code").

perf sees no symbols in the code LLVM generates at run time, only addresses. This script runs a command (a long
`mislab render`), samples it with `perf record` once shader compilation is over, disassembles the hot code from
the live process with gdb, and sorts the samples by what lavapipe made of the shader's memory accesses: Mesa
22's lavapipe runs every storage-buffer or workgroup-memory access whose address differs between lanes as a loop
over the SIMD lanes (`cmp $0x4, counter` closes it with mislab's 4-lane code, $0x8 with 8 lanes), one loop per load or store instruction, with a bounds check
per component for storage buffers. Storage loads are told apart by the descriptor slot they read their base
pointer from (an offset into lavapipe's context; on Mesa 22.3.6 slot 0x7f00 + 16·b is binding b of the render
pipeline's layout, e.g. 0x7f20 the triangle vertices, 0x7fe0 the wide BVH nodes). Mesa 25 unrolls these loops into a
block per lane, which this classifier does not sort; its hot addresses and disassembly are still kept (--keep).

Needs perf and gdb (Debian: linux-perf, gdb), permission to attach to the process (root, or
kernel.yama.ptrace_scope = 0 and kernel.perf_event_paranoid ≤ 1). Not used by tests or the product.

usage: scripts/jit-profile.py [--warm S] [--seconds S] [--keep PREFIX] -- mislab render SCENE ... --spp 5000
"""
import argparse
import collections
import os
import re
import signal
import subprocess
import sys
import tempfile
import time


def hot_addresses(data):
    """Percent of all samples per JIT instruction address, and per object (perf's own percentages are rounded to
    0.01 %, which over thousands of addresses adds up: count samples instead)."""
    out = subprocess.run(["perf", "report", "-i", data, "--sort", "dso,sym", "--stdio", "-n"],
                         capture_output=True, text=True, check=True).stdout
    counts, dsos = {}, collections.Counter()
    for line in out.splitlines():
        m = re.match(r"\s*[\d.]+%\s+(\d+)\s+(.+?)\s+\[[.k]\]\s+(\S+)", line)
        if not m:
            continue
        n, dso, sym = int(m.group(1)), m.group(2).strip(), m.group(3)
        jit = dso.startswith("[JIT]")
        dsos["JIT" if jit else dso] += n
        if jit and sym.startswith("0x"):
            counts[int(sym, 16)] = counts.get(int(sym, 16), 0) + n
    total = max(sum(dsos.values()), 1)
    return ({a: 100.0 * n / total for a, n in counts.items()},
            collections.Counter({k: 100.0 * n / total for k, n in dsos.items()}))


def disassemble(pid, hot):
    """gdb's disassembly of every 4-KiB-connected run of hot addresses, from its first hot instruction."""
    runs = []
    for a in sorted(hot):
        if runs and a - runs[-1][1] < 4096:
            runs[-1][1] = a
        else:
            runs.append([a, a])
    ins = {}
    for start, end in runs:
        count = (end - start) // 2 + 64
        out = subprocess.run(["gdb", "-p", str(pid), "-batch", "-ex", f"x/{count}i {start:#x}"],
                             capture_output=True, text=True).stdout
        for line in out.splitlines():
            m = re.match(r"\s*(?:=>)?\s*(0x[0-9a-f]+)(?: <[^>]*>)?:\s*(.*)", line)
            if m:
                ins[int(m.group(1), 16)] = m.group(2).strip()
    return ins


def lane_loops(ins):
    """(first, end) address ranges of lavapipe's per-lane loops: `xor r, r` … `cmp $LANES, r; jae end`, LANES 4
    (mislab's default 128-bit code, docs/platform-notes.md), 8 or 16."""
    addrs = sorted(ins)
    loops = []
    for i, a in enumerate(addrs[:-1]):
        m = re.match(r"cmp\s+\$0x(?:4|8|10),(%e\w\w|%r\d+d)$", ins[a])
        j = re.search(r"jae\s+0x([0-9a-f]+)", ins[addrs[i + 1]])
        if not (m and j):
            continue
        reg, k = m.group(1), i
        while k > 0 and i - k < 400 and not re.match(rf"xor\s+{re.escape(reg)},{re.escape(reg)}$", ins[addrs[k]]):
            k -= 1
        loops.append((addrs[k], int(j.group(1), 16)))
    return loops


def classify(ins, hot, loops):
    addrs = sorted(ins)
    kinds, counts, seen = collections.Counter(), collections.Counter(), set()
    for first, end in loops:
        body = [b for b in addrs if first <= b < end and b not in seen]
        seen.update(body)
        text = " ".join(ins[b] for b in body) + " "
        pct = sum(hot.get(b, 0.0) for b in body)
        slots = sorted(set(re.findall(r"mov\s+(0x[0-9a-f]+)\(%r\w+\),%r\w+\s", text)))
        loads = len(re.findall(r"vpbroadcast[dq]\s+\(%r", text))
        stores = len(re.findall(r"mov\s+%\w+,\(%r\w+,%r\w+,[14]\)", text))
        if slots:
            kind = f"storage load, slot {','.join(slots)}, {loads} components"
        elif stores:
            kind = f"workgroup-memory store, {stores} components"
        elif loads:
            kind = f"workgroup-memory load, {loads} components"
        else:
            kind = "other per-lane loop"
        kinds[kind] += pct
        counts[kind] += 1
    return kinds, counts


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--warm", type=float, default=10.0, help="seconds to wait before sampling (compilation)")
    ap.add_argument("--seconds", type=float, default=6.0, help="seconds to sample")
    ap.add_argument("--keep", help="also write PREFIX.hot (address, %%) and PREFIX.asm (annotated disassembly)")
    ap.add_argument("command", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    cmd = a.command[1:] if a.command[:1] == ["--"] else a.command
    if not cmd:
        ap.error("give the command to profile after --")
    env = dict(os.environ)
    env.pop("XDG_RUNTIME_DIR", None)
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    try:
        time.sleep(a.warm)
        if proc.poll() is not None:
            sys.exit(f"the command ended (exit {proc.returncode}) before sampling began: give it more work")
        with tempfile.TemporaryDirectory() as tmp:
            data = os.path.join(tmp, "perf.data")
            subprocess.run(["perf", "record", "-F", "2000", "-p", str(proc.pid), "-o", data, "--", "sleep",
                            str(a.seconds)], capture_output=True, check=True)
            if proc.poll() is not None:
                sys.exit("the command ended while being sampled: give it more work")
            hot, dsos = hot_addresses(data)
        ins = disassemble(proc.pid, hot)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    loops = lane_loops(ins)
    kinds, counts = classify(ins, hot, loops)
    jit = sum(hot.values())
    seen = sum(p for addr, p in hot.items() if addr in ins)
    print("samples by object: " + ", ".join(f"{k} {v:.1f} %" for k, v in dsos.most_common(4)))
    print(f"JIT code: {jit:.1f} % of samples, {seen:.1f} % disassembled; in per-lane loops: {sum(kinds.values()):.1f} %")
    for kind, pct in kinds.most_common():
        if pct >= 0.3:
            print(f"  {pct:5.1f} %  {counts[kind]:3d} loops  {kind}")
    if sum(kinds.values()) < 1.0:
        # Mesa 25 unrolls the lane loop (a block per lane, no counter): the loads are there, this shape is not.
        print("  no per-lane loops of Mesa 22.3's shape found (Mesa 25 unrolls them); --keep PREFIX keeps the "
              "annotated disassembly to read")
    if a.keep:
        with open(a.keep + ".hot", "w") as f:
            for addr, p in sorted(hot.items(), key=lambda x: -x[1]):
                f.write(f"{p:.2f}% {addr:#x}\n")
        with open(a.keep + ".asm", "w") as f:
            for addr in sorted(ins):
                f.write(f"{hot.get(addr, 0.0):6.2f} {addr:#x} {ins[addr]}\n")


if __name__ == "__main__":
    main()
