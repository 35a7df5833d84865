#!/usr/bin/env bash
# Are a batch's reported numbers real? Runs a bundled batch (or reuses its result folder), renders
# a reference FACTOR times deeper than the batch's own (default 16; an exact reference gets FACTOR
# times its camera samples, an auto one FACTOR times its spp of the same method, with another
# seed), and checks every table cell's corrected MRSE against the same runs' MRSE against the
# deep reference (`penumbra check-depth`, 10% by default). Exit status 1 when a cell is outside.
#
#   tools/check_reference_depth.sh BATCH [OUT_DIR] [FACTOR]
#     BATCH    a bundled batch's name (batches/BATCH.json) or a spec path
#     OUT_DIR  default build/depth-check/BATCH (the batch's result folder, the deep reference and
#              depth-check.json/.txt go there; an existing result folder is reused)
#   Environment: PENUMBRA (the client, default build/release/client/penumbra), THREADS (of the
#   deep render, default all cores), CHECK_SECONDS (replaces the batch's budget in seconds, for a
#   quicker check; the batch then runs from a copy of its spec), CHECK_TOLERANCE (default 0.10).
set -euo pipefail
cd "$(dirname "$0")/.."
batch=${1:?usage: tools/check_reference_depth.sh BATCH [OUT_DIR] [FACTOR]}
name=$(basename "$batch" .json)
out=${2:-build/depth-check/$name}
factor=${3:-16}
penumbra=${PENUMBRA:-build/release/client/penumbra}
threads=${THREADS:-0}
spec=$batch
[[ -f $spec ]] || spec=batches/$batch.json
mkdir -p "$out"

if [[ ! -f $out/result/batch.json ]]; then
  run_spec=$spec
  if [[ -n ${CHECK_SECONDS:-} ]]; then
    # A copy of the spec beside the original (its scene path stays relative to the same folder).
    run_spec=$(dirname "$spec")/.depth-check-$name.json
    python3 - "$spec" "$run_spec" "$CHECK_SECONDS" <<'EOF'
import json, sys
spec = json.load(open(sys.argv[1]))
spec["budget"]["seconds"] = float(sys.argv[3])
json.dump(spec, open(sys.argv[2], "w"), indent=2)
EOF
    trap 'rm -f "$run_spec"' EXIT
  fi
  echo "== batch $name -> $out/result"
  /usr/bin/time -f "batch: %e s wall, %U s user" "$penumbra" batch run "$run_spec" -o "$out/result" --quiet
fi

# The deep reference: the same kind as the batch's, FACTOR times deeper, another seed.
read -r kind method sampler spp scene scene_dir fallback fallback_samples camera_samples < <(python3 - "$out/result/batch.json" "$spec" <<'EOF'
import json, os, sys
index = json.load(open(sys.argv[1]))
spec = index["spec"]
ref = index["reference"]
reference = spec.get("reference", "auto")
fallback, fallback_samples, camera_samples = "bsdf+sa", 64, 16
if isinstance(reference, dict) and reference.get("kind") == "exact":
    fallback = reference.get("fallback", fallback)
    fallback_samples = reference.get("fallback_samples", fallback_samples)
    camera_samples = reference.get("camera_samples", camera_samples)
scene = spec["scene"]
folder = os.path.dirname(os.path.abspath(sys.argv[2]))
if "/" in scene or scene.endswith(".json") or scene.endswith(".pbrt"):
    scene = os.path.normpath(os.path.join(folder, scene))
else:
    scene = os.path.join(os.path.dirname(folder), "scenes", scene + ".json")
print(ref["kind"], ref["method"].replace(" ", "_") or "-", ref.get("sampler") or "stratified",
      ref["spp"], scene, folder, fallback, fallback_samples, camera_samples)
EOF
)
deep=$out/deep-reference.exr
if [[ ! -f $deep ]]; then
  if [[ $kind == exact ]]; then
    echo "== deep exact reference: $((camera_samples * factor)) camera samples per pixel"
    /usr/bin/time -f "deep reference: %e s wall, %U s user" nice "$penumbra" exact-reference "$scene" \
      -o "$deep" --camera-samples $((camera_samples * factor)) --fallback "$fallback" \
      --fallback-samples "$fallback_samples" --seed 4242 --threads "$threads"
  elif [[ $kind == auto ]]; then
    echo "== deep reference: $method at $((spp * factor)) spp"
    /usr/bin/time -f "deep reference: %e s wall, %U s user" nice "$penumbra" render "$scene" \
      -m "$method" -s "$sampler" --spp $((spp * factor)) --seed 4242 --threads "$threads" \
      -o "$deep" --quiet
  else
    echo "check_reference_depth: a $kind reference: give the deep reference as $deep" >&2
    exit 2
  fi
fi
"$penumbra" check-depth "$out/result" --deep "$deep" --tolerance "${CHECK_TOLERANCE:-0.10}" \
  --json "$out/depth-check.json" | tee "$out/depth-check.txt"
