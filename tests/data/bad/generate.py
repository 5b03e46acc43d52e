#!/usr/bin/env python3
"""Writes the bad-input corpus that tests/bad_input.rs runs `mislab render` on, and its MANIFEST.tsv.

    python3 tests/data/bad/generate.py        (standard library only; deterministic: fixed seeds)

Every case is declared here with the outcome it must have, so the corpus and its expectations cannot drift
apart. The hand-written cases (one defect each, sections 1-4) are spelled out literally; the systematic bulk
(section 5: truncations at many offsets, byte garbling at seeded positions, wrong magic variants) is derived
from small valid base files that this script also writes (a cube .glb, a triangle .gltf, a 16x8 .hdr / .exr,
PNG textures), none of them copied from third-party data. A generated case is kept only when its outcome can
be predicted here (the script simulates the GLB container rules, checks JSON syntax with Python's parser,
computes the exact out-of-range index a garbled byte produces, ...); anything else is not emitted.

MANIFEST.tsv columns (tab-separated; '#' starts a comment line):
    file      path relative to this directory
    mode      scene: `mislab render FILE ...`; env: `mislab render furnace --env FILE ...`
    expect    error   exit code 2, stderr names the file and contains `substring`, no image left behind
              warning exit code 0 (renders), stderr has "warning:" and contains `substring`
              ok      exit code 0 (renders), no warning
    substring text the message must contain (describes the problem, e.g. "index 57 at position 2")
    args      optional extra command-line arguments, space-separated

Files under aux/ are not cases: they are the buffers, images, maps and glTF files the cases refer to.
"""

import base64
import json
import os
import random
import shutil
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
# Directories this script owns (rewritten from scratch on every run).
OWNED = [
    "aux", "gltf", "glb", "texture", "toml", "env",
    "gen-glb-trunc", "gen-gltf-trunc", "gen-bin-trunc", "gen-png-trunc", "gen-hdr-trunc", "gen-exr-trunc",
    "gen-glb-garble", "gen-gltf-garble", "gen-hdr-garble", "gen-exr-garble", "gen-magic", "hostile",
]
MANIFEST = []
for _d in OWNED:
    shutil.rmtree(os.path.join(HERE, _d), ignore_errors=True)


def write(rel, data):
    path = os.path.join(HERE, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    if isinstance(data, str):
        data = data.encode("utf-8")
    with open(path, "wb") as f:
        f.write(data)


def case(rel, data, expect, substring="", mode=None, args=""):
    """A corpus file and what `mislab render` must do with it."""
    assert expect in ("error", "warning", "ok"), expect
    assert expect != "error" or substring, rel
    assert "\t" not in substring and "\n" not in substring
    assert rel not in [m[0] for m in MANIFEST], rel
    if mode is None:
        mode = "env" if rel.lower().endswith((".hdr", ".exr")) else "scene"
    text = data if isinstance(data, str) else data.decode("utf-8", "replace")
    if rel.endswith(".gltf") and '"../aux' in text and "--allow-outside-paths" not in args:
        # These cases test something else and reach aux/ by design: glTF URIs that leave the file's
        # directory are refused without the flag (section 6 tests that).
        args = (args + " --allow-outside-paths").strip()
    write(rel, data)
    MANIFEST.append((rel, mode, expect, substring, args))


def aux(name, data):
    write("aux/" + name, data)


# ---------------------------------------------------------------------------------------------------------
# Encoders (minimal, stdlib only)

def b64uri(data):
    return "data:application/octet-stream;base64," + base64.b64encode(data).decode()


def to_json(obj):
    return json.dumps(obj, separators=(",", ":"), ensure_ascii=False)


def pad4(data, fill):
    return data + fill * (-len(data) % 4)


def chunk(kind, data):
    return struct.pack("<II", len(data), kind) + data


JSON_CHUNK, BIN_CHUNK = 0x4E4F534A, 0x004E4942


def glb(doc, bin_data, version=2):
    body = chunk(JSON_CHUNK, pad4(to_json(doc).encode(), b" "))
    if bin_data is not None:
        body += chunk(BIN_CHUNK, pad4(bin_data, b"\0"))
    return struct.pack("<4sII", b"glTF", version, 12 + len(body)) + body


def png(width, height, rows=None, color_type=0):
    """8-bit grey (0) or RGBA (6) PNG; rows = list of byte rows (default: a grey ramp)."""
    channels = {0: 1, 2: 3, 6: 4}[color_type]
    if rows is None:
        rows = [bytes((x * 37 + y * 11) % 256 for x in range(width * channels)) for y in range(height)]
    raw = b"".join(b"\0" + r for r in rows)

    def pchunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", width, height, 8, color_type, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + pchunk(b"IHDR", ihdr) + pchunk(b"IDAT", zlib.compress(raw, 9)) + pchunk(b"IEND", b"")


def hdr_pixels(w, h):
    # RGBE texels that are neither run-length markers (1,1,1,e) nor new-RLE scanline starts (2,2,<128,e).
    return [[(40 + 7 * x + 3 * y, 90 + 5 * x, 120 + 2 * y, 128 + (x + y) % 3) for x in range(w)] for y in range(h)]


def hdr(w=16, h=8, header=None, rle=False, pixels=None):
    """Radiance RGBE: flat (uncompressed) scanlines, or new-style RLE (literal runs only)."""
    if header is None:
        header = f"#?RADIANCE\n# mislab bad-input corpus\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n"
    out = bytearray(header.encode("latin-1"))
    for row in pixels if pixels is not None else hdr_pixels(w, h):
        if rle:
            out += bytes([2, 2, w >> 8, w & 255])
            for c in range(4):
                values = [p[c] for p in row]
                for i in range(0, len(values), 128):
                    part = values[i:i + 128]
                    out.append(len(part))
                    out += bytes(part)
        else:
            for p in row:
                out += bytes(p)
    return bytes(out)


def exr_attr(name, kind, value):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def exr(w=16, h=8, channels="BGR", pixel_type=2, compression=0, window=None, values=None, version=2,
        magic=b"\x76\x2f\x31\x01", line_order=0, offsets=None):
    """Scanline OpenEXR, no compression (one scanline per chunk), FLOAT (2) or HALF (1) channels."""
    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", pixel_type, 0, 1, 1) for c in channels) + b"\0"
    x0, y0, x1, y1 = window if window else (0, 0, w - 1, h - 1)
    head = magic + struct.pack("<I", version)
    head += exr_attr("channels", "chlist", chlist)
    head += exr_attr("compression", "compression", bytes([compression]))
    head += exr_attr("dataWindow", "box2i", struct.pack("<4i", x0, y0, x1, y1))
    head += exr_attr("displayWindow", "box2i", struct.pack("<4i", x0, y0, x1, y1))
    head += exr_attr("lineOrder", "lineOrder", bytes([line_order]))
    head += exr_attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
    head += exr_attr("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0))
    head += exr_attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
    head += b"\0"
    fmt = "f" if pixel_type == 2 else "e"
    blocks = []
    for y in range(h):
        line = b""
        for c in range(len(channels)):
            row = [values(x, y, c) if values else 0.1 * (c + 1) + 0.01 * x + 0.02 * y for x in range(w)]
            line += struct.pack(f"<{w}{fmt}", *row)
        blocks.append(struct.pack("<ii", y0 + y, len(line)) + line)
    at, table = len(head) + 8 * h, []
    for b in blocks:
        table.append(at)
        at += len(b)
    if offsets:
        table = offsets(table)
    return head + b"".join(struct.pack("<Q", o) for o in table) + b"".join(blocks)


# ---------------------------------------------------------------------------------------------------------
# Valid bases

def f32s(values):
    return b"".join(struct.pack("<f", v) for v in values)


def tri_buffer(positions=None, indices=(0, 1, 2), index_fmt="H", normals=None):
    """positions (3 x vec3) | indices (padded to 4) | normals (3 x vec3)."""
    positions = positions or [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    normals = normals or [(0, 0, 1)] * len(positions)
    data = f32s([c for p in positions for c in p])
    idx = pad4(b"".join(struct.pack("<" + index_fmt, i) for i in indices), b"\0")
    return data + idx + f32s([c for n in normals for c in n]), len(data), len(idx)


def tri(emissive=True, buffer=None):
    """A valid glTF: one counter-clockwise triangle (normal +Z), indexed, with normals and an emissive
    material (so it renders without a no-lights warning). The buffer is an embedded base64 data URI."""
    data, plen, ilen = buffer or tri_buffer()
    doc = {
        "asset": {"version": "2.0", "generator": "mislab bad-input corpus"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "tri"}],
        "meshes": [{"name": "Tri", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 2}, "indices": 1,
                                                   "material": 0}]}],
        "materials": [{"name": "glow", "emissiveFactor": [1, 1, 1]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": plen},
            {"buffer": 0, "byteOffset": plen, "byteLength": 6},
            {"buffer": 0, "byteOffset": plen + ilen, "byteLength": len(data) - plen - ilen},
        ],
        "buffers": [{"byteLength": len(data), "uri": b64uri(data)}],
    }
    if not emissive:
        del doc["materials"]
        del doc["meshes"][0]["primitives"][0]["material"]
    return doc


TRI_BIN = tri_buffer()[0]  # 80 bytes


def cube_bin():
    """24 vertices (4 per face), normals, 36 u16 indices: positions @0 (288 B), normals @288, indices @576."""
    positions, normals, indices = [], [], []
    for axis in range(3):
        for sign in (1, -1):
            n = [0, 0, 0]
            n[axis] = sign
            u, v = [0, 0, 0], [0, 0, 0]
            u[(axis + 1) % 3], v[(axis + 2) % 3] = 1, 1
            base = len(positions)
            for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                positions.append([0.5 * (n[i] + su * u[i] + sv * v[i]) for i in range(3)])
                normals.append(n)
            quad = [0, 1, 2, 0, 2, 3] if sign > 0 else [0, 2, 1, 0, 3, 2]
            indices += [base + q for q in quad]
    data = f32s([c for p in positions for c in p]) + f32s([c for n in normals for c in n])
    return data + b"".join(struct.pack("<H", i) for i in indices)


CUBE_BIN = cube_bin()  # 648 bytes
CUBE_INDEX_AT = 576


def cube_doc():
    return {
        "asset": {"version": "2.0", "generator": "mislab bad-input corpus"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "cube", "rotation": [0.2, 0.3, 0, 0.9327379]}],
        "meshes": [{"name": "Cube", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2,
                                                    "material": 0}]}],
        "materials": [{"name": "glow", "emissiveFactor": [1, 0.5, 0.25]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 24, "type": "VEC3",
             "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]},
            {"bufferView": 0, "byteOffset": 288, "componentType": 5126, "count": 24, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 576, "byteStride": 12},
            {"buffer": 0, "byteOffset": 576, "byteLength": 72},
        ],
        "buffers": [{"byteLength": 648}],
    }


CUBE_GLB = glb(cube_doc(), CUBE_BIN)
HDR_FLAT = hdr()
HDR_RLE = hdr(rle=True)
EXR_BASE = exr()


def edited(doc, edit):
    doc = json.loads(json.dumps(doc))
    edit(doc)
    return doc


def j(text):
    return json.loads(text)


# ---------------------------------------------------------------------------------------------------------
# Simulations used to predict the outcome of generated cases

def glb_container(data, is_glb_ext=True):
    """The loader's container rules (src/scene/gltf.rs: split_container / parse_glb). Returns
    ("error", substring) or ("ok", json_bytes, bin_bytes_or_None)."""
    if not data.startswith(b"glTF"):
        stripped = data.lstrip(b" \t\r\n\x0c")
        if is_glb_ext and not stripped.startswith(b"{"):
            return ("error", "expected the magic bytes")
        return ("json", data)
    if len(data) < 12:
        return ("error", "shorter than the 12-byte header")
    version, total = struct.unpack_from("<II", data, 4)
    if version != 2:
        return ("error", f"GLB container version {version} is not supported")
    if total > len(data):
        return ("error", f"the header declares {total} bytes but the file has {len(data)}")
    if total < 12:
        return ("error", f"declares a total length of {total} bytes")
    json_chunk, bin_chunk, at = None, None, 12
    while at < total:
        if total - at < 8:
            return ("error", f"incomplete chunk header at byte {at}")
        length, kind = struct.unpack_from("<II", data, at)
        start = at + 8
        if length > total - start:
            return ("error", f"a chunk at byte {at} declares {length} bytes but only {total - start} remain")
        body = data[start:start + length]
        if kind == JSON_CHUNK and json_chunk is None:
            json_chunk = body
        elif kind == BIN_CHUNK and bin_chunk is None:
            bin_chunk = body
        at = start + length
    if json_chunk is None:
        return ("error", "GLB file has no JSON chunk")
    return ("ok", json_chunk, bin_chunk)


def json_fails(data):
    try:
        json.loads(data.decode("utf-8"))
        return False
    except (ValueError, UnicodeDecodeError):
        return True


# =========================================================================================================
# 1. glTF JSON, one defect each (triangle base with an embedded buffer)

aux("tri.bin", TRI_BIN)
aux("one.png", png(1, 1, [bytes([200, 120, 40, 255])], color_type=6))
aux("ramp.png", png(8, 8))
aux("wide-16385x1.png", png(16385, 1))
aux("tall-1x16385.png", png(1, 16385))
aux("zero-0x0.png", png(0, 0, rows=[]))
aux("not-a-png.png", b"this is a text file pretending to be a PNG image\n")
aux("truncated.png", png(8, 8)[:40])
_ramp = png(8, 8)
aux("bad-zlib.png", _ramp[:_ramp.index(b"IDAT") + 4] + b"\xff\xff" + _ramp[_ramp.index(b"IDAT") + 6:])
aux("empty.png", b"")
aux("fake.jpg", b"\xff\xd8\xff\xe0\0\x10JFIF\0\x01\x01\0\0\x01\0\x01\0\0\xff\xdb\0\x43\0" + bytes(20))
aux("base.hdr", HDR_FLAT)
aux("truncated.hdr", HDR_FLAT[:200])
aux("bad-magic.exr", b"\x76\x2f\x31\x02" + EXR_BASE[4:])
aux("sky.png", png(16, 8))
aux("valid.gltf", to_json(tri()))
aux("bad-index.gltf", to_json(tri(buffer=tri_buffer(indices=(0, 1, 57)))))
aux("garbage.gltf", "{ this is not json")
aux("scene.toml", "[camera]\nposition = [0, 0, 5]\n")


def g(name, edit, expect, substring="", args=""):
    doc = edited(tri(), edit)
    case(f"gltf/{name}.gltf", to_json(doc), expect, substring, args=args)


def set_(path, value):
    def edit(doc):
        target = doc
        for k in path[:-1]:
            target = target[k]
        target[path[-1]] = value
    return edit


def many(*edits):
    def edit(doc):
        for e in edits:
            e(doc)
    return edit


ATTR = ["meshes", 0, "primitives", 0, "attributes"]
PRIM = ["meshes", 0, "primitives", 0]

# Accessors: existence, type, component type, counts, ranges, strides.
g("accessor-missing", set_(ATTR + ["POSITION"], 7), "error",
  "accessor 7 (POSITION of mesh 'Tri' primitive 0) does not exist (the file has 3 accessors)")
g("accessor-missing-normal", set_(ATTR + ["NORMAL"], 70), "error", "accessor 70 (NORMAL of mesh 'Tri' primitive 0) does not exist")
g("accessor-missing-indices", set_(PRIM + ["indices"], 3), "error", "accessor 3 (indices of mesh 'Tri' primitive 0) does not exist")
g("accessor-type-vec2-position", set_(["accessors", 0, "type"], "VEC2"), "error", "type VEC2 is not valid for POSITION (expected VEC3)")
g("accessor-type-vec4-position", set_(["accessors", 0, "type"], "VEC4"), "error", "type VEC4 is not valid for POSITION (expected VEC3)")
g("accessor-type-mat4-indices", set_(["accessors", 1, "type"], "MAT4"), "error", "type MAT4 is not valid for indices (expected SCALAR)")
g("accessor-type-scalar-normal", set_(["accessors", 2, "type"], "SCALAR"), "error", "type SCALAR is not valid for NORMAL (expected VEC3)")
g("accessor-type-unknown", set_(["accessors", 0, "type"], "VEC7"), "error", "invalid accessor type")
g("accessor-component-u16-position", set_(["accessors", 0, "componentType"], 5123), "error",
  "componentType 5123 (U16) is not valid for POSITION (expected FLOAT)")
g("accessor-component-i8-normal", set_(["accessors", 2, "componentType"], 5120), "error", "componentType 5120 (I8) is not valid for NORMAL")
g("accessor-component-float-indices", set_(["accessors", 1, "componentType"], 5126), "error",
  "componentType 5126 (F32) is not valid for indices (expected UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT)")
g("accessor-component-i16-indices", set_(["accessors", 1, "componentType"], 5122), "error", "componentType 5122 (I16) is not valid for indices")
g("accessor-component-unknown", set_(["accessors", 0, "componentType"], 9999), "error", "invalid componentType")
g("accessor-normalized-position", set_(["accessors", 0, "normalized"], True), "error", "(normalized F32) is not valid for POSITION")
g("accessor-count-past-view", set_(["accessors", 0, "count"], 10), "error",
  "10 elements of 12 bytes (stride 12) from byteOffset 0 do not fit in bufferView 0 (36 bytes)")
g("accessor-offset-past-view", set_(["accessors", 0, "byteOffset"], 4), "error",
  "3 elements of 12 bytes (stride 12) from byteOffset 4 do not fit in bufferView 0 (36 bytes)")
g("accessor-offset-huge", set_(["accessors", 2, "byteOffset"], 4294967290), "error", "from byteOffset 4294967290 do not fit in bufferView 2")
g("accessor-indices-past-view", set_(["accessors", 1, "count"], 4), "error",
  "4 elements of 2 bytes (stride 2) from byteOffset 0 do not fit in bufferView 1 (6 bytes)")
g("accessor-count-huge", set_(["accessors", 0, "count"], 4000000000), "error", "count 4000000000 exceeds the limit of 67108864 elements")
g("accessor-count-huge-zeros", set_(["accessors", 0], {"componentType": 5126, "count": 4000000000, "type": "VEC3"}), "error",
  "accessor 0 (POSITION of mesh 'Tri' primitive 0): count 4000000000 exceeds the limit of 67108864 elements")
g("accessor-zeros-wrong-type", set_(["accessors", 1], {"componentType": 5126, "count": 3, "type": "SCALAR"}), "error",
  "accessor 1 (indices of mesh 'Tri' primitive 0): componentType 5126 (F32) is not valid for indices")
g("accessor-count-negative", set_(["accessors", 0, "count"], -3), "error", "invalid glTF JSON")
g("accessor-count-float", set_(["accessors", 0, "count"], 2.5), "error", "invalid glTF JSON")
g("accessor-normal-count-mismatch", set_(["accessors", 2, "count"], 2), "error",
  "accessor 2 (NORMAL of mesh 'Tri' primitive 0): count 2 differs from the POSITION count 3")
g("accessor-uv-count-mismatch", many(set_(ATTR + ["TEXCOORD_0"], 3),
                                     lambda d: d["accessors"].append({"bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC2"})),
  "error", "accessor 3 (TEXCOORD_0 of mesh 'Tri' primitive 0): count 2 differs from the POSITION count 3")
g("accessor-uv-u8-not-normalized", many(set_(ATTR + ["TEXCOORD_0"], 3),
                                        lambda d: d["accessors"].append({"bufferView": 2, "componentType": 5121, "count": 3, "type": "VEC2"})),
  "error", "componentType 5121 (U8) is not valid for TEXCOORD_0")
g("stride-smaller-than-element", set_(["bufferViews", 0, "byteStride"], 4), "error",
  "accessor 0 (POSITION of mesh 'Tri' primitive 0): byteStride 4 is smaller than the element size 12")
g("stride-zero", set_(["bufferViews", 2, "byteStride"], 0), "error", "byteStride 0 is smaller than the element size 12")
g("stride-past-view", set_(["bufferViews", 0, "byteStride"], 16), "error",
  "3 elements of 12 bytes (stride 16) from byteOffset 0 do not fit in bufferView 0 (36 bytes)")
g("bufferview-missing", set_(["accessors", 1, "bufferView"], 9), "error", "bufferView 9 does not exist (the file has 3 bufferViews)")
g("bufferview-past-buffer", set_(["bufferViews", 2, "byteLength"], 400), "error",
  "bufferView 2 (bytes 44..444) extends past the end of buffer 0 (80 bytes)")
g("bufferview-offset-past-buffer", set_(["bufferViews", 0, "byteOffset"], 1000), "error",
  "bufferView 0 (bytes 1000..1036) extends past the end of buffer 0 (80 bytes)")
g("bufferview-length-overflow", set_(["bufferViews", 0, "byteLength"], 18446744073709551615), "error", "extends past the end of buffer 0")
g("bufferview-buffer-missing", set_(["bufferViews", 0, "buffer"], 4), "error", "bufferView 0 names buffer 4, which does not exist")
# Indices.
g("index-out-of-range", lambda d: d.update(tri(buffer=tri_buffer(indices=(0, 1, 57)))), "error",
  "accessor 1 (indices of mesh 'Tri' primitive 0): index 57 at position 2 is out of range (the primitive has 3 vertices)")
g("index-out-of-range-u8", lambda d: d.update(edited(tri(buffer=tri_buffer(indices=(200, 1, 2), index_fmt="B")),
                                                      set_(["accessors", 1, "componentType"], 5121))), "error",
  "index 200 at position 0 is out of range (the primitive has 3 vertices)")
g("index-out-of-range-u32", lambda d: d.update(edited(tri(buffer=tri_buffer(indices=(0, 4294967295, 2), index_fmt="I")),
                                                       many(set_(["accessors", 1, "componentType"], 5125),
                                                            set_(["bufferViews", 1, "byteLength"], 12)))), "error",
  "index 4294967295 at position 1 is out of range")
g("index-equal-to-count", lambda d: d.update(tri(buffer=tri_buffer(indices=(0, 3, 2)))), "error",
  "index 3 at position 1 is out of range (the primitive has 3 vertices)")
g("index-without-positions", many(set_(["accessors", 0, "count"], 2), set_(ATTR, {"POSITION": 0})), "error",
  "index 2 at position 2 is out of range (the primitive has 2 vertices)")
# Sparse accessors.
SPARSE = {"count": 1, "indices": {"bufferView": 1, "byteOffset": 4, "componentType": 5123}, "values": {"bufferView": 2}}
g("sparse-index-out-of-range", many(set_(["accessors", 0, "count"], 2), set_(["accessors", 0, "sparse"], SPARSE),
                                    set_(ATTR, {"POSITION": 0}), set_(PRIM + ["indices"], None),
                                    lambda d: d["meshes"][0]["primitives"][0].pop("indices")),
  "error", "sparse index 2 (entry 0) is out of range: the accessor has 2 elements")
g("sparse-count-too-large", set_(["accessors", 0, "sparse"], dict(SPARSE, count=5)), "error", "sparse count 5 exceeds the accessor count 3")
g("sparse-indices-view-missing", set_(["accessors", 0, "sparse"], dict(SPARSE, indices={"bufferView": 9, "componentType": 5123})),
  "error", "sparse indices: bufferView 9 does not exist")
g("sparse-values-past-view", set_(["accessors", 0, "sparse"], dict(SPARSE, count=3, indices={"bufferView": 1, "componentType": 5123},
                                                                    values={"bufferView": 1})), "error",
  "sparse values: 3 elements of 12 bytes (stride 12) from byteOffset 0 do not fit in bufferView 1 (6 bytes)")
g("sparse-indices-float", set_(["accessors", 0, "sparse"], dict(SPARSE, indices={"bufferView": 1, "componentType": 5126})),
  "error", "sparse indices have an invalid componentType")
# Buffers and URIs.
g("buffer-short", set_(["buffers", 0, "byteLength"], 1000), "error", "buffer 0: byteLength is 1000 but only 80 bytes of data are present")
g("buffer-no-uri", lambda d: d["buffers"][0].pop("uri"), "error", "buffer 0 has no uri (only a .glb's first buffer may omit it)")
g("buffer-missing-bin", set_(["buffers", 0, "uri"], "nothere.bin"), "error", "buffer 0: cannot read")
g("buffer-missing-bin-named", lambda d: d["buffers"][0].update(uri="missing%20file.bin", name="geometry"), "error",
  "buffer 0 'geometry': cannot read")
g("buffer-uri-directory", set_(["buffers", 0, "uri"], "../aux"), "error", "buffer 0: cannot read")
g("buffer-external-short", lambda d: d["buffers"][0].update(uri="../aux/tri.bin", byteLength=81), "error",
  "buffer 0: byteLength is 81 but only 80 bytes of data are present")
g("buffer-bad-base64", set_(["buffers", 0, "uri"], "data:application/octet-stream;base64,@@@@"), "error", "invalid base64 in data URI")
g("buffer-truncated-base64", set_(["buffers", 0, "uri"], b64uri(TRI_BIN)[:-7]), "error", "invalid base64 in data URI")
g("buffer-data-uri-not-base64", set_(["buffers", 0, "uri"], "data:application/octet-stream,abc"), "error",
  "is not base64-encoded (glTF requires ';base64')")
g("buffer-data-uri-no-comma", set_(["buffers", 0, "uri"], "data:application/octet-stream;base64"), "error", "malformed data URI (no ',')")
g("buffer-remote-uri", set_(["buffers", 0, "uri"], "https://example.com/tri.bin"), "error",
  "is neither a relative file path nor a data: URI (nothing is downloaded)")
g("buffer-byte-length-string", set_(["buffers", 0, "byteLength"], "80"), "error", "invalid glTF JSON")
# Node graph.
g("node-cycle-self", set_(["nodes", 0, "children"], [0]), "error", "cycle")
g("node-cycle-two", set_(["nodes"], [{"mesh": 0, "children": [1]}, {"children": [0]}]), "error", "cycle")
g("node-cycle-three", set_(["nodes"], [{"mesh": 0, "children": [1]}, {"children": [2]}, {"children": [1]}]), "error", "cycle")
g("node-cycle-unreachable", set_(["nodes"], [{"mesh": 0}, {"children": [2]}, {"children": [1]}]), "error", "cycle")
g("node-cycle-no-scenes", many(set_(["nodes"], [{"mesh": 0, "children": [1]}, {"children": [0]}]),
                               lambda d: d.pop("scenes"), lambda d: d.pop("scene")), "error", "cycle")
g("node-missing-root", set_(["scenes", 0, "nodes"], [5]), "error", "node 5 does not exist (the file has 1 nodes)")
g("node-missing-child", set_(["nodes", 0, "children"], [9]), "error", "9 does not exist (the file has 1 nodes)")
g("node-too-deep", set_(["nodes"], [{"children": [i + 1]} for i in range(599)] + [{"mesh": 0}]), "error",
  "the node hierarchy is deeper than 512 levels")
g("node-instance-bomb", set_(["nodes"], [{"children": [i + 1, i + 1]} for i in range(40)] + [{"mesh": 0}]), "error",
  "node instances")
g("node-mesh-missing", set_(["nodes", 0, "mesh"], 3), "error", "mesh 3 does not exist (the file has 1 meshes)")
g("node-camera-missing", set_(["nodes", 0, "camera"], 2), "error", "camera 2 does not exist (the file has 0 cameras)")
g("node-light-missing", set_(["nodes", 0, "extensions"], {"KHR_lights_punctual": {"light": 0}}), "error",
  "KHR_lights_punctual light 0 does not exist (the file has 0)")
g("node-rotation-zero", set_(["nodes", 0, "rotation"], [0, 0, 0, 0]), "error", "is not a valid quaternion")
g("node-rotation-inf", set_(["nodes", 0, "rotation"], [1e39, 0, 0, 1]), "error", "is not a valid quaternion")
g("node-translation-inf", set_(["nodes", 0, "translation"], [1e39, 0, 0]), "error", "node 0 'tri': the transform contains non-finite values")
g("node-scale-inf", set_(["nodes", 0, "scale"], [1, -1e39, 1]), "error", "the transform contains non-finite values")
g("node-matrix-inf", set_(["nodes", 0, "matrix"], [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 3e38 * 10, 1]), "error",
  "the transform contains non-finite values")
g("node-matrix-short", set_(["nodes", 0, "matrix"], [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0]), "error", "invalid glTF JSON")
g("node-index-negative", set_(["nodes", 0, "mesh"], -1), "error", "invalid glTF JSON")
g("node-index-string", set_(["nodes", 0, "mesh"], "0"), "error", "invalid glTF JSON")
# Scenes.
g("scene-default-missing", set_(["scene"], 3), "error", "scene 3 is the default scene, but the file has 1 scene(s)")
g("scene-requested-missing", lambda d: None, "error", "scene 4 was requested, but the file has 1 scene(s)", args="--gltf-scene 4")
g("scene-empty", set_(["scenes", 0, "nodes"], []), "error", "the scene is empty: no geometry, no lights and no environment")
g("scene-none-and-no-nodes", many(lambda d: d.pop("scenes"), lambda d: d.pop("scene"), set_(["nodes"], [])), "error", "the scene is empty: no geometry, no lights and no environment")
# Meshes, materials, modes.
g("mesh-missing-material", set_(PRIM + ["material"], 3), "error", "material 3 does not exist (the file has 1 materials)")
g("mesh-invalid-mode", set_(PRIM + ["mode"], 9), "error", "mesh 'Tri' primitive 0: invalid primitive mode")
g("mesh-points-only", set_(PRIM + ["mode"], 0), "error", "the scene is empty: no geometry, no lights and no environment")
g("mesh-no-position", set_(ATTR, {"NORMAL": 2}), "error", "the scene is empty: no geometry, no lights and no environment")
g("mesh-primitives-missing", lambda d: d["meshes"][0].pop("primitives"), "error", "invalid glTF JSON")
# Extensions.
for ext in ["EXT_meshopt_compression", "KHR_draco_mesh_compression", "KHR_mesh_quantization", "KHR_texture_basisu",
            "VENDOR_unknown_extension"]:
    g(f"required-{ext}", set_(["extensionsRequired"], [ext]), "error",
      f"the file requires the glTF extension {ext}, which is not supported")
g("required-after-supported", set_(["extensionsRequired"], ["KHR_lights_punctual", "EXT_mystery"]), "error",
  "requires the glTF extension EXT_mystery")
g("used-unknown", set_(["extensionsUsed"], ["EXT_mystery"]), "warning", "ignoring unsupported glTF extension(s): EXT_mystery")
# The document itself.
g("asset-missing", lambda d: d.pop("asset"), "error", "invalid glTF JSON")
g("asset-version-1", set_(["asset", "version"], "1.0"), "error", "glTF version '1.0' is not supported (only 2.x)")
g("asset-version-3", set_(["asset", "version"], "3.0"), "error", "glTF version '3.0' is not supported")
g("asset-version-number", set_(["asset", "version"], 2.0), "error", "invalid glTF JSON")
# Non-finite and absurd values that are repaired (with a warning) rather than refused.
NAN_POS = tri_buffer(positions=[(0, 0, 0), (1, 0, 0), (0, 1, 0), (float("nan"), 0, 0)], indices=(0, 1, 2, 1, 3, 2))
g("positions-nan-partial", lambda d: d.update(edited(tri(buffer=NAN_POS), many(
    set_(["accessors", 0, "count"], 4), set_(["accessors", 1, "count"], 6), set_(["bufferViews", 1, "byteLength"], 12),
    set_(["accessors", 2, "count"], 4)))), "error", "non-finite vertex position: vertex 3 is (NaN, 0, 0) (POSITION holds NaN/Inf")
INF_POS = tri_buffer(positions=[(float("inf"), 0, 0), (1, 0, 0), (0, float("-inf"), 0)])
g("positions-inf-all", lambda d: d.update(tri(buffer=INF_POS)), "error", "non-finite vertex position: vertex 0 is (inf, 0, 0)")
NAN_NORMALS = tri_buffer(normals=[(float("nan"), 0, 1), (0, 0, 0), (0, 0, 1)])
g("normals-nan", lambda d: d.update(tri(buffer=NAN_NORMALS)), "warning", "zero or non-finite vertex normal(s) regenerated")
g("camera-yfov-inf", many(set_(["cameras"], [{"type": "perspective", "perspective": {"yfov": 1e39, "znear": 0.1}}]),
                          set_(["nodes", 0, "camera"], 0)), "warning", "unusable yfov")
g("material-emission-inf", set_(["materials", 0, "emissiveFactor"], [1e39, 1, 1]), "warning",
  "non-finite factors replaced by the glTF defaults")
g("no-lights", lambda d: d.update(tri(emissive=False)), "warning", "no lights and no environment")
# Accessors without a bufferView are all zeros: 60 million zero positions (or indices) from a few bytes of JSON.
g("positions-implicit-zeros", set_(["accessors", 0], {"componentType": 5126, "count": 60000000, "type": "VEC3"}),
  "error", "the scene is empty: no geometry, no lights and no environment")
g("indices-implicit-zeros", set_(["accessors", 1], {"componentType": 5125, "count": 60000000, "type": "SCALAR"}),
  "error", "the scene is empty: no geometry, no lights and no environment")
# Deeply nested (but valid) JSON loads: no recursion limit trips and the stack does not overflow.
case("gltf/json-nested-deeply.gltf", to_json(tri())[:-1] + ',"extras":' + "[" * 3000 + "]" * 3000 + "}", "ok")

# Textures (textured triangle with UVs: base colour from an image).
UV_BIN = TRI_BIN + f32s([0, 0, 1, 0, 0, 1])


def textured(uri=None, **image):
    doc = tri(buffer=(UV_BIN, 36, 8))
    doc["bufferViews"][2]["byteLength"] = 36
    doc["bufferViews"].append({"buffer": 0, "byteOffset": 80, "byteLength": 24})
    doc["accessors"].append({"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC2"})
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 3
    doc["materials"][0]["pbrMetallicRoughness"] = {"baseColorTexture": {"index": 0}}
    doc["textures"] = [{"source": 0}]
    doc["images"] = [dict({"uri": uri} if uri else {}, **image)]
    return doc


def t(name, doc, expect, substring=""):
    case(f"texture/{name}.gltf", to_json(doc), expect, substring)


t("one-by-one", textured("../aux/one.png"), "ok")
t("ramp-embedded", textured(b64uri(png(8, 8))), "ok")
t("wide-16385x1", textured("../aux/wide-16385x1.png"), "error",
  "image 0 (../aux/wide-16385x1.png): 16385×1 texels exceeds the texture size limit of 16384 texels per side")
t("tall-1x16385", textured("../aux/tall-1x16385.png"), "error", "1×16385 texels exceeds the texture size limit of 16384")
t("zero-size", textured("../aux/zero-0x0.png"), "error", "cannot decode the image")
t("missing-file", textured("../aux/missing.png"), "error", "image 0 (../aux/missing.png): cannot read")
t("missing-percent-encoded", textured("../aux/missing%20image.png"), "error", "missing image.png")
t("not-an-image", textured("../aux/not-a-png.png"), "error", "image 0 (../aux/not-a-png.png): cannot decode the image")
t("truncated-png", textured("../aux/truncated.png"), "error", "cannot decode the image")
t("bad-zlib-png", textured("../aux/bad-zlib.png"), "error", "cannot decode the image: Format error decoding Png: Corrupt deflate stream")
t("empty-file", textured("../aux/empty.png"), "error", "cannot decode the image")
t("fake-jpeg", textured("../aux/fake.jpg"), "error", "cannot decode the image")
t("bad-base64", textured("data:image/png;base64,!!!!"), "error", "invalid base64 in data URI")
t("remote", textured("http://example.com/a.png"), "error", "nothing is downloaded")
t("no-uri-no-view", textured(), "error", "image 0 (image 0): has neither a uri nor a bufferView")
t("view-missing", textured(bufferView=7, mimeType="image/png"), "error", "bufferView 7 does not exist")
t("view-not-an-image", textured(bufferView=0, mimeType="image/png"), "error", "cannot decode the image")
t("image-index-missing", edited(textured("../aux/one.png"), set_(["textures", 0, "source"], 4)), "error",
  "material 0 'glow': image 4 does not exist (the file has 1 images)")
t("texture-index-missing", edited(textured("../aux/one.png"),
                                  set_(["materials", 0, "pbrMetallicRoughness", "baseColorTexture", "index"], 5)),
  "error", "texture 5 does not exist (the file has 1 textures)")
t("sampler-missing", edited(textured("../aux/one.png"), set_(["textures", 0, "sampler"], 2)), "error",
  "sampler 2 does not exist (the file has 0 samplers)")
t("source-missing", edited(textured("../aux/one.png"), lambda d: d["textures"][0].pop("source")), "error", "texture 0 has no source image")
t("transform-inf", edited(textured("../aux/one.png"), set_(
    ["materials", 0, "pbrMetallicRoughness", "baseColorTexture", "extensions"],
    {"KHR_texture_transform": {"scale": [1e39, 1]}})), "warning", "KHR_texture_transform")

# =========================================================================================================
# 2. GLB containers (a cube: positions, normals, 36 u16 indices in the BIN chunk)

case("glb/valid-cube.glb", CUBE_GLB, "ok")


def glb_with(doc=None, bin_data=CUBE_BIN, version=2):
    return glb(doc or cube_doc(), bin_data, version)


def patch(data, at, new):
    return data[:at] + new + data[at + len(new):]


JSON_LEN = struct.unpack_from("<I", CUBE_GLB, 12)[0]
BIN_HEADER_AT = 20 + JSON_LEN
case("glb/version-1.glb", patch(CUBE_GLB, 4, struct.pack("<I", 1)), "error", "GLB container version 1 is not supported (expected 2)")
case("glb/version-0.glb", patch(CUBE_GLB, 4, struct.pack("<I", 0)), "error", "GLB container version 0 is not supported")
case("glb/version-max.glb", patch(CUBE_GLB, 4, struct.pack("<I", 0xFFFFFFFF)), "error", "GLB container version 4294967295")
case("glb/length-past-end.glb", patch(CUBE_GLB, 8, struct.pack("<I", 99999)), "error",
     f"truncated GLB: the header declares 99999 bytes but the file has {len(CUBE_GLB)}")
case("glb/length-max.glb", patch(CUBE_GLB, 8, struct.pack("<I", 0xFFFFFFFF)), "error", "the header declares 4294967295 bytes")
case("glb/length-zero.glb", patch(CUBE_GLB, 8, struct.pack("<I", 0)), "error", "declares a total length of 0 bytes")
case("glb/length-cuts-bin.glb", patch(CUBE_GLB, 8, struct.pack("<I", len(CUBE_GLB) - 4)), "error",
     f"a chunk at byte {BIN_HEADER_AT} declares 648 bytes but only 644 remain")
case("glb/length-cuts-chunk-header.glb", patch(CUBE_GLB, 8, struct.pack("<I", BIN_HEADER_AT + 4)), "error",
     f"truncated GLB: incomplete chunk header at byte {BIN_HEADER_AT}")
case("glb/json-length-past-end.glb", patch(CUBE_GLB, 12, struct.pack("<I", 50000)), "error",
     f"truncated GLB: a chunk at byte 12 declares 50000 bytes but only {len(CUBE_GLB) - 20} remain")
case("glb/json-length-max.glb", patch(CUBE_GLB, 12, struct.pack("<I", 0xFFFFFFFF)), "error", "a chunk at byte 12 declares 4294967295 bytes")
case("glb/json-type-wrong.glb", patch(CUBE_GLB, 16, b"JSOX"), "error", "GLB file has no JSON chunk")
case("glb/bin-type-wrong.glb", patch(CUBE_GLB, BIN_HEADER_AT + 4, b"BIX\0"), "error",
     "buffer 0 has no uri, and the GLB file has no BIN chunk")
case("glb/bin-length-past-end.glb", patch(CUBE_GLB, BIN_HEADER_AT, struct.pack("<I", 700)), "error",
     f"a chunk at byte {BIN_HEADER_AT} declares 700 bytes but only 648 remain")
no_bin = glb_with(bin_data=None)
case("glb/bin-missing.glb", no_bin, "error", "buffer 0 has no uri, and the GLB file has no BIN chunk")
case("glb/bin-short.glb", glb_with(bin_data=CUBE_BIN[:100]), "error", "buffer 0: byteLength is 648 but only 100 bytes of data are present")
case("glb/bin-empty.glb", glb_with(bin_data=b""), "error", "buffer 0: byteLength is 648 but only 0 bytes of data are present")
case("glb/only-bin-chunk.glb", struct.pack("<4sII", b"glTF", 2, 12 + 8 + 648) + chunk(BIN_CHUNK, CUBE_BIN), "error",
     "GLB file has no JSON chunk")
case("glb/header-only.glb", struct.pack("<4sII", b"glTF", 2, 12), "error", "GLB file has no JSON chunk")
case("glb/json-empty.glb", struct.pack("<4sII", b"glTF", 2, 20) + chunk(JSON_CHUNK, b""), "error", "invalid glTF JSON")
case("glb/json-invalid.glb", glb_with(doc=None)[:20] + b"{nope" + glb_with()[25:], "error", "invalid glTF JSON")
case("glb/second-buffer-no-uri.glb", glb_with(edited(cube_doc(), lambda d: d["buffers"].append({"byteLength": 4}))), "error",
     "buffer 1 has no uri (only a .glb's first buffer may omit it)")
case("glb/accessor-past-bin.glb", glb_with(edited(cube_doc(), set_(["accessors", 2, "count"], 1000))), "error",
     "accessor 2 (indices of mesh 'Cube' primitive 0): 1000 elements of 2 bytes (stride 2) from byteOffset 0 do not fit in bufferView 1 (72 bytes)")
case("glb/view-past-bin.glb", glb_with(edited(cube_doc(), set_(["bufferViews", 1, "byteLength"], 720))), "error",
     "bufferView 1 (bytes 576..1296) extends past the end of buffer 0 (648 bytes)")
case("glb/stride-mismatch.glb", glb_with(edited(cube_doc(), set_(["bufferViews", 0, "byteStride"], 24))), "error",
     "accessor 1 (NORMAL of mesh 'Cube' primitive 0): 24 elements of 12 bytes (stride 24) from byteOffset 288 do not fit in bufferView 0 (576 bytes)")
case("glb/stride-too-small.glb", glb_with(edited(cube_doc(), set_(["bufferViews", 0, "byteStride"], 8))), "error",
     "accessor 0 (POSITION of mesh 'Cube' primitive 0): byteStride 8 is smaller than the element size 12")
case("glb/index-57.glb", glb_with(bin_data=patch(CUBE_BIN, CUBE_INDEX_AT + 2 * 5, struct.pack("<H", 57))), "error",
     "accessor 2 (indices of mesh 'Cube' primitive 0): index 57 at position 5 is out of range (the primitive has 24 vertices)")
case("glb/position-nan.glb", glb_with(bin_data=patch(CUBE_BIN, 12 * 4 + 4, struct.pack("<f", float("nan")))), "error",
     "non-finite vertex position")
case("glb/position-inf.glb", glb_with(bin_data=patch(CUBE_BIN, 0, struct.pack("<f", float("inf")))), "error",
     "non-finite vertex position")
case("glb/buffer-uri-missing-file.glb", glb_with(edited(cube_doc(), set_(["buffers", 0, "uri"], "cube.bin"))), "error",
     "buffer 0: cannot read")
case("glb/version-1-json.glb", glb_with(edited(cube_doc(), set_(["asset", "version"], "1.0"))), "error",
     "glTF version '1.0' is not supported")
case("glb/required-extension.glb", glb_with(edited(cube_doc(), set_(["extensionsRequired"], ["KHR_draco_mesh_compression"]))),
     "error", "requires the glTF extension KHR_draco_mesh_compression")
case("glb/cycle.glb", glb_with(edited(cube_doc(), set_(["nodes", 0, "children"], [0]))), "error", "cycle")
case("glb/empty-file.glb", b"", "error", "expected the magic bytes")
case("glb/png-renamed.glb", png(4, 4), "error", "not a binary glTF file: expected the magic bytes \"glTF\"")
case("glb/text.glb", b"this is not a glb at all\n", "error", "expected the magic bytes")

# =========================================================================================================
# 3. TOML scenes (docs/scene-format.md)

VALID_TOML = """\
[camera]
position = [0, 1, 5]
look_at = [0, 0, 0]

[materials.white]
type = "lambert"
reflectance = 0.8

[materials.lamp]
type = "emitter"
emission = 5

[[sphere]]
center = [0, 0, 0]
radius = 1
material = "white"

[[quad]]
corner = [-0.5, 3, -0.5]
edge_u = [1, 0, 0]
edge_v = [0, 0, 1]
material = "lamp"
"""
# The valid scene (lit by the emitting quad), to which most cases append one defective section.
LIT = VALID_TOML


def tm(name, text, expect, substring=""):
    case(f"toml/{name}.toml", text, expect, substring)


tm("valid", VALID_TOML, "ok")
# Syntax.
tm("syntax-unclosed-table-header", "[camera\nposition = [0, 0, 5]\n", "error", "line 1, column 8: invalid table header")
tm("syntax-unclosed-array", "[camera]\nposition = [0, 0, 5\nvfov = 40\n", "error", "line 3")
tm("syntax-unclosed-string", LIT + '[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = "white\n', "error", "line 26")
tm("syntax-missing-value", "[camera]\nposition =\n", "error", "line 2")
tm("syntax-bare-word", "[camera]\nposition = here\n", "error", "line 2")
tm("syntax-duplicate-key", "[camera]\nposition = [0, 0, 5]\nposition = [0, 0, 6]\n", "error", "duplicate key `position`")
tm("syntax-duplicate-table", "[camera]\nposition = [0, 0, 5]\n[camera]\nposition = [0, 0, 6]\n", "error", "duplicate key `camera`")
tm("syntax-table-then-array", LIT + "[sphere]\nradius = 1\n", "error", "line 23")
tm("syntax-bad-escape", LIT.replace('"white"\n\n[[quad]]', '"wh\\qite"\n\n[[quad]]'), "error", "line 16")
tm("syntax-bad-number", "[camera]\nposition = [0, 1.2.3, 5]\n", "error", "line 2")
tm("syntax-leading-zero", "[camera]\nposition = [0, 01, 5]\n", "error", "line 2")
tm("syntax-inline-table-newline", LIT + '[[include]]\ngltf = "../aux/valid.gltf"\nrotate = { axis = [0, 1, 0],\n angle = 30 }\n', "error", "line 25")
tm("syntax-key-without-equals", "[camera]\nposition [0, 0, 5]\n", "error", "line 2")
tm("syntax-json", '{"camera": {"position": [0, 0, 5]}}\n', "error", "line 1")
tm("syntax-nul-byte", "[camera]\nposition = [0, 0, 5]\x00\n", "error", "line 2")
case("toml/encoding-latin1.toml", "[materials.caf\u00e9]\ntype = \"lambert\"\n".encode("latin-1"), "error", "not UTF-8 text")
case("toml/encoding-utf16.toml", "[camera]\nposition = [0, 0, 5]\n".encode("utf-16"), "error", "not UTF-8 text")
case("toml/binary-garbage.toml", bytes(random.Random(7).randrange(256) for _ in range(300)), "error", "not UTF-8 text")
# Structure and types.
tm("unknown-top-level-key", "lights = 3\n" + LIT, "error", "line 1, column 1: unknown field `lights`, expected one of `camera`")
tm("unknown-camera-key", "[camera]\nposition = [0, 0, 5]\nfov = 40\n", "error", "unknown field `fov`, expected one of `position`, `look_at`, `forward`, `up`, `vfov`")
tm("camera-position-string", '[camera]\nposition = "here"\n', "error", "invalid type: string \"here\"")
tm("camera-position-two", "[camera]\nposition = [0, 5]\n", "error", "invalid length 2")
tm("camera-position-four", "[camera]\nposition = [0, 5, 1, 2]\n", "error", "line 2, column 12: invalid length 4, expected an array of 3 numbers")
tm("mesh-index-four", LIT + '[[mesh]]\npositions = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nindices = [[0, 1, 2, 0]]\nmaterial = "white"\n',
   "error", "invalid length 4, expected an array of 3 numbers")
tm("include-translate-four", LIT + '[[include]]\ngltf = "../aux/valid.gltf"\ntranslate = [1, 2, 3, 4]\n', "error", "invalid length 4")
tm("camera-missing-position", "[camera]\nvfov = 40\n", "error", "missing field `position`")
tm("camera-vfov-bool", "[camera]\nposition = [0, 0, 5]\nvfov = true\n", "error", "invalid type: boolean `true`")
tm("camera-vfov-date", "[camera]\nposition = [0, 0, 5]\nvfov = 1979-05-27\n", "error", "line 3")
tm("materials-not-a-table", "materials = 3\n", "error", "invalid type: integer `3`")
tm("sphere-not-an-array", '[sphere]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = "a"\n', "error", "line 1")
tm("sphere-missing-radius", LIT + '[[sphere]]\ncenter = [0, 0, 0]\nmaterial = "white"\n', "error", "missing field `radius`")
tm("sphere-radius-string", LIT + '[[sphere]]\ncenter = [0, 0, 0]\nradius = "big"\nmaterial = "white"\n', "error", "invalid type: string \"big\"")
tm("mesh-index-negative", LIT + '[[mesh]]\npositions = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nindices = [[0, -1, 2]]\nmaterial = "white"\n',
   "error", "invalid value: integer `-1`")
tm("mesh-index-pair", LIT + '[[mesh]]\npositions = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nindices = [[0, 1]]\nmaterial = "white"\n',
   "error", "invalid length 2")
tm("colour-two-numbers", LIT.replace("reflectance = 0.8", "reflectance = [0.5, 0.5]"), "error",
   "invalid length 2, expected a number or an array of 3 numbers")
tm("colour-four-numbers", LIT.replace("reflectance = 0.8", "reflectance = [0.5, 0.5, 0.5, 1]"), "error", "invalid length 4")
tm("colour-string", LIT.replace("reflectance = 0.8", 'reflectance = "red"'), "error", "invalid type: string \"red\"")
# Materials.
tm("material-unknown-type", LIT.replace('type = "lambert"', 'type = "glass"'), "error",
   "line 5: material 'white': unknown type \"glass\" (expected lambert, conductor, metallic-roughness, coated-diffuse, dielectric, diffuse-transmission or emitter)")
tm("material-key-not-for-type", LIT.replace("reflectance = 0.8", "reflectance = 0.8\nalpha = 0.1"), "error",
   "material 'white': type \"lambert\" does not take 'alpha'")
tm("material-conductor-no-alpha", LIT.replace('type = "lambert"', 'type = "conductor"'), "error", "type \"conductor\" needs 'alpha'")
tm("material-emitter-no-emission", LIT.replace("emission = 5", ""), "error", "type \"emitter\" needs 'emission'")
tm("material-alpha-above-one", LIT.replace('type = "lambert"\nreflectance = 0.8', 'type = "conductor"\nalpha = 1.5'), "error",
   "alpha must be in [0, 1] (got 1.5)")
tm("material-metallic-negative", LIT.replace('type = "lambert"\nreflectance = 0.8', 'type = "metallic-roughness"\nmetallic = -0.1'),
   "error", "metallic must be in [0, 1] (got -0.1)")
tm("material-roughness-nan", LIT.replace('type = "lambert"\nreflectance = 0.8', 'type = "metallic-roughness"\nroughness = nan'),
   "error", "roughness must be in [0, 1] (got NaN)")
tm("material-reflectance-negative", LIT.replace("reflectance = 0.8", "reflectance = [0.5, -0.1, 0.5]"), "error",
   "reflectance must be finite and non-negative")
tm("material-emission-inf", LIT.replace("emission = 5", "emission = inf"), "error", "emission must be finite and non-negative")
tm("material-unknown-reference", LIT.replace('material = "white"', 'material = "gold"'), "error",
   "line 13: [[sphere]] 1: unknown material 'gold' (defined: lamp, white)")
tm("material-none-defined", '[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = "white"\n', "error",
   "unknown material 'white' (none are defined)")
tm("material-reflectance-above-one", LIT.replace("reflectance = 0.8", "reflectance = 1.5"), "warning",
   "material 'white' reflects more than it receives")
# Shapes.
tm("sphere-radius-zero", LIT.replace("radius = 1", "radius = 0"), "error", "[[sphere]] 1: radius must be positive and finite (got 0)")
tm("sphere-radius-negative", LIT.replace("radius = 1", "radius = -1"), "error", "radius must be positive and finite (got -1)")
tm("sphere-radius-inf", LIT.replace("radius = 1", "radius = inf"), "error", "radius must be positive and finite (got inf)")
tm("sphere-center-nan", LIT.replace("center = [0, 0, 0]", "center = [0, nan, 0]"), "error", "[[sphere]] 1: center must be finite")
tm("quad-parallel-edges", LIT.replace("edge_v = [0, 0, 1]", "edge_v = [2, 0, 0]"), "error",
   "[[quad]] 1: edge_u and edge_v are parallel or zero, so the quad has no area")
tm("quad-zero-edge", LIT.replace("edge_u = [1, 0, 0]", "edge_u = [0, 0, 0]"), "error", "edge_u and edge_v are parallel or zero")
tm("quad-corner-inf", LIT.replace("corner = [-0.5, 3, -0.5]", "corner = [-inf, 3, -0.5]"), "error", "corner and edges must be finite")
RECT = '[[rectangle]]\ncenter = [0, -1, 0]\nnormal = [0, 1, 0]\nsize = 4\nmaterial = "white"\n'
tm("rectangle-normal-zero", LIT + RECT.replace("normal = [0, 1, 0]", "normal = [0, 0, 0]"), "error",
   "[[rectangle]] 1: normal must be a finite non-zero vector")
tm("rectangle-size-zero", LIT + RECT.replace("size = 4", "size = 0"), "error", "size must be positive and finite")
tm("rectangle-size-negative", LIT + RECT.replace("size = 4", "size = [4, -2]"), "error", "size must be positive and finite")
tm("rectangle-u-axis-parallel", LIT + RECT + "u_axis = [0, 2, 0]\n", "error", "u_axis is parallel to the normal")
tm("rectangle-u-axis-nan", LIT + RECT + "u_axis = [nan, 0, 0]\n", "error", "u_axis must be finite")
tm("rectangle-missing-size", LIT + RECT.replace("size = 4\n", ""), "error", "missing field `size`")
MESH = '[[mesh]]\npositions = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nindices = [[0, 1, 2]]\nmaterial = "white"\n'
tm("mesh-position-nan", LIT + MESH.replace("[1, 0, 0]", "[nan, 0, 0]"), "error", "[[mesh]] 1: positions must be finite")
tm("mesh-position-inf", LIT + MESH.replace("[0, 1, 0]]", "[0, -inf, 0]]"), "error", "positions must be finite")
tm("mesh-indices-empty", LIT + MESH.replace("[[0, 1, 2]]", "[]"), "error", "[[mesh]] 1: no triangles (indices is empty)")
tm("mesh-index-out-of-range", LIT + MESH.replace("[[0, 1, 2]]", "[[0, 1, 57]]"), "error", "index 57 is out of range (3 positions)")
tm("mesh-normals-count", LIT + MESH + "normals = [[0, 0, 1], [0, 0, 1]]\n", "error", "2 normals for 3 positions")
tm("mesh-normal-zero", LIT + MESH + "normals = [[0, 0, 1], [0, 0, 0], [0, 0, 1]]\n", "error", "normals must be finite and non-zero")
tm("mesh-unknown-key", LIT + MESH + "uvs = [[0, 0], [1, 0], [0, 1]]\n", "error", "unknown field `uvs`")
tm("mesh-missing-indices", LIT + MESH.replace("indices = [[0, 1, 2]]\n", ""), "error", "missing field `indices`")
# Camera.
CAM = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n"
tm("camera-look-at-position", LIT.replace(CAM, "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 1, 5]\n"), "error",
   "line 1: [camera]: the viewing direction is zero or not finite (look_at equals position?)")
tm("camera-look-at-and-forward", LIT.replace(CAM, CAM + "forward = [0, 0, -1]\n"), "error", "give either look_at or forward, not both")
tm("camera-up-parallel", LIT.replace(CAM, "[camera]\nposition = [0, 0, 5]\nforward = [0, 2, 0]\n"), "error",
   "up is parallel to the viewing direction")
tm("camera-up-zero", LIT.replace(CAM, CAM + "up = [0, 0, 0]\n"), "error", "up must be a finite non-zero vector")
tm("camera-vfov-zero", LIT.replace(CAM, CAM + "vfov = 0\n"), "error", "vfov must be between 0 and 180 degrees (got 0)")
tm("camera-vfov-180", LIT.replace(CAM, CAM + "vfov = 180\n"), "error", "vfov must be between 0 and 180 degrees (got 180)")
tm("camera-vfov-nan", LIT.replace(CAM, CAM + "vfov = nan\n"), "error", "vfov must be between 0 and 180 degrees (got NaN)")
tm("camera-position-inf", LIT.replace("position = [0, 1, 5]", "position = [0, inf, 5]"), "error", "[camera]: position must be finite")
# Lights.
tm("light-unknown-type", LIT + '[[light]]\ntype = "area"\n', "error", "[[light]] 1: unknown type \"area\" (expected point, spot or directional)")
tm("light-point-with-direction", LIT + '[[light]]\ntype = "point"\nposition = [0, 2, 0]\nintensity = 1\ndirection = [0, -1, 0]\n',
   "error", "[[light]] 1 (type \"point\"): does not take 'direction'")
tm("light-point-no-position", LIT + '[[light]]\ntype = "point"\nintensity = 1\n', "error", "needs a finite 'position'")
tm("light-point-no-intensity", LIT + '[[light]]\ntype = "point"\nposition = [0, 2, 0]\n', "error", "needs 'intensity'")
tm("light-intensity-negative", LIT + '[[light]]\ntype = "point"\nposition = [0, 2, 0]\nintensity = -3\n', "error",
   "intensity must be finite and non-negative")
tm("light-spot-cones-reversed", LIT + '[[light]]\ntype = "spot"\nposition = [0, 2, 0]\ndirection = [0, -1, 0]\nintensity = 1\ninner_cone = 30\nouter_cone = 20\n',
   "error", "need 0 ≤ inner_cone < outer_cone ≤ 90 degrees (got 30, 20)")
tm("light-spot-cone-wide", LIT + '[[light]]\ntype = "spot"\nposition = [0, 2, 0]\ndirection = [0, -1, 0]\nintensity = 1\nouter_cone = 120\n',
   "error", "(got 0, 120)")
tm("light-directional-zero", LIT + '[[light]]\ntype = "directional"\ndirection = [0, 0, 0]\nirradiance = 1\n', "error",
   "needs a finite non-zero 'direction'")
tm("light-directional-intensity", LIT + '[[light]]\ntype = "directional"\ndirection = [0, -1, 0]\nintensity = 1\n', "error",
   "does not take 'intensity'")
tm("light-missing-type", LIT + '[[light]]\nposition = [0, 2, 0]\n', "error", "missing field `type`")
# Environment.
tm("env-constant-and-map", LIT + '[environment]\nconstant = 1\nmap = "../aux/base.hdr"\n', "error",
   "[environment]: give either constant or map, not both")
tm("env-neither", LIT + "[environment]\nscale = 2\n", "error", "[environment]: needs constant = [r, g, b] or map = \"file.hdr\"")
tm("env-constant-negative", LIT + "[environment]\nconstant = [1, -1, 1]\n", "error", "constant must be finite and non-negative")
tm("env-constant-with-scale", LIT + "[environment]\nconstant = 1\nscale = 2\n", "error", "scale and rotation only apply to a map")
tm("env-map-missing", LIT + '[environment]\nmap = "../aux/nowhere.hdr"\n', "error", "nowhere.hdr: environment map not found")
tm("env-map-scale-negative", LIT + '[environment]\nmap = "../aux/base.hdr"\nscale = -1\n', "error",
   "scale must be finite and non-negative (got -1)")
tm("env-map-rotation-nan", LIT + '[environment]\nmap = "../aux/base.hdr"\nrotation = nan\n', "error", "rotation must be finite")
tm("env-map-png", LIT + '[environment]\nmap = "../aux/sky.png"\n', "error", "unknown environment map format '.png'")
tm("env-map-truncated", LIT + '[environment]\nmap = "../aux/truncated.hdr"\n', "error", "truncated")
tm("env-map-bad-exr", LIT + '[environment]\nmap = "../aux/bad-magic.exr"\n', "error", "file identifier missing")
tm("env-unknown-key", LIT + '[environment]\nmap = "../aux/base.hdr"\nexposure = 1\n', "error", "unknown field `exposure`")
# Includes.
INC = '[[include]]\ngltf = "../aux/valid.gltf"\n'
tm("include-valid", LIT + INC, "ok")
tm("include-missing", LIT + '[[include]]\ngltf = "../aux/missing.glb"\n', "error", "[[include]] 1 ('../aux/missing.glb'): glTF file")
tm("include-bad-index", LIT + '[[include]]\ngltf = "../aux/bad-index.gltf"\n', "error",
   "bad-index.gltf: accessor 1 (indices of mesh 'Tri' primitive 0): index 57 at position 2 is out of range")
tm("include-garbage", LIT + '[[include]]\ngltf = "../aux/garbage.gltf"\n', "error", "garbage.gltf: invalid glTF JSON")
tm("include-a-toml", LIT + '[[include]]\ngltf = "../aux/scene.toml"\n', "error", "scene.toml: invalid glTF JSON")
tm("include-scale-zero", LIT + INC + "scale = [1, 0, 1]\n", "error", "scale must be finite and non-zero")
tm("include-rotate-both", LIT + INC + "rotate = { axis = [0, 1, 0], angle = 30, euler = [0, 30, 0] }\n", "error",
   "rotate needs either { axis = [x, y, z], angle = degrees } or { euler = [x, y, z] }")
tm("include-rotate-axis-zero", LIT + INC + "rotate = { axis = [0, 0, 0], angle = 30 }\n", "error",
   "rotate.axis must be a finite non-zero vector")
tm("include-rotate-angle-nan", LIT + INC + "rotate = { axis = [0, 1, 0], angle = nan }\n", "error", "rotate.angle must be finite")
tm("include-translate-inf", LIT + INC + "translate = [0, inf, 0]\n", "error", "translate must be finite")
tm("include-scene-missing", LIT + INC + "scene = 5\n", "error", "scene 5 was requested, but the file has 1 scene(s)")
tm("include-unknown-key", LIT + '[[include]]\nfile = "../aux/valid.gltf"\n', "error", "unknown field `file`")
# Valid but dark.
tm("empty", "", "error", "the scene is empty: no geometry, no lights and no environment")
tm("no-lights", LIT.replace("[materials.lamp]\ntype = \"emitter\"\nemission = 5\n", "").replace(
    '[[quad]]\ncorner = [-0.5, 3, -0.5]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]\nmaterial = "lamp"\n', ""),
   "warning", "the scene has no lights and no environment: the image will be black")

# =========================================================================================================
# 4. Environment maps, used as `mislab render furnace --env FILE`

case("env/valid.hdr", HDR_FLAT, "ok")
case("env/valid-rle.hdr", HDR_RLE, "ok")
case("env/valid.exr", EXR_BASE, "ok")
H = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"
case("env/empty.hdr", b"", "error", "empty file")
case("env/signature-rgbe.hdr", hdr(header="#?RGBE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8 +X 16\n"), "error", "signature not found")
case("env/signature-missing.hdr", hdr(header="FORMAT=32-bit_rle_rgbe\n\n-Y 8 +X 16\n"), "error", "signature not found")
case("env/format-xyze.hdr", hdr(header="#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 8 +X 16\n"), "error",
     "unsupported Radiance .hdr variant")
case("env/orientation-flipped.hdr", hdr(header=H + "+Y 8 +X 16\n"), "error", "Orientation +Y +X")
case("env/height-zero.hdr", hdr(header=H + "-Y 0 +X 16\n"), "error", "empty image (16×0)")
case("env/width-zero.hdr", hdr(header=H + "-Y 8 +X 0\n"), "error", "empty image (0×8)")
case("env/height-text.hdr", hdr(header=H + "-Y eight +X 16\n"), "error", "height")
case("env/width-overflow.hdr", hdr(header=H + "-Y 8 +X 99999999999\n"), "error", "width")
case("env/height-negative.hdr", hdr(header=H + "-Y -8 +X 16\n"), "error", "height")
case("env/dimensions-short.hdr", hdr(header=H + "-Y 8 +X\n"), "error", "Dimensions line too short")
case("env/dimensions-long.hdr", hdr(header=H + "-Y 8 +X 16 +Z 4\n"), "error", "Dimensions line too long")
case("env/too-wide.hdr", hdr(header=H + "-Y 1 +X 16385\n"), "error", "16384")
case("env/too-tall.hdr", hdr(header=H + "-Y 16385 +X 2\n"), "error", "16384")
case("env/huge-claimed.hdr", hdr(header=H + "-Y 4096 +X 8192\n"), "error", "truncated")
case("env/no-header-end.hdr", hdr(header="#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n-Y 8 +X 16\n"), "error", "truncated")
case("env/header-only.hdr", H + "-Y 8 +X 16\n", "error", "truncated")
case("env/pixels-short.hdr", HDR_FLAT[:-4], "error", "truncated")
rle_row_overrun = bytearray(HDR_RLE)
rle_row_overrun[HDR_RLE.index(bytes([2, 2, 0, 16])) + 4] = 100  # first literal run claims 100 of 16 values
case("env/rle-run-too-long.hdr", bytes(rle_row_overrun), "error", "Wrong length of decoded scanline")
rle_repeat_overrun = bytearray(HDR_RLE)
rle_repeat_overrun[HDR_RLE.index(bytes([2, 2, 0, 16])) + 4: HDR_RLE.index(bytes([2, 2, 0, 16])) + 6] = bytes([128 + 40, 7])
case("env/rle-repeat-too-long.hdr", bytes(rle_repeat_overrun), "error", "Wrong length of decoded scanline")
first_marker = hdr_pixels(16, 8)
first_marker[0][0] = (1, 1, 1, 4)
case("env/old-rle-first-marker.hdr", hdr(pixels=first_marker), "error", "run length marker")
marker_overrun = hdr_pixels(16, 8)
marker_overrun[2][5] = (1, 1, 1, 200)
case("env/old-rle-marker-overrun.hdr", hdr(pixels=marker_overrun), "error", "Wrong length of decoded scanline")
huge_exponent = hdr_pixels(16, 8)
huge_exponent[3][3] = (200, 200, 200, 255)
case("env/exponent-255.hdr", hdr(pixels=huge_exponent), "warning", "above 1e30")
case("env/is-an-exr.hdr", EXR_BASE, "error", "signature not found")
case("env/is-a-png.hdr", png(16, 8), "error", "signature not found")
case("env/is-an-hdr.exr", HDR_FLAT, "error", "file identifier missing")
case("env/empty.exr", b"", "error", "empty file")
case("env/magic-wrong.exr", b"\x76\x2f\x31\x02" + EXR_BASE[4:], "error", "file identifier missing")
case("env/version-3.exr", exr(version=3), "error", "file versions other than 2.0 are not supported")
case("env/flags-unknown.exr", exr(version=2 | 0x10000000), "error", "too new file feature flags")
case("env/compression-unknown.exr", exr(compression=42), "error", "compression")
case("env/channels-none.exr", exr(channels=""), "error", "channels")
case("env/channels-luminance-only.exr", exr(channels="Y"), "error", "no R, G, B channels found")
case("env/channels-unsorted.exr", exr(channels="RGB"), "error", "channel names are not sorted alphabetically")
case("env/pixel-type-unknown.exr", exr(pixel_type=7), "error", "pixel type attribute value")
case("env/window-y-inverted.exr", exr(window=(0, 7, 15, 0)), "error", "a chunk lies outside the image's data window")
case("env/window-huge.exr", exr(window=(0, 0, 2000000000, 7)), "error", "window")
case("env/window-too-wide.exr", exr(window=(0, 0, 16384, 0), h=1), "error", "16384")
case("env/line-order-unknown.exr", exr(line_order=9), "error", "line order attribute value")
case("env/offset-past-end.exr", exr(offsets=lambda t: t[:3] + [999999] + t[4:]), "error", "truncated or corrupt")
case("env/offset-negative.exr", exr(offsets=lambda t: t[:3] + [2 ** 63 + 5] + t[4:]), "error", "corrupt")
case("env/offsets-swapped.exr", exr(offsets=lambda t: [t[1], t[0]] + t[2:]), "ok")
case("env/offsets-zero.exr", exr(offsets=lambda t: [0] * len(t)), "error", "a chunk lies outside the image's data window")
case("env/attribute-size-huge.exr",
     EXR_BASE.replace(b"compression\0compression\0\x01\0\0\0", b"compression\0compression\0\xff\xff\xff\x7f"), "error",
     "truncated or corrupt")
case("env/header-unterminated.exr", EXR_BASE[:200], "error", "truncated or corrupt")
case("env/half-nan-inf.exr", exr(pixel_type=1, values=lambda x, y, c: float("nan") if (x, y) == (3, 2) else
                                 (float("inf") if (x, y) == (4, 2) else 0.5)), "warning", "3 NaN; 3 infinite")
case("env/negative-values.exr", exr(values=lambda x, y, c: -2.0 if (x, y, c) == (1, 1, 0) else 0.5), "warning", "1 negative")
case("env/not-2-to-1.exr", exr(w=8, h=8), "warning", "8×8 is not 2:1")
case("env/map.png", png(16, 8), "error", "unknown environment map format '.png'", mode="env")
case("env/map.toml", VALID_TOML, "error", "unknown environment map format '.toml'", mode="env")

# =========================================================================================================
# 5. Systematic bulk: truncations, garbling at seeded positions, wrong magic

rng = random.Random(20251122)

# 5a. Truncations of the valid cube .glb at every header offset and at seeded offsets through both chunks.
offsets = sorted(set(range(0, 13)) | {20, 21, BIN_HEADER_AT - 1, BIN_HEADER_AT, BIN_HEADER_AT + 4, BIN_HEADER_AT + 8,
                                        len(CUBE_GLB) - 1} | set(rng.sample(range(13, len(CUBE_GLB)), 16)))
for k in offsets:
    cut = CUBE_GLB[:k]
    outcome = glb_container(cut)
    assert outcome[0] == "error", (k, outcome)
    case(f"gen-glb-trunc/cube-{k:04d}.glb", cut, "error", outcome[1])

# 5b. Truncations of the valid triangle .gltf (embedded buffer): every cut that leaves invalid JSON.
TRI_TEXT = to_json(tri()).encode()
for k in sorted(set(rng.sample(range(0, len(TRI_TEXT)), 28)) | {0, 1, len(TRI_TEXT) - 1}):
    cut = TRI_TEXT[:k]
    if json_fails(cut):
        case(f"gen-gltf-trunc/tri-{k:04d}.gltf", cut, "error", "invalid glTF JSON")

# 5c. External buffers cut short: the .gltf is the case, its .bin (in aux/) is truncated.
for k in (0, 1, 12, 35, 36, 42, 43, 79):
    aux(f"tri-{k:02d}.bin", TRI_BIN[:k])
    doc = tri()
    doc["buffers"][0]["uri"] = f"../aux/tri-{k:02d}.bin"
    case(f"gen-bin-trunc/tri-bin-{k:02d}.gltf", to_json(doc), "error",
         f"buffer 0: byteLength is 80 but only {k} bytes of data are present")

# 5d. Truncated PNG textures.
RAMP = png(8, 8)
IDAT_END = len(RAMP) - 12 - 4  # the IEND chunk and IDAT's CRC follow the compressed data
for k in sorted({1, 8, 16, 29, 33, 40, (41 + IDAT_END) // 2, IDAT_END - 1}):
    aux(f"ramp-{k:03d}.png", RAMP[:k])
    case(f"gen-png-trunc/ramp-{k:03d}.gltf", to_json(textured(f"../aux/ramp-{k:03d}.png")), "error",
         f"image 0 (../aux/ramp-{k:03d}.png): cannot decode the image")

# 5e. Truncations of the .hdr bases (flat and run-length encoded) and of the .exr base.
for name, base in (("flat", HDR_FLAT), ("rle", HDR_RLE)):
    for k in sorted(set(rng.sample(range(1, len(base)), 12)) | {1, 10, 40, len(base) - 1}):
        case(f"gen-hdr-trunc/{name}-{k:04d}.hdr", base[:k], "error", "truncated")
for k in sorted(set(rng.sample(range(1, len(EXR_BASE)), 20)) | {1, 4, 8, 100, len(EXR_BASE) - 1}):
    case(f"gen-exr-trunc/base-{k:04d}.exr", EXR_BASE[:k], "error", "truncated or corrupt")

# 5f. GLB garbling at seeded positions, kept where the outcome is certain:
#   header and chunk-header bytes (simulated container rules), JSON bytes that break the JSON syntax,
#   and index bytes (the exact out-of-range index and its position are known).
header_positions = list(range(4, 20)) + list(range(BIN_HEADER_AT, BIN_HEADER_AT + 8))
for at in header_positions:
    for value in [rng.choice([0x00, 0xFF, CUBE_GLB[at] ^ 0x5A])]:
        if value == CUBE_GLB[at]:
            continue
        data = patch(CUBE_GLB, at, bytes([value]))
        outcome = glb_container(data)
        if outcome[0] == "error":
            expect = outcome[1]
        else:
            _, jchunk, bchunk = outcome
            if json_fails(jchunk):
                expect = "invalid glTF JSON"
            elif bchunk is None:
                expect = "no BIN chunk"
            elif len(bchunk) < 648:
                expect = f"byteLength is 648 but only {len(bchunk)} bytes"
            else:
                continue  # still loads (e.g. a longer total length with trailing bytes)
        case(f"gen-glb-garble/header-{at:04d}-{value:02x}.glb", data, "error", expect)
json_start, json_end = 20, 20 + JSON_LEN
structural = [i for i in range(json_start, json_end) if CUBE_GLB[i:i + 1] in b'{}[]:,"']
for at in sorted(rng.sample(structural, 16)):
    value = rng.choice(b"x#\x00\xff;")
    data = patch(CUBE_GLB, at, bytes([value]))
    if json_fails(data[json_start:json_end]):
        case(f"gen-glb-garble/json-{at:04d}-{value:02x}.glb", data, "error", "invalid glTF JSON")
bin_start = BIN_HEADER_AT + 8
for i in sorted(rng.sample(range(36), 16)):
    high = rng.randrange(1, 256)
    at = bin_start + CUBE_INDEX_AT + 2 * i + 1
    data = patch(CUBE_GLB, at, bytes([high]))
    index = struct.unpack_from("<H", data, at - 1)[0]
    case(f"gen-glb-garble/index-{i:02d}-{high:02x}.glb", data, "error",
         f"index {index} at position {i} is out of range (the primitive has 24 vertices)")

# 5g. glTF JSON garbling at seeded positions: a structural character replaced so that the JSON breaks.
structural = [i for i in range(len(TRI_TEXT)) if TRI_TEXT[i:i + 1] in b'{}[]:,"']
for at in sorted(rng.sample(structural, 30)):
    value = rng.choice(b"x#\x00\xff;'")
    data = patch(TRI_TEXT, at, bytes([value]))
    if json_fails(data):
        case(f"gen-gltf-garble/tri-{at:04d}-{value:02x}.gltf", data, "error", "invalid glTF JSON")

# 5h. .hdr header garbling: the signature, the FORMAT value, the orientation tags and the dimensions.
HEAD = HDR_FLAT[:HDR_FLAT.index(b"\n\n") + 2]
DIMS_AT = len(HEAD)
FORMAT_AT = HDR_FLAT.index(b"32-bit")
for at in sorted(rng.sample(range(0, 10), 6)):
    case(f"gen-hdr-garble/signature-{at:02d}.hdr", patch(HDR_FLAT, at, b"%"), "error", "signature not found")
for at in sorted(rng.sample(range(FORMAT_AT, FORMAT_AT + 14), 6)):
    case(f"gen-hdr-garble/format-{at:02d}.hdr", patch(HDR_FLAT, at, b"#"), "error", "unsupported Radiance .hdr variant")
for at, value, expect in ((DIMS_AT, b"+", "Orientation +Y +X"), (DIMS_AT + 1, b"X", "Orientation -X +X"),
                          (DIMS_AT + 3, b"z", "height"), (DIMS_AT + 6, b"Y", "Orientation -Y +Y"),
                          (DIMS_AT + 8, b"q", "width"), (DIMS_AT + 9, b"-", "width")):
    case(f"gen-hdr-garble/dimensions-{at:02d}.hdr", patch(HDR_FLAT, at, value), "error", expect)

# 5i. .exr garbling of the magic number and of offset-table entries (pointing past the end of the file).
for at in range(4):
    case(f"gen-exr-garble/magic-{at}.exr", patch(EXR_BASE, at, bytes([EXR_BASE[at] ^ 0x20])), "error", "file identifier missing")
TABLE_AT = len(EXR_BASE) - 8 * 8 - 8 * (8 + 16 * 3 * 4)
for i in sorted(rng.sample(range(8), 6)):
    at = TABLE_AT + 8 * i + 2  # third byte: the offset grows by a multiple of 64 KiB, past the end
    case(f"gen-exr-garble/offset-{i}.exr", patch(EXR_BASE, at, bytes([EXR_BASE[at] + 7])), "error", "truncated or corrupt")

# 5j. Wrong magic variants in .glb files.
for i, magic in enumerate([b"gltf", b"GLTF", b"glTf", b"glTF"[::-1], b"\0\0\0\0", b"\xff\xff\xff\xff", b"gl\0F", b"KTX ",
                           b"\x89PNG", b"PK\x03\x04", b"%PDF", b"\xef\xbb\xbfg", b" glT", b"\nglT"]):
    data = magic + CUBE_GLB[4:]
    outcome = glb_container(data)
    assert outcome[0] == "error", magic
    case(f"gen-magic/magic-{i:02d}.glb", data, "error", outcome[1])
for i, magic in enumerate([b"{lTF", b" {lT"]):
    data = magic + CUBE_GLB[4:]
    case(f"gen-magic/json-like-{i:02d}.glb", data, "error", "invalid glTF JSON")
case("gen-magic/glb-bytes-in-gltf.gltf", patch(CUBE_GLB, 0, b"glTf"), "error", "invalid glTF JSON")

# =========================================================================================================
# 6. Hostile inputs (issue 17): indices of 2^32 and more (which gltf-json wraps), URIs that leave the asset's
# directory, declared sizes far beyond any limit, and echoed input that must be cut. Special files (FIFOs,
# /dev/zero, symlink loops) cannot live in git: tests/bad_input.rs makes them at run time.

def h(name, edit, expect, substring="", args="", base=None):
    doc = edited(base() if base else tri(), edit)
    case(f"hostile/{name}.gltf", to_json(doc), expect, substring, args=args)


W = 2 ** 32
h("index-wrap-mesh", set_(["nodes", 0, "mesh"], W), "error", "nodes[0].mesh: index 4294967296 does not exist")
h("index-wrap-mesh-plus-5", set_(["nodes", 0, "mesh"], W + 5), "error", "nodes[0].mesh: index 4294967301 does not exist")
h("index-wrap-child", set_(["nodes", 0, "children"], [W + 1]), "error", "nodes[0].children[0]: index 4294967297 does not exist")
h("index-wrap-position", set_(ATTR + ["POSITION"], W), "error", "attributes.POSITION: index 4294967296 does not exist")
h("index-wrap-normal", set_(ATTR + ["NORMAL"], W + 2), "error", "attributes.NORMAL: index 4294967298 does not exist")
h("index-wrap-indices", set_(PRIM + ["indices"], W + 1), "error", "primitives[0].indices: index 4294967297 does not exist")
h("index-wrap-material", set_(PRIM + ["material"], W), "error", "primitives[0].material: index 4294967296 does not exist")
h("index-wrap-default-scene", set_(["scene"], W), "error", "scene: index 4294967296 does not exist")
h("index-wrap-scene-node", set_(["scenes", 0, "nodes"], [W]), "error", "scenes[0].nodes[0]: index 4294967296 does not exist")
h("index-wrap-bufferview", set_(["accessors", 0, "bufferView"], W), "error", "accessors[0].bufferView: index 4294967296")
h("index-wrap-buffer", set_(["bufferViews", 0, "buffer"], W), "error", "bufferViews[0].buffer: index 4294967296")
h("index-wrap-2-pow-53", set_(["nodes", 0, "mesh"], 2 ** 53), "error", "index 9007199254740992 does not exist")
h("index-wrap-u64-max", set_(["nodes", 0, "mesh"], 2 ** 64 - 1), "error", "index 18446744073709551615 does not exist")
h("index-wrap-texture", lambda d: d.update(edited(textured(b64uri(png(8, 8))), set_(["materials", 0, "pbrMetallicRoughness",
  "baseColorTexture", "index"], W))), "error", "baseColorTexture.index: index 4294967296 does not exist")
h("index-wrap-image-source", lambda d: d.update(edited(textured(b64uri(png(8, 8))), set_(["textures", 0, "source"], W))),
  "error", "textures[0].source: index 4294967296 does not exist")
h("index-in-extras-is-data", set_(["nodes", 0, "extras"], {"mesh": W}), "ok")
# Declared sizes: refused before anything is read or allocated.
h("buffer-bytelength-2-pow-53", set_(["buffers", 0, "byteLength"], 2 ** 53), "error",
  "buffer 0: byteLength 9007199254740992 exceeds the limit")
h("buffer-bytelength-2-pow-53-external", lambda d: d["buffers"][0].update(uri="tri.bin", byteLength=2 ** 53), "error",
  "buffer 0: byteLength 9007199254740992 exceeds the limit")
# URIs: absolute, climbing with ../ or %2e%2e, refused (resolved against the glTF file's directory).
h("uri-absolute", set_(["buffers", 0, "uri"], "/etc/passwd"), "error", "buffer 0: URI '/etc/passwd' is an absolute path")
h("uri-absolute-missing", set_(["buffers", 0, "uri"], "/nonexistent/mislab.bin"), "error", "is an absolute path")
h("uri-parent", set_(["buffers", 0, "uri"], "../../../../../../../../etc/passwd"), "error",
  "leads outside the glTF file's directory")
h("uri-parent-percent", set_(["buffers", 0, "uri"], "%2e%2e/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd"), "error",
  "leads outside the glTF file's directory")
h("uri-parent-after-descent", set_(["buffers", 0, "uri"], "a/../../aux/tri.bin"), "error", "leads outside the glTF file's directory")
h("uri-parent-allowed", lambda d: d["buffers"][0].update(uri="../aux/tri.bin", byteLength=80), "ok", args="--allow-outside-paths")
h("uri-image-absolute", lambda d: d.update(textured("/etc/passwd")), "error", "image 0 (/etc/passwd): URI '/etc/passwd' is an absolute path")
h("uri-image-parent", lambda d: d.update(textured("../../../../../../etc/passwd")), "error", "leads outside the glTF file's directory")
h("uri-image-percent", lambda d: d.update(textured("%2E%2E/%2E%2E/%2E%2E/%2E%2E/etc/passwd")), "error", "leads outside")
# Echoed input is cut: a URI of 100 000 characters is quoted as its first 80 and its length.
h("uri-long", set_(["buffers", 0, "uri"], "x" * 100000 + ".bin"), "error", "characters)': cannot be read")
h("uri-long-scheme", set_(["buffers", 0, "uri"], "http://" + "y" * 100000), "error", "… (100007 characters)")
case("hostile/no-extension", to_json(tri()), "error", "has no file extension")
case("hostile/extension-long." + "z" * 200, to_json(tri()), "error", "unknown scene format")
case("hostile/unknown-key-long.toml", "k" * 100000 + " = 1\n" + VALID_TOML, "error", "characters)")

# =========================================================================================================
# The manifest

with open(os.path.join(HERE, "MANIFEST.tsv"), "w", encoding="utf-8") as f:
    f.write("# Written by generate.py: do not edit by hand (edit and re-run the generator).\n")
    f.write("# file\tmode\texpect\tsubstring\targs\n")
    for row in MANIFEST:
        f.write("\t".join(row) + "\n")
counts = {}
for rel, _, expect, _, _ in MANIFEST:
    key = (rel.split("/")[0], expect)
    counts[key] = counts.get(key, 0) + 1
for (category, expect), count in sorted(counts.items()):
    print(f"{category:18} {expect:8} {count}")
print(f"{len(MANIFEST)} cases")
