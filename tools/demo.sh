#!/usr/bin/env bash
# Builds Penumbra and runs the demo: the bundled equal-time comparison on cornell-occluders,
# written with its report to ./demo-out (or the folder given as the first argument).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-demo-out}
bash tools/setup.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_FARM=ON -DPENUMBRA_BENCH=OFF >/dev/null
ninja -C build/release penumbra
./build/release/client/penumbra demo -o "$out"
