#!/usr/bin/env bash
# Per-sample cost of every method on the seed system's Cornell box, in one run: each method
# renders scenes/cornell-box.json (the seed's cornell-box.pbrt, same triangles, camera and light)
# at 512x512 with the random sampler and one light sample, on one thread, as a whole process
# (`penumbra render`), once at 1 spp and once at 16 spp. Printed per method, as a markdown table:
#   whole ns   the 16-spp process's user+sys CPU time per camera sample (what a user waits for,
#              scene load, BVH build and EXR writing included), the figure the seed's are
#              measured as;
#   render ns  (CPU at 16 spp - CPU at 1 spp) / (15 camera samples per pixel): the cost of a
#              sample without the fixed costs;
#   fixed s    CPU at 1 spp minus one pass at the render rate: loading, BVHs, writing;
#   seed ns    the seed system's whole-process figure for its matching integrator (measured on
#              this kind of machine: one thread, 512x512, 16 spp), and seed / whole.
# Methods a scene refuses get a row with the refusal. Timings on a shared machine are noisy:
# compare the rows of one run.
#
#   bench/compare.sh [--build DIR] [--scene FILE] [--spp N] [--methods "m1 m2 ..."]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build/release"
scene="$root/scenes/cornell-box.json"
spp=16
methods=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --scene) scene="$2"; shift 2 ;;
    --spp) spp="$2"; shift 2 ;;
    --methods) methods="$2"; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "compare.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
penumbra="$build/client/penumbra"
[[ -x "$penumbra" ]] || { echo "compare.sh: $penumbra not built (ninja -C $build penumbra)" >&2; exit 2; }
[[ "$spp" -ge 2 ]] || { echo "compare.sh: --spp must be at least 2" >&2; exit 2; }

# Penumbra method -> the seed integrator it matches and that integrator's ns per camera sample
# (pt-surf-area, pt-solid-angle, brdf, line-surf-area, line-solid-angle, brdf + line-solid-angle,
# two line-surf-area directions).
declare -A seed_name=(
  [area]=pt-surf-area [sa]=pt-solid-angle [bsdf]=brdf [line-area:v]=line-surf-area
  [line-sa:u]=line-solid-angle [bsdf+line-sa:u/balance]="brdf+line-solid-angle"
  [line-area:u+line-area:v/balance]="line-surf-area x2")
declare -A seed_ns=(
  [area]=2305 [sa]=2425 [bsdf]=2413 [line-area:v]=2505 [line-sa:u]=2539
  [bsdf+line-sa:u/balance]=2846 [line-area:u+line-area:v/balance]=3410)
if [[ -z "$methods" ]]; then
  methods="area sa bsdf psa bsdf+sa/balance line-area:v line-sa:u line-sa:v"
  methods+=" bsdf+line-sa:u/balance line-area:u+line-area:v/balance"
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# CPU seconds (user + sys) of one render, or the refusal on stderr.
cpu_of() {  # method spp
  local log="$work/time.log"
  if ! /usr/bin/time -f '%U %S' -o "$log" "$penumbra" render "$scene" -m "$1" -s random \
         --spp "$2" --threads 1 --seed 1 --quiet -o "$work/out.exr" >"$work/stdout" 2>"$work/stderr"; then
    return 1
  fi
  awk '{printf "%.3f", $1 + $2}' "$log"
}

width=512 height=512
read -r width height < <(python3 -c "import json,sys; c=json.load(open(sys.argv[1])).get('camera',{}); print(c.get('width',512), c.get('height',512))" "$scene" 2>/dev/null || echo "512 512")
pixels=$((width * height))
echo "scene $(basename "$scene") ${width}x${height}, random sampler, 1 thread, ${spp} spp"
echo
echo "| method | whole ns | render ns | fixed s | seed integrator | seed ns | seed / whole |"
echo "|---|---|---|---|---|---|---|"
for method in $methods; do
  if ! one=$(cpu_of "$method" 1) || ! many=$(cpu_of "$method" "$spp"); then
    echo "| \`$method\` | refused: $(tr '\n' ' ' <"$work/stderr" | cut -c1-100) | | | | | |"
    continue
  fi
  python3 - "$method" "$one" "$many" "$spp" "$pixels" "${seed_name[$method]:-}" "${seed_ns[$method]:-}" <<'EOF'
import sys
method, one, many, spp, pixels, seed_name, seed_ns = sys.argv[1:]
one, many, spp, pixels = float(one), float(many), int(spp), int(pixels)
whole = many / (spp * pixels) * 1e9
render = max(many - one, 0.0) / ((spp - 1) * pixels) * 1e9
fixed = one - render * pixels * 1e-9
seed = f"{seed_ns}" if seed_ns else ""
ratio = f"{float(seed_ns) / whole:.1f}x" if seed_ns else ""
print(f"| `{method}` | {whole:,.0f} | {render:,.0f} | {fixed:.2f} | {seed_name} | {seed} | {ratio} |")
EOF
done
