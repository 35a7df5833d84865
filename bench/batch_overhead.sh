#!/usr/bin/env bash
# Batch overhead: a 4-method batch with a budget of 10 compute seconds per
# method on one worker with one render thread. Goal: the batch's wall time (submission to done,
# calibration included) within 15% of the 40 s of compute its equal-time runs are budgeted.
# The reference is rendered first by a warm-up batch and then reused from the cache, so it is
# not part of the timed batch. Also printed, from the kernel's per-thread accounting
# (/proc/PID/task/TID/schedstat) over the timed batch: the coordinator's and the worker's CPU
# seconds, and the worker's render thread's wall split into on a CPU, runnable but waiting for
# one (the machine's load), and neither (waiting for work: the farm's own overhead).
#
#   bash bench/batch_overhead.sh [BUILD_DIR] [SECONDS_PER_METHOD]
# PENUMBRA_BENCH_KEEP=DIR keeps the coordinator's and worker's logs and data in DIR.
set -euo pipefail
build=$(cd "${1:-build}" && pwd)
per_method=${2:-10}
source_dir=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d /tmp/penumbra-batch-overhead.XXXXXX)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  if [ -n "${PENUMBRA_BENCH_KEEP:-}" ]; then
    rm -rf "$PENUMBRA_BENCH_KEEP" && mv "$work" "$PENUMBRA_BENCH_KEEP"
  else
    rm -rf "$work"
  fi
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
# Per thread of the coordinator and the worker: nanoseconds on a CPU and waiting for one
# (runnable, not running: /proc/PID/task/TID/schedstat).
sched_snapshot() {  # label pid
  for task in /proc/"$2"/task/*; do
    read -r run wait _ <"$task/schedstat"
    echo "$1 ${task##*/} $(tr ' ' '_' <"$task/comm") $run $wait"
  done
}
write_spec warm '{"spp": [1]}'
write_spec timed "{\"seconds\": $per_method}"
"$build/client/penumbra" batch run "$work/warm.json" -o "$work/warm" --coordinator "$address" \
  --no-report >/dev/null
{ sched_snapshot coordinator "${pids[0]}"; sched_snapshot worker "${pids[1]}"; } >"$work/sched.before"
"$build/client/penumbra" batch run "$work/timed.json" -o "$work/timed" --coordinator "$address" \
  --no-report >"$work/timed.log"
{ sched_snapshot coordinator "${pids[0]}"; sched_snapshot worker "${pids[1]}"; } >"$work/sched.after"

python3 - "$work/timed/batch.json" "$per_method" "$work/sched.before" "$work/sched.after" <<'PY'
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
print(f"batch wall vs its jobs' compute: {100 * (wall / index['compute_seconds'] - 1):+.1f}%")

# Where the wall time went, from the kernel's per-thread accounting during the timed batch.
def load(path):
    threads = {}
    for line in open(path):
        process, tid, comm, run, wait = line.split()
        threads[(process, tid)] = (comm, int(run) / 1e9, int(wait) / 1e9)
    return threads
before, after = load(sys.argv[3]), load(sys.argv[4])
delta = {key: (comm, run - before.get(key, (comm, 0, 0))[1], wait - before.get(key, (comm, 0, 0))[2])
         for key, (comm, run, wait) in after.items()}
for process in ("coordinator", "worker"):
    run = sum(d[1] for key, d in delta.items() if key[0] == process)
    print(f"{process}: {run:.2f} s on a CPU over all threads")
render = max((d for key, d in delta.items() if key[0] == "worker"), key=lambda d: d[1])
print(f"worker's busiest thread ({render[0]}): {render[1]:.2f} s on a CPU, {render[2]:.2f} s "
      f"runnable but waiting for a CPU, {wall - render[1] - render[2]:.2f} s of the wall neither")
PY
