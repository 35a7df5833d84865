#!/usr/bin/env bash
# Equal-time MRSE of the line methods on cornell-occluders and monoliths: sa, bsdf+sa,
# line-sa:v, line-bd16:rand, bsdf+line-sa:v/balance and bsdf+line-sa:v/smooth, each rendered by
# `penumbra render --seconds` for the same compute (CPU) time, against a long bsdf+sa reference.
# Prints one markdown table per scene: method, spp reached, compute seconds, MRSE of the whole
# image and of each region of the scene (lower is better), and MRSE x seconds relative to sa
# (the equal-time efficiency; below 1 beats sa). A method the scene refuses (line-bd16 on GGX
# materials) gets a row with the refusal message.
#
#   bench/line_equal_time.sh [--build DIR] [--seconds S] [--reference-seconds R]
#                            [--threads N] [--scenes "a b"] [--out DIR]
#
# Defaults: build/release, 5 s per method, 120 s reference, 1 thread, both scenes, output in
# DIR/line_equal_time. Use --seconds 1 for a quick run. The reference (bsdf+sa, seed 99) is
# cached in the output folder under a name holding the scene file's hash and its budget, so it
# is rendered once per scene version. The budget is CPU time summed over threads (one thread by
# default, so runs do not fight over the shared cores); a render stops at a pass boundary, so
# every pixel has the same spp. The reference's own noise adds about MRSE(bsdf+sa) x
# (spp of bsdf+sa / spp of the reference) to every figure.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build/release"
seconds=5
reference_seconds=120
threads=1
scenes="cornell-occluders monoliths"
out=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --seconds) seconds="$2"; shift 2 ;;
    --reference-seconds) reference_seconds="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --scenes) scenes="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) echo "line_equal_time.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
out="${out:-$build/line_equal_time}"
penumbra="$build/client/penumbra"
[[ -x "$penumbra" ]] || { echo "line_equal_time.sh: no $penumbra: build the target penumbra" >&2; exit 1; }
mkdir -p "$out"
methods=(sa bsdf+sa line-sa:v line-bd16:rand bsdf+line-sa:v/balance bsdf+line-sa:v/smooth)

# The value of MRSE row `name` in a render log ("  name  MRSE m  RMSE r").
mrse_of() { awk -v r="$2" '$1 == r && $2 == "MRSE" {print $3}' "$1"; }

for scene in $scenes; do
  scene_file="$root/scenes/$scene.json"
  hash=$(sha256sum "$scene_file" | cut -c1-12)
  reference="$out/$scene-reference-$hash-${reference_seconds}s.exr"
  reference_log="${reference%.exr}.log"
  if [[ ! -f "$reference" ]]; then
    echo "rendering the reference of $scene (bsdf+sa, $reference_seconds s compute) ..." >&2
    partial="${reference%.exr}-partial"
    "$penumbra" render "$scene_file" -m bsdf+sa --seconds "$reference_seconds" \
      --threads "$threads" --seed 99 -o "$partial.exr" > "$reference_log"
    mv "$partial.png" "${reference%.exr}.png"
    mv "$partial.exr" "$reference"
  fi
  reference_spp=$(grep -o '[0-9]* spp' "$reference_log" | head -1)
  rows=()
  sa_product=""
  regions=""
  for method in "${methods[@]}"; do
    name="${method//[\/:+]/_}"
    log="$out/$scene-$name.log"
    if "$penumbra" render "$scene_file" -m "$method" --seconds "$seconds" --threads "$threads" \
      --seed 1 --reference "$reference" -o "$out/$scene-$name.exr" > "$log" 2> "$log.err"; then
      if [[ -z "$regions" ]]; then
        regions=$(awk '$2 == "MRSE" && $1 != "image" {print $1}' "$log")
      fi
      spp=$(grep -o '[0-9]* spp' "$log" | head -1 | cut -d' ' -f1)
      spent=$(grep -o '[0-9.]* s compute' "$log" | head -1 | cut -d' ' -f1)
      image=$(mrse_of "$log" image)
      product=$(awk -v m="$image" -v s="$spent" 'BEGIN {printf "%.6g", m * s}')
      [[ "$method" == "sa" ]] && sa_product="$product"
      relative=$(awk -v p="$product" -v q="${sa_product:-0}" 'BEGIN {if (q > 0) printf "%.3f", p / q; else print "-"}')
      row="| \`$method\` | $spp | $spent | $image"
      for r in $regions; do row="$row | $(mrse_of "$log" "$r")"; done
      rows+=("$row | $relative |")
    else
      reason=$(grep -v '^\s*$' "$log.err" | tail -1 | sed 's/|/\\|/g')
      rows+=("| \`$method\` | refused | - | ${reason:-failed (see $log.err)} |")
    fi
  done
  echo
  echo "### $scene: $seconds s compute per method, $threads thread(s); reference bsdf+sa, $reference_spp"
  echo
  header="| method | spp | seconds | MRSE image"
  rule="|---|---|---|---"
  for r in $regions; do header="$header | MRSE $r"; rule="$rule|---"; done
  echo "$header | MRSE x s / sa |"
  echo "$rule|---|"
  printf '%s\n' "${rows[@]}"
done
