#!/usr/bin/env bash
# Runs every test of the workspace, or of the packages named as arguments:
#   1. unit tests: pytest over catkin_ws/src/<pkg>/test/unit (no ROS master needed),
#   2. integration tests: every catkin_ws/src/<pkg>/test/*.test with rostest,
#   3. with mbzirc_robustness: the fault suite, short schedule (root; SKIP_FAULTS=1 skips it).
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
    # A .test file with several <test> nodes prints a summary per test: every one must succeed.
    grep -q '^ \* RESULT: SUCCESS' <<<"$clean" || { [ $rc -eq 0 ] && rc=1; }
    grep -q '^ \* RESULT: FAIL' <<<"$clean" && { [ $rc -eq 0 ] && rc=1; }
    grep -qE '^ \* TESTS: [1-9]' <<<"$clean" || { [ $rc -eq 0 ] && rc=1; }
    secs=$(( $(date +%s) - start ))
    n_tests=$(grep -oE '^ \* TESTS: [0-9]+' <<<"$clean" | grep -oE '[0-9]+$' | awk '{s+=$1} END {print s+0}')
    n_tests=${n_tests:-0}
    n_bad=$(grep -oE '^ \* (ERRORS|FAILURES): [0-9]+' <<<"$clean" | grep -oE '[0-9]+$' | awk '{s+=$1} END {print s+0}')
    n_bad=${n_bad:-0}
    [ "$n_bad" -gt 0 ] && { [ $rc -eq 0 ] && rc=1; }
    if [ $rc -eq 0 ]; then passed=$((passed + n_tests)); echo "    ok: $n_tests test cases (${secs}s)"
    else passed=$((passed + (n_tests > n_bad ? n_tests - n_bad : 0))); failed=$((failed + (n_bad > 0 ? n_bad : 1)))
         failures+=("$name"); echo "    FAILED rc=$rc (${secs}s), log:"
         tail -60 "$RESULTS/${p}__$(basename "$t" .test).log" | sed 's/^/    | /'; fi
  done
done

# ---- fault suite (issue 9) -----------------------------------------------------------------------
# The mission on network-namespace hosts (ground station + one per robot): a UAV's link cut for 60 s, another
# cut for good, kill -9 of a detector, an agent, the estimator and the central unit. Short schedule (ends
# once every fault is judged, ~3-4 min); `make test-faults` runs the long one. Needs root (ip netns).
# Each judged fault counts as a test case; SKIP_FAULTS=1 (or SKIP_ROSTEST=1) skips the step.
run_faults=0
if [ -z "${SKIP_ROSTEST:-}" ] && [ -z "${SKIP_FAULTS:-}" ]; then
  for p in "${PKGS[@]}"; do [ "$p" = mbzirc_robustness ] && run_faults=1; done
fi
if [ "$run_faults" -eq 1 ]; then
  echo "=== fault suite (short): rosrun mbzirc_robustness fault_suite --stop-when-done"
  flog="$RESULTS/fault_suite.log"; freport="$RESULTS/fault_suite_report.json"
  rm -f "$freport"
  start=$(date +%s)
  if [ "$(id -u)" -ne 0 ] || ! ip netns list >/dev/null 2>&1; then
    echo "needs root and ip netns (SKIP_FAULTS=1 skips it)" > "$flog"; rc=1
  else
    (cd "$RESULTS" && timeout -k 20 "${FAULTS_TIMEOUT:-900}" rosrun mbzirc_robustness fault_suite \
       --start 30 --spacing 15 --duration 900 --stop-when-done --out "$RESULTS/faults" \
       --fuzz-dir "$ROOT/results/robustness" --report "$freport") > "$flog" 2>&1
    rc=$?
  fi
  secs=$(( $(date +%s) - start ))
  read -r fp ff < <(python - "$freport" 2>/dev/null <<'PY' || echo "0 0"
import json, sys
r = json.load(open(sys.argv[1]))
print(int(r.get("checks_passed", 0)), int(r.get("checks_failed", 0)))
PY
)
  fp=${fp:-0}; ff=${ff:-0}
  [ "$rc" -ne 0 ] && [ "$ff" -eq 0 ] && ff=1      # crashed, timed out or no report: one failure
  passed=$((passed + fp)); failed=$((failed + ff))
  if [ "$rc" -eq 0 ] && [ "$ff" -eq 0 ]; then echo "    ok: $fp faults survived (${secs}s)"
  else failures+=("fault suite ($ff failed)"); echo "    FAILED rc=$rc (${secs}s), log $flog:"
       tail -40 "$flog" | sed 's/^/    | /'; fi
fi

echo
((${#failures[@]})) && printf 'failed: %s\n' "${failures[@]}"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
