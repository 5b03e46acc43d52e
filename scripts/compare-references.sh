#!/usr/bin/env bash
# Reproduces the tables of docs/references.md: mislab against the published Tungsten reference images of the
# Bitterli scenes, mislab's pbrt-v4 against its Mitsuba 3 XML renders of the same scenes, and (with MITSUBA_PY)
# mislab against Mitsuba 3 itself. Re-run it after materials change; it prints Markdown table rows.
#
#   scripts/compare-references.sh [OUT_DIR]        (default /tmp/mislab-references)
# Environment:
#   MISLAB       the binary (default target/release/mislab; build it first)
#   DIV          render at 1/DIV of the reference size per axis (DIV must divide both, and 16); blocks shrink to
#                16/DIV px (default 4)
#   TIME         seconds of rendering per Tungsten comparison (default 150; this 2-core machine, lavapipe)
#   ONLY         a regular expression: only the scenes whose name matches
#   MITSUBA_PY   a python with mitsuba 3.9.1 (scratch venv, never a dependency); unset = skip that table
#   PNG_DIR      where the side-by-side PNGs go (default docs/references)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-/tmp/mislab-references}
mislab=${MISLAB:-$root/target/release/mislab}
div=${DIV:-4}
time=${TIME:-150}
only=${ONLY:-.}
png_dir=${PNG_DIR:-$root/docs/references}
scenes=$root/../shared/testdata/scenes/bitterli
mkdir -p "$out" "$png_dir"
[ -x "$mislab" ] || { echo "no mislab binary at $mislab (cargo build --release, or set MISLAB)" >&2; exit 2; }

# One JSON comparison as table cells: mean ratio (R, G, B) | block relMSE (all) | per channel.
cells() {
  python3 -c 'import json, sys
c = json.load(sys.stdin)
r = " / ".join(f"{v:.3f}" for v in c["mean_ratio"])
a = c["block_relmse_all"]
print(f"{r} | {a:.2e} | " + " / ".join(f"{v:.2e}" for v in c["block_relmse"]))'
}

# The pbrt file's maxdepth (pbrt counts path vertices after the camera like Mitsuba's max_depth − 1 = mislab's
# --max-depth); capped at 32 to bound the render time (deeper paths carry little energy here).
depth_of() {
  local d
  d=$(grep -o '"integer maxdepth" \[ *[0-9]*' "$1" | grep -o '[0-9]*$' || true)
  d=${d:-8}
  [ "$d" -gt 32 ] && d=32
  echo "$d"
}

echo "## mislab vs Tungsten (TungstenRender.exr), ${div}x smaller, blocks $((16 / div)) px = 16 px of the reference"
echo
echo "| scene | size | spp | NaN/Inf | mean ratio R / G / B | 16x16-block relMSE | per channel |"
echo "|---|---|---|---|---|---|---|"
for ref in "$scenes"/*/pbrt-v4/TungstenRender.exr; do
  dir=$(dirname "$ref")
  name=$(basename "$(dirname "$dir")")
  [[ $name =~ $only ]] || continue
  # The reference's own size, from compare's JSON.
  read -r w h < <("$mislab" compare "$ref" "$ref" --json | python3 -c 'import json, sys; print(*json.load(sys.stdin)["sizes"][1])')
  w=$((w / div)) h=$((h / div))
  depth=$(depth_of "$dir/scene-v4.pbrt")
  log=$out/$name.log
  "$mislab" reference "$dir/scene-v4.pbrt" --width $w --height $h --mode path --max-depth "$depth" \
    --time "$time" -o "$out/$name.exr" --force 2>"$log" || { echo "| $name | render failed: $(tail -1 "$log") |"; continue; }
  spp=$(grep -o '^[0-9]* spp' "$log" | tail -1 | grep -o '[0-9]*')
  nan=$(grep -o '[0-9]* NaN/Inf' "$log" | tail -1 | grep -o '^[0-9]*')
  c=$("$mislab" compare "$out/$name.exr" "$ref" --block 16 --json --side-by-side "$png_dir/$name.png" 2>/dev/null | cells)
  echo "| $name | ${w}x$h | $spp | $nan | $c |"
done

# The same scene in both formats, rendered by mislab with the same settings: 8x8-block relMSE between them.
echo
echo "## mislab: pbrt-v4 vs Mitsuba 3 XML of the same scene (8x8 blocks; the XML render is the reference)"
echo
echo "| scene | size | spp | mean ratio R / G / B | 8x8-block relMSE | per channel |"
echo "|---|---|---|---|---|---|"
both() { # name xml-file w h spp mode depth
  local name=$1 xml=$2 w=$3 h=$4 spp=$5 depth=$6
  [[ $name =~ $only ]] || return 0
  for f in pbrt xml; do
    local src=$scenes/$name/pbrt-v4/scene-v4.pbrt
    [ $f = xml ] && src=$scenes/$name/mitsuba3/$xml
    "$mislab" reference "$src" --width "$w" --height "$h" --mode path --max-depth "$depth" --spp "$spp" \
      -o "$out/$name-$f.exr" --force 2>"$out/$name-$f.log"
  done
  c=$("$mislab" compare "$out/$name-pbrt.exr" "$out/$name-xml.exr" --block 8 --json \
    --side-by-side "$png_dir/$name-pbrt-vs-xml.png" 2>/dev/null | cells)
  echo "| $name | ${w}x$h | $spp | $c |"
}
both cornell-box scene_v3.xml 256 256 128 64
both veach-mis scene.xml 320 180 64 2

[ -n "${MITSUBA_PY:-}" ] || { echo; echo "(MITSUBA_PY unset: no Mitsuba 3 table)"; exit 0; }
echo
echo "## mislab vs Mitsuba 3.9.1 (llvm_ad_rgb) on the XML scenes (16x16 blocks; Mitsuba's render is the reference)"
echo
echo "| scene | size | mislab spp | Mitsuba spp | mean ratio R / G / B | 16x16-block relMSE | per channel |"
echo "|---|---|---|---|---|---|---|"
mitsuba() { # name src-xml w h mislab-spp mitsuba-spp mislab-depth
  local name=$1 src=$2 w=$3 h=$4 spp=$5 mspp=$6 depth=$7
  [[ $name =~ $only ]] || return 0
  local tag
  tag=$(basename "$src" .xml)
  # Mitsuba's max_depth counts the camera ray: mislab's --max-depth D is Mitsuba's D + 1.
  "$MITSUBA_PY" "$root/scripts/mitsuba-render.py" "$src" "$out/$tag-mitsuba.exr" --width "$w" --height "$h" \
    --spp "$mspp" --chunk 128 --max-depth $((depth + 1)) 2>"$out/$tag-mitsuba.log"
  "$mislab" reference "$src" --width "$w" --height "$h" --mode path --max-depth "$depth" --spp "$spp" \
    -o "$out/$tag-mislab.exr" --force 2>"$out/$tag-mislab.log"
  c=$("$mislab" compare "$out/$tag-mislab.exr" "$out/$tag-mitsuba.exr" --block 16 --json \
    --side-by-side "$png_dir/$tag-vs-mitsuba.png" 2>/dev/null | cells)
  echo "| $name ($tag) | ${w}x$h | $spp | $mspp | $c |"
}
# Copies named for their scene (the XML files reference no other files, so they may live in $out).
cp "$scenes/cornell-box/mitsuba3/scene_v3.xml" "$out/cornell-box.xml"
cp "$scenes/veach-mis/mitsuba3/scene.xml" "$out/veach-mis.xml"
mitsuba cornell-box "$out/cornell-box.xml" 256 256 256 1024 64
mitsuba veach-mis "$out/veach-mis.xml" 320 180 128 1024 2
# veach-mis with the conductors' specular_reflectance 0.3 and Beckmann distribution changed to what mislab
# renders (1, GGX): separates the importer and camera (which should agree) from those two material differences.
sed -e 's/name="specular_reflectance" value="0.3, 0.3, 0.3"/name="specular_reflectance" value="1, 1, 1"/' \
    -e 's/value="beckmann"/value="ggx"/' "$scenes/veach-mis/mitsuba3/scene.xml" >"$out/veach-mis-ggx-tint1.xml"
mitsuba veach-mis "$out/veach-mis-ggx-tint1.xml" 320 180 128 1024 2
