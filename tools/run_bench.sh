#!/usr/bin/env bash
# Runs every benchmark bench/bench_*.py (each prints its figures and writes bench/results/<name>.json),
# then merges them into bench/results/latest.json (one object per benchmark). BENCH="a b" runs a subset.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
set +u; source "$ROOT/env.sh"; set -u
cd "$ROOT/bench"
mkdir -p results
status=0
for b in bench_*.py; do
  name="${b#bench_}"; name="${name%.py}"
  if [ -n "${BENCH:-}" ] && [[ " $BENCH " != *" $name "* ]]; then continue; fi
  echo "=== benchmark $name"
  python "$b" || { echo "benchmark $name FAILED"; status=1; }
done
python - <<'PY'
import glob, json, os, time
out = {"generated": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "machine": {"cores": os.cpu_count()}}
for f in sorted(glob.glob("results/*.json")):
    name = os.path.basename(f)[:-5]
    if name == "latest":
        continue
    with open(f) as fh:
        out[name] = json.load(fh)
with open("results/latest.json", "w") as fh:
    json.dump(out, fh, indent=2)
print("wrote bench/results/latest.json with", len(out) - 2, "benchmarks")
PY
exit $status
