#!/usr/bin/env bash
# Builds Penumbra and runs every test: the Release build (all tests, farm included), then the
# core tests again under AddressSanitizer + UndefinedBehaviorSanitizer, then the libFuzzer
# targets of fuzz/ (a small clang build of only them) each for a bounded time under ASan + UBSan
# + LeakSanitizer, two at a time, each counted as one test. Ends with one line
# "N passed, N failed". Installs what it needs first (Debian 12, as root).
#   PENUMBRA_SKIP_SANITIZE=1  skip the sanitizer pass and the fuzzing (quick local runs)
#   PENUMBRA_FUZZ_SECONDS=N   seconds per fuzz target (default 20; 0 skips the fuzzing)
#   PENUMBRA_JOBS=N           build jobs (default: cores)
set -uo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh || { echo "setup failed"; exit 1; }
jobs=${PENUMBRA_JOBS:-$(nproc)}
fuzz_seconds=${PENUMBRA_FUZZ_SECONDS:-20}
started=$SECONDS
# Elapsed time since the start, printed with each phase (the whole command must stay well under
# 30 minutes on CI's 2 cores).
elapsed() { printf '[%dm%02ds]' $(((SECONDS - started) / 60)) $(((SECONDS - started) % 60)); }
passed=0
failed=0
skipped=0
status=0

run_suite() {  # name build-dir ctest-exclude-regex cmake-args...
  local name=$1 dir=$2 exclude=$3
  shift 3
  echo "== $(elapsed) $name: configure and build ($dir)"
  if ! cmake -S . -B "$dir" -G Ninja "$@" >"$dir.configure.log" 2>&1; then
    cat "$dir.configure.log"; echo "$name: configure failed"; failed=$((failed + 1)); status=1; return
  fi
  if ! ninja -C "$dir" -j "$jobs" >"$dir.build.log" 2>&1; then
    tail -n 60 "$dir.build.log"; echo "$name: build failed"; failed=$((failed + 1)); status=1; return
  fi
  echo "== $(elapsed) $name: ctest"
  local log="$dir.ctest.log"
  local filter=()
  [ -n "$exclude" ] && filter=(-E "$exclude")
  (cd "$dir" && ctest --output-on-failure -j "$jobs" --timeout 900 "${filter[@]}") 2>&1 | tee "$log"
  local total fails skips
  total=$(sed -n 's/.*tests failed out of \([0-9]*\).*/\1/p' "$log" | tail -n 1)
  fails=$(sed -n 's/.* \([0-9]*\) tests failed out of.*/\1/p' "$log" | tail -n 1)
  if [ -z "$total" ]; then echo "$name: ctest printed no summary"; failed=$((failed + 1)); status=1; return; fi
  # Skipped tests (the farm's test programs in a build without the farm) count neither way.
  skips=$(sed -n '/The following tests did not run:/,/^$/p' "$log" | grep -c '(Skipped)' || true)
  passed=$((passed + total - fails - skips))
  skipped=$((skipped + skips))
  failed=$((failed + fails))
  [ "$fails" = 0 ] || status=1
}

# Each libFuzzer target of fuzz/ for `seconds`, two at a time (2 cores), new inputs going to a
# scratch corpus (the committed seeds in fuzz/corpus/<target>/ are only read). A target passes
# when it finishes without a crash, leak, timeout or sanitizer report; a failing input is kept as
# <dir>/fuzz-artifacts/<target>-crash-... (reproduce: <dir>/fuzz/fuzz_<target> <that file>).
run_fuzzers() {  # build-dir seconds
  local dir=$1 seconds=$2
  # The targets the build configured (fuzz_batch_spec only once core/batch/ exists).
  local targets=() target
  for target in "$dir"/fuzz/fuzz_*; do
    [ -x "$target" ] && [ -f "$target" ] && targets+=("${target##*/fuzz_}")
  done
  if [ "${#targets[@]}" = 0 ]; then
    echo "fuzzing: no fuzz_* programs in $dir/fuzz"; failed=$((failed + 1)); status=1; return
  fi
  echo "== $(elapsed) fuzzing: ${#targets[@]} targets, ${seconds} s each, 2 at a time"
  rm -rf "$dir/fuzz-work" "$dir/fuzz-artifacts"
  mkdir -p "$dir/fuzz-work" "$dir/fuzz-artifacts"
  local running=0
  for target in "${targets[@]}"; do
    (
      local binary="$dir/fuzz/fuzz_$target" log="$dir/fuzz-work/$target.log"
      local options=(-max_total_time="$seconds" -timeout=30 -rss_limit_mb=2048 -print_final_stats=1
                     -artifact_prefix="$dir/fuzz-artifacts/$target-")
      [ -f "fuzz/dictionaries/$target.dict" ] && options+=(-dict="fuzz/dictionaries/$target.dict")
      mkdir -p "$dir/fuzz-work/$target"
      "$binary" "${options[@]}" "$dir/fuzz-work/$target" "fuzz/corpus/$target" >"$log" 2>&1
      echo $? >"$dir/fuzz-work/$target.rc"
    ) &
    running=$((running + 1))
    if [ "$running" -ge 2 ]; then wait -n; running=$((running - 1)); fi
  done
  wait
  for target in "${targets[@]}"; do
    local rc log="$dir/fuzz-work/$target.log"
    rc=$(cat "$dir/fuzz-work/$target.rc" 2>/dev/null || echo 1)
    if [ "$rc" = 0 ]; then
      passed=$((passed + 1))
      echo "fuzz_$target: passed ($(grep -m1 -o 'stat::number_of_executed_units: [0-9]*' "$log" | sed 's/.*: //') runs, $(grep -o 'cov: [0-9]*' "$log" | tail -n 1))"
    else
      failed=$((failed + 1)); status=1
      echo "fuzz_$target: FAILED (exit $rc); the end of its log ($log):"
      tail -n 40 "$log"
    fi
  done
}

mkdir -p build
# The release pass builds every integration test (farm, faults, batches, paper reproductions,
# CLI) but of the unit tests of tests/core only the browser checks: the sanitizer pass below runs
# every other unit test, and building them in both passes cost about a quarter of the command.
# With PENUMBRA_SKIP_SANITIZE=1 the release pass builds them all instead.
core_tests="report/viewer_browser_test;report/batch_report_test"
[ "${PENUMBRA_SKIP_SANITIZE:-0}" = 1 ] && core_tests=""
run_suite "release" build/release "" -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_FARM=ON -DPENUMBRA_BENCH=ON \
  "-DPENUMBRA_CORE_TESTS=$core_tests"
if [ "${PENUMBRA_SKIP_SANITIZE:-0}" != 1 ]; then
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  # The paper reproductions and the bias check of every method on every bundled scene
  # (tests/reproduce) and the equal-time batches (tests/batch) are statistical end-to-end runs of
  # code the unit tests cover; under the sanitizers they would take most of the budget, so they
  # are built and run in the release pass only.
  # -O1 with line tables only (-g1): ASan's usual level; the build takes about half the time of
  # -O2 -g (measured 233 s against 429 s on 2 cores) and its tests ran as fast (94 s against 102 s).
  # The browser checks drive Chromium (not instrumented) over pages the release pass checks too.
  run_suite "asan+ubsan" build/sanitize "^(ViewerBrowser\\.|BatchReportTest\\.HtmlRendersInHeadlessChromium$)" \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
    -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DPENUMBRA_SANITIZE=ON \
    -DPENUMBRA_FARM=OFF -DPENUMBRA_BENCH=OFF "-DPENUMBRA_SKIP_TEST_FOLDERS=reproduce;batch"
  # The fuzzers need clang (libFuzzer). The sanitizer pass stays with gcc: the tree is written
  # for gcc 12 and clang 14 lacks some of its C++20 (capturing structured bindings in lambdas
  # broke core/report once), so a new file could break a clang pass. The fuzzers get a small
  # clang tree of their own that builds only them and the libraries they test.
  if [ "$fuzz_seconds" != 0 ]; then
    echo "== $(elapsed) fuzz targets: configure and build (build/fuzz, clang)"
    if CC=clang CXX=clang++ cmake -S . -B build/fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
         -DPENUMBRA_SANITIZE=ON -DPENUMBRA_FUZZ=ON -DPENUMBRA_FARM=OFF -DPENUMBRA_BENCH=OFF \
         -DPENUMBRA_TESTS=OFF >build/fuzz.configure.log 2>&1 &&
       ninja -C build/fuzz -j "$jobs" fuzzers >build/fuzz.build.log 2>&1; then
      run_fuzzers build/fuzz "$fuzz_seconds"
    else
      tail -n 60 build/fuzz.configure.log build/fuzz.build.log; echo "fuzz targets: build failed"
      failed=$((failed + 1)); status=1
    fi
  else
    echo "== fuzzing skipped (PENUMBRA_FUZZ_SECONDS=0)"
  fi
fi
echo "== $(elapsed) done; $skipped skipped (not counted: tests that need the farm, in the build without it, or need files that are absent)"
echo "$passed passed, $failed failed"
exit $status
