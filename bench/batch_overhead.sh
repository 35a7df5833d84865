#!/usr/bin/env bash
# Batch overhead (issue #7 benchmark): a 4-method batch with a budget of 10 compute seconds per
# method on one worker with one render thread. Goal: the batch's wall time (submission to done,
# calibration included) within 15% of the 40 s of compute its equal-time runs are budgeted.
# The reference is rendered first by a warm-up batch and then reused from the cache, so it is
# not part of the timed batch.
#
#   bash bench/batch_overhead.sh [BUILD_DIR] [SECONDS_PER_METHOD]
set -euo pipefail
build=$(cd "${1:-build}" && pwd)
per_method=${2:-10}
source_dir=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d /tmp/penumbra-batch-overhead.XXXXXX)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

"$build/server/penumbra-coordinator" --listen 127.0.0.1:0 --data-dir "$work/data" \
  --port-file "$work/port" >"$work/coordinator.log" 2>&1 &
pids+=($!)
for _ in $(seq 200); do [ -s "$work/port" ] && break; sleep 0.05; done
address="127.0.0.1:$(cat "$work/port")"
"$build/worker/penumbra-worker" --coordinator "$address" --threads 1 --cache-dir "$work/cache" \
  --name bench >"$work/worker.log" 2>&1 &
pids+=($!)

scene="$source_dir/scenes/cornell-occluders.json"
write_spec() {  # name budget
  cat >"$work/$1.json" <<JSON
{"format": "penumbra/batch@1", "name": "$1", "scene": "$scene",
 "methods": ["area", "sa", "bsdf+sa", "line-sa:v"],
 "budget": $2,
 "reference": {"method": "bsdf+sa", "spp": 8}}
JSON
}
write_spec warm '{"spp": [1]}'
write_spec timed "{\"seconds\": $per_method}"
"$build/client/penumbra" batch run "$work/warm.json" -o "$work/warm" --coordinator "$address" \
  --no-report >/dev/null
"$build/client/penumbra" batch run "$work/timed.json" -o "$work/timed" --coordinator "$address" \
  --no-report >"$work/timed.log"

python3 - "$work/timed/batch.json" "$per_method" <<'PY'
import json, sys
index = json.load(open(sys.argv[1]))
per_method = float(sys.argv[2])
budget = per_method * len(index["methods"])
runs = [(m["label"], r) for m in index["methods"] for r in m["runs"] if r.get("equal_time")]
compute = sum(r["compute_seconds"] for _, r in runs)
wall = index["wall_seconds"]
print(f"batch {index['batch_id']}: {len(runs)} methods x {per_method:g} s, reference cached: "
      f"{index['reference']['cached']}")
for label, run in runs:
    print(f"  {label:12s} {run['spp']:5d} spp  {run['compute_seconds']:7.2f} compute s  "
          f"{run['wall_seconds']:7.2f} wall s  MRSE {run['errors'][0]['mrse']:.4g}")
print(f"runs' compute {compute:.2f} s, all jobs' compute (calibration included) "
      f"{index['compute_seconds']:.2f} s")
print(f"batch wall {wall:.2f} s vs {budget:g} s budgeted compute: "
      f"{100 * (wall / budget - 1):+.1f}% (goal within +15%)")
PY
