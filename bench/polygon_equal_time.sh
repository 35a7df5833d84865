#!/usr/bin/env bash
# Equal-time MRSE of the polygon methods on polygon-cornell and occluded-planes:
# sa, psa, bsdf+sa, psa+ltc/weighted and psa+ltc/clamped-optimal, each rendered by
# `penumbra render --seconds` for the same compute (CPU) time, against a long bsdf+sa reference.
# Prints a markdown table (MRSE of the whole image and of each region; lower is better).
#
#   bench/polygon_equal_time.sh [build-dir] [seconds per method] [reference seconds] [out-dir]
#
# Defaults: build-polygon2, 6 s per method, 120 s reference, /tmp/polygon_equal_time. The
# budget is compute time summed over threads (one thread here, so runs do not fight over cores);
# a render stops at the first pass boundary past the budget, so every pixel has the same spp.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build-polygon2}"
seconds="${2:-6}"
reference_seconds="${3:-120}"
out="${4:-/tmp/polygon_equal_time}"
penumbra="$build/client/penumbra"
[[ -x "$penumbra" ]] || { echo "no $penumbra: build the target penumbra first" >&2; exit 1; }
mkdir -p "$out"
methods=(sa psa bsdf+sa psa+ltc/weighted psa+ltc/clamped-optimal)

for scene in polygon-cornell occluded-planes; do
  reference="$out/$scene-reference.exr"
  if [[ ! -f "$reference" ]]; then
    "$penumbra" render "$root/scenes/$scene.json" -m bsdf+sa --seconds "$reference_seconds" \
      --threads 1 --seed 99 -o "$reference" > "$out/$scene-reference.log"
  fi
  echo
  echo "### $scene ($seconds s per method, reference: bsdf+sa, $(grep -o '[0-9]* spp' "$out/$scene-reference.log"))"
  echo
  header="| method | spp | MRSE image"
  rule="|---|---|---"
  regions=$("$penumbra" render "$root/scenes/$scene.json" -m sa --spp 1 --threads 1 \
    --reference "$reference" -o "$out/probe.exr" | awk '/MRSE/ {print $1}' | grep -v '^image$' || true)
  for r in $regions; do header="$header | MRSE $r"; rule="$rule|---"; done
  echo "$header |"
  echo "$rule|"
  for method in "${methods[@]}"; do
    name="${method//\//_}"
    log="$out/$scene-$name.log"
    "$penumbra" render "$root/scenes/$scene.json" -m "$method" --seconds "$seconds" --threads 1 \
      --seed 1 --reference "$reference" -o "$out/$scene-$name.exr" > "$log"
    spp=$(grep -o '[0-9]* spp' "$log" | head -1 | cut -d' ' -f1)
    row="| \`$method\` | $spp | $(awk '$1 == "image" && /MRSE/ {print $3}' "$log")"
    for r in $regions; do row="$row | $(awk -v r="$r" '$1 == r && /MRSE/ {print $3}' "$log")"; done
    echo "$row |"
  done
done
