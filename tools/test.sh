#!/usr/bin/env bash
# Builds Penumbra and runs every test: the Release build (all tests, farm included), then the
# core tests again under AddressSanitizer + UndefinedBehaviorSanitizer. Ends with one line
# "N passed, N failed". Installs what it needs first (Debian 12, as root).
#   PENUMBRA_SKIP_SANITIZE=1  skip the sanitizer pass (quick local runs)
#   PENUMBRA_JOBS=N           build jobs (default: cores)
set -uo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh || { echo "setup failed"; exit 1; }
jobs=${PENUMBRA_JOBS:-$(nproc)}
passed=0
failed=0
status=0

run_suite() {  # name build-dir ctest-exclude-regex cmake-args...
  local name=$1 dir=$2 exclude=$3
  shift 3
  echo "== $name: configure and build ($dir)"
  if ! cmake -S . -B "$dir" -G Ninja "$@" >"$dir.configure.log" 2>&1; then
    cat "$dir.configure.log"; echo "$name: configure failed"; failed=$((failed + 1)); status=1; return
  fi
  if ! ninja -C "$dir" -j "$jobs" >"$dir.build.log" 2>&1; then
    tail -n 60 "$dir.build.log"; echo "$name: build failed"; failed=$((failed + 1)); status=1; return
  fi
  echo "== $name: ctest"
  local log="$dir.ctest.log"
  local filter=()
  [ -n "$exclude" ] && filter=(-E "$exclude")
  (cd "$dir" && ctest --output-on-failure -j "$jobs" --timeout 900 "${filter[@]}") 2>&1 | tee "$log"
  local total fails
  total=$(sed -n 's/.*tests failed out of \([0-9]*\).*/\1/p' "$log" | tail -n 1)
  fails=$(sed -n 's/.* \([0-9]*\) tests failed out of.*/\1/p' "$log" | tail -n 1)
  if [ -z "$total" ]; then echo "$name: ctest printed no summary"; failed=$((failed + 1)); status=1; return; fi
  passed=$((passed + total - fails))
  failed=$((failed + fails))
  [ "$fails" = 0 ] || status=1
}

mkdir -p build
run_suite "release" build/release "" -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_FARM=ON -DPENUMBRA_BENCH=ON
if [ "${PENUMBRA_SKIP_SANITIZE:-0}" != 1 ]; then
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  # The paper reproductions are statistical end-to-end runs of code the unit tests cover; under
  # the sanitizers they would take most of the budget, so they run in the release pass only.
  run_suite "asan+ubsan" build/sanitize "^(ReproductionSuite|LinesSalesinJarosz|LinesBillenDutre)\\." \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPENUMBRA_SANITIZE=ON \
    -DPENUMBRA_FARM=OFF -DPENUMBRA_BENCH=OFF
fi
echo "$passed passed, $failed failed"
exit $status
