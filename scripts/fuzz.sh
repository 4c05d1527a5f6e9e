#!/usr/bin/env bash
# Runs the libFuzzer harnesses (fuzz/fuzz_<format>.cpp) and prints one summary line per format.
#
#   scripts/fuzz.sh FORMAT|all [SECONDS=600] [JOBS=nproc]
#
# FORMAT is obj, mtl (OBJ material libraries), ply, off, stl, gltf, lpm (progressive meshes), meshopt (the meshopt vertex decoder,
# on a stride byte, two count bytes and a stream), simplify (the simplifier, on 16 option bytes
# followed by an OFF file) or compare (lod::compare's certified bound, on two small meshes: see
# fuzz/fuzz_compare.cpp). JOBS is how many fuzzer processes run at once: with `all`,
# that many formats at a time; with one format and JOBS > 1, libFuzzer's -fork=JOBS.
#
# Builds the fuzz preset when needed. Seeds (fuzz/seeds/<format>/) are copied into the working corpus
# fuzz/corpus-<format>/, which keeps growing from run to run; crashes, leaks, timeouts and OOMs land in
# fuzz/artifacts/<format>-*; the full libFuzzer output goes to build/fuzz/<format>.log. Both folders
# are git-ignored. Reproduce a crash with: build/fuzz/fuzz_<format> fuzz/artifacts/<format>-crash-...
#
# Extra libFuzzer flags go in LODKIT_FUZZ_ARGS, e.g. LODKIT_FUZZ_ARGS="-ignore_crashes=1" (with
# JOBS > 1) to keep fuzzing past a known crash, or "-only_ascii=1".
#
# Exit status: 0 when no fuzzer crashed, 1 when one did (a new artifact or a non-zero fuzzer exit),
# 2 for bad usage or a failed build.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

all_formats=(obj mtl ply off stl gltf lpm meshopt simplify compare)
usage() {
  echo "usage: scripts/fuzz.sh FORMAT|all [SECONDS=600] [JOBS=$(nproc)]   (FORMAT: ${all_formats[*]})" >&2
  exit 2
}
if [ $# -lt 1 ] || [ $# -gt 3 ]; then usage; fi
target=$1
seconds=${2:-600}
jobs=${3:-$(nproc)}
[[ $seconds =~ ^[1-9][0-9]*$ ]] || usage
[[ $jobs =~ ^[1-9][0-9]*$ ]] || usage
if [ "$target" = all ]; then
  formats=("${all_formats[@]}")
elif [[ " ${all_formats[*]} " == *" $target "* ]]; then
  formats=("$target")
else
  usage
fi

build=build/fuzz
mkdir -p build
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake --preset fuzz >build/fuzz-configure.log 2>&1 || { cat build/fuzz-configure.log >&2; exit 2; }
fi
cmake --build --preset fuzz >"$build/build.log" 2>&1 || { tail -n 60 "$build/build.log" >&2; exit 2; }

# Inputs libFuzzer may grow to: glTF needs room for base64 buffers, the rest stay small and fast.
max_len() { case $1 in gltf) echo 65536 ;; *) echo 16384 ;; esac; }

count_artifacts() {
  find fuzz/artifacts -maxdepth 1 -type f \( -name "$1-crash-*" -o -name "$1-leak-*" -o -name "$1-timeout-*" \
    -o -name "$1-oom-*" \) 2>/dev/null | wc -l
}

# Runs one fuzzer and writes "format executions exec/s corpus crashes status" to build/fuzz/<format>.summary.
run_one() {
  local format=$1 corpus=fuzz/corpus-$1 log=$build/$1.log
  mkdir -p "$corpus" fuzz/artifacts
  local seed
  for seed in fuzz/seeds/"$format"/*; do
    [ -e "$corpus/${seed##*/}" ] || cp "$seed" "$corpus/"
  done
  local before
  before=$(count_artifacts "$format")
  local args=("$corpus" "-dict=fuzz/dicts/$format.dict" "-max_total_time=$seconds" "-artifact_prefix=fuzz/artifacts/$format-"
              "-rss_limit_mb=2048" "-max_len=$(max_len "$format")" "-timeout=10" "-print_final_stats=1")
  if [ ${#formats[@]} -eq 1 ] && [ "$jobs" -gt 1 ]; then args+=("-fork=$jobs"); fi
  # shellcheck disable=SC2206  # split on purpose: several flags in one variable
  args+=(${LODKIT_FUZZ_ARGS:-})
  local status=0
  "$build/fuzz_$format" "${args[@]}" >"$log" 2>&1 || status=$?
  # -print_final_stats gives the totals; fork mode and crashes may not, so fall back to the last status line.
  local executions rate
  executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  [ -n "$executions" ] || executions=$(grep -oE '^#[0-9]+' "$log" | tail -n 1 | tr -d '#' || true)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
  [ -n "$rate" ] || rate=$(grep -oE 'exec/s:? [0-9]+' "$log" | tail -n 1 | grep -oE '[0-9]+$' || true)
  local corpus_size crashes
  corpus_size=$(find "$corpus" -maxdepth 1 -type f | wc -l)
  crashes=$(($(count_artifacts "$format") - before))
  echo "$format ${executions:-?} ${rate:-?} $corpus_size $crashes $status" >"$build/$format.summary"
}

if [ ${#formats[@]} -gt 1 ]; then parallel="$jobs formats at a time"; else parallel="$jobs fuzzer process(es)"; fi
echo "fuzz: ${formats[*]} for ${seconds}s each, $parallel; logs in $build/<format>.log" >&2
for format in "${formats[@]}"; do
  rm -f "$build/$format.summary"
  if [ ${#formats[@]} -gt 1 ]; then
    while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
    run_one "$format" &
  else
    run_one "$format"
  fi
done
wait

failed=0
printf '%-6s %14s %8s %8s %8s %7s\n' format executions exec/s corpus crashes status
for format in "${formats[@]}"; do
  if [ ! -f "$build/$format.summary" ]; then
    printf '%-6s %14s %8s %8s %8s %7s\n' "$format" '?' '?' '?' '?' 'lost'
    failed=1
    continue
  fi
  read -r name executions rate corpus_size crashes status <"$build/$format.summary"
  printf '%-6s %14s %8s %8s %8s %7s\n' "$name" "$executions" "$rate" "$corpus_size" "$crashes" "$status"
  if [ "$crashes" -ne 0 ] || [ "$status" -ne 0 ]; then failed=1; fi
done

# For each failure: what happened, and where the reproducer is.
for format in "${formats[@]}"; do
  [ -f "$build/$format.summary" ] || continue
  read -r _ _ _ _ crashes status <"$build/$format.summary"
  if [ "$crashes" -eq 0 ] && [ "$status" -eq 0 ]; then continue; fi
  echo >&2
  echo "$format: $build/$format.log" >&2
  grep -E '^==== lodkit fuzz oracle|^SUMMARY: |^==[0-9]+==ERROR|runtime error:' "$build/$format.log" | head -n 4 | sed 's/^/  /' >&2 || true
  sed -n 's/^artifact_prefix=.*; Test unit written to \(.*\)$/  reproduce: '"${build//\//\\/}"'\/fuzz_'"$format"' \1/p' "$build/$format.log" | head -n 3 >&2
done
exit "$failed"
