#!/bin/sh
# expect_refusal.sh RC PATTERN CMD...: CMD must exit with RC and print PATTERN (a refusal test).
rc_want=$1 pattern=$2
shift 2
out=$("$@" 2>&1)
rc=$?
echo "$out"
[ "$rc" -eq "$rc_want" ] || { echo "exit code $rc, want $rc_want"; exit 1; }
echo "$out" | grep -qF -- "$pattern" || { echo "no '$pattern' in the output"; exit 1; }
