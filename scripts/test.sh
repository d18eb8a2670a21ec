#!/usr/bin/env bash
# The README's second command: install what is missing, build, run every test.
#   bash scripts/test.sh            everything: all CTest labels in the Release build, then the
#                                   unit and net labels under ASan+UBSan, the net label under TSan,
#                                   the container label (builds the image with buildah, runs it),
#                                   and every fuzz target for 10 s (PEAKCAST_FUZZ_SECONDS)
#   bash scripts/test.sh -L unit    only the Release build's CTest, with these ctest arguments
# Each part is timed; the last line sums the tests of every part ("N passed, N failed").
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
install_packages "${PEAKCAST_PACKAGES[@]}" "${PEAKCAST_TEST_PACKAGES[@]}"
install_node_modules

declare -a part_names part_secs
tally=$(mktemp)  # "passed failed" lines from every part (parts may run in subshells)
failures=$(mktemp)  # "part: test" for every test that failed, repeated at the end of the output
details=$(mktemp)  # why each failed: the telling lines of its output, repeated at the very end
trap 'rm -f "$tally" "$failures" "$details"' EXIT
# with_env VAR=value... CMD: runs CMD (a function too) with those variables, in a subshell.
with_env() {
  (
    while [[ $1 == *=* ]]; do export "$1"; shift; done
    "$@"
  )
}
# part NAME CMD...: runs CMD, records its wall time; a failing part is counted, the run goes on.
part() {
  local name=$1 start=$SECONDS rc=0
  shift
  echo "== peakcast test part: $name"
  "$@" || rc=$?
  part_names+=("$name")
  part_secs+=($((SECONDS - start)))
  [[ $rc -eq 0 ]] || { echo "== part '$name' failed (exit $rc)"; any_failed=1; }
  return 0
}
# ctest_counted DIR ARGS...: ctest, adding its counts to the totals.
ctest_counted() {
  local dir=$1 log
  shift
  log=$(mktemp)
  (cd "$dir" && ctest --output-on-failure -j"$(nproc)" --timeout 900 "$@") 2>&1 | tee "$log"
  local rc=${PIPESTATUS[0]}
  local total fails
  total=$(grep -oE 'tests passed, [0-9]+ tests failed out of [0-9]+' "$log" | grep -oE '[0-9]+$' | tail -1)
  fails=$(grep -oE '[0-9]+ tests failed out of' "$log" | grep -oE '^[0-9]+' | tail -1)
  echo "$((${total:-0} - ${fails:-0})) ${fails:-0}" >>"$tally"
  # CTest lists them after "The following tests FAILED:", one "\t<n> - <name> (<why>)" a line.
  sed -n '/The following tests FAILED:/,$p' "$log" | grep -E '^[[:space:]]+[0-9]+ - ' |
    sed "s|^[[:space:]]*|${dir##*/}: |" >>"$failures"
  # A CI log is read from its end: each failed test's own lines that say why, there too.
  local name
  sed -n '/The following tests FAILED:/,$p' "$log" | sed -nE 's/^[[:space:]]+[0-9]+ - ([^ ]+) .*/\1/p' |
    while read -r name; do
      echo "-- ${dir##*/}: $name" >>"$details"
      awk -v t="$name" '{s = $0} sub(/^[0-9]+\/[0-9]+ Test: /, "", s) && s == t {on = 1} on && /^<end of output>/ {exit} on' \
        "$dir/Testing/Temporary/LastTest.log" 2>/dev/null |
        grep -E 'FAIL|rror|ssert|not ok|✖|Sanitizer|Which is|Expected|timed out' | head -n 25 >>"$details" || true
    done
  rm -f "$log"
  return "$rc"
}
# fuzz_counted SECONDS: every fuzz target, each counted as one test.
fuzz_counted() {
  local log rc
  log=$(mktemp)
  bash "$PEAKCAST_ROOT/scripts/fuzz.sh" "$1" 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  local line
  line=$(grep -E '^fuzz: [0-9]+ passed, [0-9]+ failed' "$log" | tail -1)
  grep -E '^fuzz_[a-z_]+ .* FAILED' "$log" | sed 's/^/fuzz: /' >>"$failures" || true
  echo "$(echo "$line" | grep -oE '[0-9]+ passed' | grep -oE '[0-9]+' || echo 0) $(echo "$line" | grep -oE '[0-9]+ failed' | grep -oE '[0-9]+' || echo 1)" >>"$tally"
  rm -f "$log"
  return "$rc"
}
any_failed=0

part "build (Release)" build_peakcast Release
if [[ $# -gt 0 ]]; then
  part "ctest $*" ctest_counted "$BUILD_DIR" "$@"
else
  # The container label builds an image for minutes: a part of its own, alone on the machine.
  part "tests: all labels but container" ctest_counted "$BUILD_DIR" -LE container
  if [[ -z ${PEAKCAST_SKIP_SANITIZERS:-} ]]; then
    asan=$PEAKCAST_ROOT/build-asan tsan=$PEAKCAST_ROOT/build-tsan
    # Sanitizer builds hold only what their labels run (CMake targets peakcast_label_<label>).
    part "build (ASan+UBSan)" with_env PEAKCAST_TARGETS="peakcast_label_unit peakcast_label_net" \
      build_peakcast RelWithDebInfo "$asan" -DPEAKCAST_SANITIZE=ON
    # Mesa keeps allocations until exit: leak checks only where no GL runs (the unit label).
    part "tests: unit under ASan+UBSan" with_env UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
      ASAN_OPTIONS=detect_leaks=1 ctest_counted "$asan" -L unit
    part "tests: net under ASan+UBSan" with_env UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
      ASAN_OPTIONS=detect_leaks=0 ctest_counted "$asan" -L net
    part "build (TSan)" with_env PEAKCAST_TARGETS=peakcast_label_net build_peakcast RelWithDebInfo "$tsan" -DPEAKCAST_TSAN=ON
    part "tests: net under TSan" with_env TSAN_OPTIONS="halt_on_error=1 suppressions=$PEAKCAST_ROOT/tests/tsan.supp" \
      ctest_counted "$tsan" -L net
  fi
  if [[ -z ${PEAKCAST_SKIP_CONTAINER:-} ]]; then
    part "container: build the image, run it" ctest_counted "$BUILD_DIR" -L container
  fi
  if [[ -z ${PEAKCAST_SKIP_FUZZ:-} ]]; then
    part "fuzz (${PEAKCAST_FUZZ_SECONDS:-10} s per target)" fuzz_counted "${PEAKCAST_FUZZ_SECONDS:-10}"
  fi
fi

echo "== wall time by part"
for i in "${!part_names[@]}"; do printf '%6d s  %s\n' "${part_secs[$i]}" "${part_names[$i]}"; done
printf '%6d s  total\n' "$SECONDS"
passed=$(awk '{p += $1} END {print p + 0}' "$tally")
failed=$(awk '{f += $2} END {print f + 0}' "$tally")
echo "$passed passed, $failed failed"
if [[ -s $failures ]]; then
  echo "== why (the lines of each failed test's output that say so; whole output above)"
  cat "$details"
  echo "== failed tests (build folder: ctest number - name)"
  cat "$failures"
fi
[[ $any_failed -eq 0 && $failed -eq 0 ]]
