#!/usr/bin/env bash
# Runs every libFuzzer target in tests/fuzz for SECONDS each (default 30): clang build in its own
# directory (incremental), corpora kept between runs (build-fuzz/corpus), seeds from
# tests/fuzz/seeds/<target>/ and dictionaries tests/fuzz/<target>.dict. A crash, leak or timeout
# fails the run and leaves the input in build-fuzz/findings/ (add it as a regression test).
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
seconds=${1:-30}
shift || true
FUZZ_DIR=${PEAKCAST_FUZZ_BUILD_DIR:-$PEAKCAST_ROOT/build-fuzz}
command -v clang++ >/dev/null || install_packages clang libclang-rt-14-dev
# Configured every run (incremental): a target added since the last run is then known.
cmake -S "$PEAKCAST_ROOT" -B "$FUZZ_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DPEAKCAST_FUZZ=ON -DPEAKCAST_WITH_GL=OFF -DPEAKCAST_BUILD_TESTS=OFF \
  $(peakcast_ccache_flags) >/dev/null
targets=("$@")
if [[ ${#targets[@]} -eq 0 ]]; then
  for f in "$PEAKCAST_ROOT"/tests/fuzz/fuzz_*.cpp; do targets+=("$(basename "${f%.cpp}")"); done
fi
cmake --build "$FUZZ_DIR" -j"$(nproc)" --target "${targets[@]}" >/dev/null
mkdir -p "$FUZZ_DIR/findings"
failed=0
printf '%-24s %12s %8s  %s\n' target executions seconds result
for t in "${targets[@]}"; do
  corpus=$FUZZ_DIR/corpus/$t
  mkdir -p "$corpus"
  args=(-max_total_time="$seconds" -print_final_stats=1 -timeout=10 -rss_limit_mb=2048
        -artifact_prefix="$FUZZ_DIR/findings/$t-" "$corpus")
  [[ -d $PEAKCAST_ROOT/tests/fuzz/seeds/$t ]] && args+=("$PEAKCAST_ROOT/tests/fuzz/seeds/$t")
  [[ -f $PEAKCAST_ROOT/tests/fuzz/$t.dict ]] && args=(-dict="$PEAKCAST_ROOT/tests/fuzz/$t.dict" "${args[@]}")
  # tests/fuzz/<target>.options: that target's own libFuzzer flags (e.g. a tighter malloc limit).
  [[ -f $PEAKCAST_ROOT/tests/fuzz/$t.options ]] && read -r -a extra <"$PEAKCAST_ROOT/tests/fuzz/$t.options" &&
    args=("${extra[@]}" "${args[@]}")
  log=$FUZZ_DIR/$t.log
  start=$SECONDS
  if (cd "$FUZZ_DIR" && "$FUZZ_DIR/tests/fuzz/$t" "${args[@]}") >"$log" 2>&1; then result=ok; else
    result="FAILED (see $log)"
    failed=$((failed + 1))
  fi
  execs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' | tail -1)
  printf '%-24s %12s %8s  %s\n' "$t" "${execs:-?}" "$((SECONDS - start))" "$result"
done
total=${#targets[@]}
echo "fuzz: $((total - failed)) passed, $failed failed"
[[ $failed -eq 0 ]]
