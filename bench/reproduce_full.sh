#!/bin/sh
# The paper-reproduction suite's full run (the README's table) and its wall time.
#
#   bench/reproduce_full.sh [BUILD_DIR] [OUT_DIR]
#
# Runs `penumbra reproduce --full`, which prints the table (paper figure beside ours, with pass or
# fail) and writes the charts (SVG, PNG), reproduce.json and details.txt into OUT_DIR; then prints
# the wall time of the whole run. Exit code: the command's (4 when a row fails).
set -eu
build_dir=${1:-build}
out_dir=${2:-reproduce-full}
penumbra="$build_dir/client/penumbra"
if [ ! -x "$penumbra" ]; then
  echo "reproduce_full.sh: $penumbra not found; build the 'penumbra' target first" >&2
  exit 2
fi
start=$(date +%s)
status=0
"$penumbra" reproduce --full -o "$out_dir" || status=$?
end=$(date +%s)
echo "reproduce --full: $((end - start)) s wall, exit code $status, outputs in $out_dir"
exit $status
