#!/usr/bin/env bash
# Runs every test of the workspace, or of the packages named as arguments:
#   1. unit tests: pytest over catkin_ws/src/<pkg>/test/unit (no ROS master needed),
#   2. integration tests: every catkin_ws/src/<pkg>/test/*.test with rostest.
# Each rostest runs in its own network namespace (unshare -n) when the kernel allows it, so that several
# rostests (or a developer's roscore) never fight over the master port. Prints 'N passed, N failed'.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
set +u; source "$ROOT/env.sh"; set -u  # ROS's setup scripts read unset variables
SRC="$ROOT/catkin_ws/src"
RESULTS="${TEST_RESULTS_DIR:-$ROOT/test_results}"
mkdir -p "$RESULTS"
if [ $# -gt 0 ]; then PKGS=("$@"); else mapfile -t PKGS < <(ls "$SRC" | sort); fi
ROSTEST_TIMEOUT="${ROSTEST_TIMEOUT:-600}"
passed=0; failed=0; failures=()

# ---- unit tests ----------------------------------------------------------------------------------
unit_dirs=()
[ $# -eq 0 ] && unit_dirs+=("$ROOT/tests")   # workspace-level checks
for p in "${PKGS[@]}"; do [ -d "$SRC/$p/test/unit" ] && unit_dirs+=("$SRC/$p/test/unit"); done
# One pytest run per package: test modules of different packages may share a basename (test_geometry.py).
for d in "${unit_dirs[@]}"; do
  tag="$(basename "$(dirname "$(dirname "$d")")")"; [ "$d" = "$ROOT/tests" ] && tag=workspace
  echo "=== unit tests: ${d#$ROOT/}"
  xml="$RESULTS/unit_${tag}_$$.xml"
  (cd "$d" && python -m pytest -q -p no:cacheprovider --timeout=300 --junitxml="$xml" .) \
    > "$RESULTS/unit_${tag}.log" 2>&1
  rc=$?
  tail -1 "$RESULTS/unit_${tag}.log" | sed 's/^/    /'
  counts=$(python - "$xml" 2>/dev/null <<'PY'
import sys, xml.etree.ElementTree as ET
r = ET.parse(sys.argv[1]).getroot(); s = r if r.tag == "testsuite" else r.find("testsuite")
t, f, e, sk = (int(s.get(k, 0)) for k in ("tests", "failures", "errors", "skipped"))
print(t - f - e - sk, f + e)
PY
)
  read -r up uf <<<"${counts:-0 0}"
  passed=$((passed + up)); failed=$((failed + uf))
  if [ "$rc" -ne 0 ]; then
    [ "$uf" -eq 0 ] && failed=$((failed + 1))
    failures+=("unit tests of $tag"); sed -n '/= FAILURES =\|= ERRORS =/,$p' "$RESULTS/unit_${tag}.log" | tail -80
  fi
done

# ---- rostest -------------------------------------------------------------------------------------
isolate=()
if unshare -n true 2>/dev/null; then isolate=(unshare -n sh -c 'ip link set lo up 2>/dev/null; exec "$@"' sh); fi
for p in "${PKGS[@]}"; do
  [ -n "${SKIP_ROSTEST:-}" ] && break   # SKIP_ROSTEST=1: unit tests only
  for t in "$SRC/$p"/test/*.test; do
    [ -e "$t" ] || continue
    name="$p/$(basename "$t")"
    echo "=== rostest $name"
    start=$(date +%s)
    timeout -k 10 "$ROSTEST_TIMEOUT" "${isolate[@]}" rostest --text "$p" "$(basename "$t")" \
      > "$RESULTS/${p}__$(basename "$t" .test).log" 2>&1
    rc=$?
    log="$RESULTS/${p}__$(basename "$t" .test).log"
    # rostest --text exits 0 even when test cases fail: judge from its summary (and a non-empty run).
    clean="$(sed 's/\x1b\[[0-9;]*m//g' "$log")"
    grep -q '^ \* RESULT: SUCCESS' <<<"$clean" || { [ $rc -eq 0 ] && rc=1; }
    grep -qE '^ \* TESTS: [1-9]' <<<"$clean" || { [ $rc -eq 0 ] && rc=1; }
    secs=$(( $(date +%s) - start ))
    n_tests=$(grep -oE '^ \* TESTS: [0-9]+' <<<"$clean" | grep -oE '[0-9]+$' | tail -1); n_tests=${n_tests:-0}
    n_bad=$(grep -oE '^ \* (ERRORS|FAILURES): [0-9]+' <<<"$clean" | grep -oE '[0-9]+$' | awk '{s+=$1} END {print s+0}')
    n_bad=${n_bad:-0}
    if [ $rc -eq 0 ]; then passed=$((passed + n_tests)); echo "    ok: $n_tests test cases (${secs}s)"
    else passed=$((passed + (n_tests > n_bad ? n_tests - n_bad : 0))); failed=$((failed + (n_bad > 0 ? n_bad : 1)))
         failures+=("$name"); echo "    FAILED rc=$rc (${secs}s), log:"
         tail -60 "$RESULTS/${p}__$(basename "$t" .test).log" | sed 's/^/    | /'; fi
  done
done

echo
((${#failures[@]})) && printf 'failed: %s\n' "${failures[@]}"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
