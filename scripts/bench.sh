#!/usr/bin/env bash
# Peer benchmarks. Heavy, so not part of CI; one command away:
#
#   scripts/bench.sh io [RUNS=5]
#
# io: loads a binary PLY and an OBJ of >= 3M triangles (bunny00.off subdivided 1->4) with lodkit and
# with Assimp, each loader in its own process under /usr/bin/time -v; prints a markdown table of
# median load times, their ratio and peak memory, and writes bench/results/io.json.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

usage() { echo "usage: scripts/bench.sh io [RUNS=5]" >&2; exit 2; }
[ $# -ge 1 ] && [ $# -le 2 ] && [ "$1" = io ] || usage
runs=${2:-5}
[[ $runs =~ ^[1-9][0-9]*$ ]] || usage

[ -f build/release/build.ninja ] || cmake --preset release >/dev/null
bench=build/release/bench/lodkit_bench_io
grep -q '^build bench/lodkit_bench_io:' build/release/build.ninja ||
  { echo "bench: no lodkit_bench_io target (is libassimp-dev installed? run scripts/setup.sh)" >&2; exit 1; }
# Only the bench and what it links: a broken test elsewhere should not stop a benchmark run.
log=$(mktemp)
cmake --build --preset release --target lodkit_bench_io >"$log" 2>&1 || { cat "$log" >&2; rm -f "$log"; exit 1; }
rm -f "$log"
[ -f data/corpus/bunny00.off ] || scripts/fetch-corpus.sh
data=build/bench-data
# A failed writer costs its own file only; its row below is then marked failed.
"$bench" make-inputs data/corpus/bunny00.off "$data" || echo "bench: make-inputs failed for some input (see above)" >&2

echo
machine="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
echo "machine: $machine, $(date -u +%Y-%m-%dT%H:%MZ), load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo "runs per loader: $runs timed (after one untimed warm-up load), median reported"
echo

mkdir -p bench/results
results=()
# One process per (loader, file): returns the JSON line with peak_mib added, or nothing on failure.
measure() {
  local loader=$1 file=$2 log json peak
  log=$(mktemp)
  if json=$(/usr/bin/time -v "$bench" load "$loader" "$file" "$runs" --json 2>"$log"); then
    peak=$(awk -F: '/Maximum resident set size/ {gsub(/ /, "", $2); print $2}' "$log")
    rm -f "$log"
    python3 -c 'import json,sys; d=json.loads(sys.argv[1]); d["peak_mib"]=round(int(sys.argv[2])/1024,1); print(json.dumps(d))' "$json" "$peak"
  else
    echo "bench: $loader failed on $file: $(grep -v '^\s' "$log" | head -n 3)" >&2
    rm -f "$log"
  fi
}
files=("$data/big.ply" "$data/big.obj")
for file in "${files[@]}"; do
  for loader in lodkit assimp; do
    line=$(measure "$loader" "$file")
    [ -n "$line" ] && results+=("$line")
  done
done

# Exits non-zero when a ratio is missing (a failed row) or the loaders disagree on triangles.
printf '%s\n' "${results[@]}" | python3 bench/io/report.py bench/results/io.json "$machine" "$runs" "${files[@]}"
