#!/usr/bin/env bash
# Peer benchmarks. Heavy, so not part of CI; one command away:
#
#   scripts/bench.sh io [RUNS=5]
#   scripts/bench.sh simplify [--quick] [RUNS=3]
#   scripts/bench.sh simplify --requality
#   scripts/bench.sh simplify --pathological [RUNS=3]
#   scripts/bench.sh measure [PAIRS=20]
#   scripts/bench.sh errors [RUNS=3]
#   scripts/bench.sh lod [RUNS=15]
#   scripts/bench.sh optimize [--quick] [--no-big] [RUNS=5]
#   scripts/bench.sh render [RUNS=5]
#   scripts/bench.sh compress [RUNS=5]
#   scripts/bench.sh instanced [RUNS=3]
#   scripts/bench.sh turntable [RUNS=3]
#   scripts/bench.sh parts [RUNS=3]
#   scripts/bench.sh crowd [RUNS=3]
#
# io: loads a binary PLY and an OBJ of >= 3M triangles (bunny00.off subdivided 1->4) with lodkit and
# with Assimp, each loader in its own process under /usr/bin/time -v; prints a markdown table of
# median load times, their ratio and peak memory, and writes bench/results/io.json.
#
# simplify: every corpus mesh of >= 2000 triangles at 10% and 1%, plus armadillo subdivided to 832k and
# 3.3M triangles, through lodkit (all threads and one), meshoptimizer, CGAL (Garland-Heckbert and
# Lindstrom-Turk) and OpenMesh, each in its own process; distances of every result to its input;
# lodkit's five metrics side by side. Prints the tables and the issue 3 targets, writes
# bench/results/simplify.json and the rate-distortion plot bench/results/simplify-rd.{png,svg}.
# --quick: two small meshes, one run each (a smoke test of the whole chain).
# --requality: only lodkit's quality again (current build, corpus cases), judged against the peers'
# outputs the last full run left; seconds instead of minutes (bench/simplify/requality.py).
# --pathological: `lodkit simplify` to 10% on triangle fans of 2,000 to 100,000 triangles around one
# position, where per-edge work that walks a whole star is quadratic: median time and peak memory
# (bench/simplify/pathological.py).
#
# errors: levels by error, `lodkit lod --errors 0,E` against meshopt_simplify's target_error E on corpus
# meshes at E = 0.2% and 1% of the diagonal: whether each stays within E as measured (certified
# bounds), triangles and times, and lodkit's triangles at meshoptimizer's measured distance
# (bench/lod/errors.py); writes bench/results/errors.json.
#
# measure: `lodkit compare` against CGAL's distance (cgal_distance) on PAIRS (mesh, simplified) pairs:
# values and time at the same sample count; writes bench/results/measure.json.
#
# lod: geomorph throughput (lod::morph_positions on >= 1M vertices) against memcpy of the same bytes
# in the same process (target: morph <= 3x memcpy), with its peak memory; popping along a camera
# flight past 3 corpus models, geomorphs against hard switches (target: <= 1 px per frame); the
# runtime's selection cost for 10,000 objects; the chain's levels against gltfpack's (npm) at the same
# ratios: error and file size.
#
# skin: skinned simplification on the test characters (tests/skin/fixtures: the procedural humanoid
# and man.off rigged by hand): houle, subset and multipose at 25%, 10% and 3%, Hausdorff and RMS over
# every frame of every clip at 30 fps (mean and max over frames), simplification time; the skeletal
# geomorph's per-frame cost against plain skinning (target <= 1.5x; multipose <= 0.8x the better
# single-pose method's max-over-frames Hausdorff at 10% and 3%, never worse at 25%).
#
# render: a 1024x768 picture (4x MSAA) of bunny00.off subdivided to 1.2M triangles on this machine's
# OpenGL (Mesa llvmpipe without a GPU): lodkit_bench_render times upload, draw + readback and PNG
# encoding in one process over RUNS runs, and `lodkit render` runs end to end (load, context, upload,
# draw, write) RUNS times, each under /usr/bin/time -v; prints the medians and peak memory (target:
# under 5 s) and writes bench/results/render.json.
#
# compress: glTF output with -c (EXT_meshopt_compression) and -c -q (KHR_mesh_quantization) against
# gltfpack 0.18 on the same optimized files (-noq, -c -noq and its quantized -c), and --draco against
# draco_transcoder at the same bit depths: sizes raw and gzipped, and lodkit's
# load time and peak memory, plain against compressed (bench/compress/run.py); writes
# bench/results/compress.json.
#
# instanced: lodkit lod on a forest of 100 tori drawn as GPU instances (EXT_mesh_gpu_instancing: one
# chain in the torus's space) against the same forest as 100 plain nodes (one world-space chain):
# median time, peak RSS, output size, level triangles, and level 0 against the input
# (bench/lod/instanced.py); writes bench/results/instanced.json.
#
# turntable: lodkit lod on six corpus meshes in a ring below one animated node (a rigid group: one
# chain in the node's space) against each mesh's own static chain: per level, the group's triangles
# and measured error against the per-mesh chains' summed triangles and largest error; median time
# and peak RSS; output sizes plain and with -c -q (bench/lod/turntable.py); writes
# bench/results/turntable.json.
#
# parts: lodkit lod on 200 small meshes (288 triangles each), each drawn by its own animated node (one
# chain per mesh, the small chains built side by side one thread each), with --threads 1 and --threads 0
# (all cores): median wall time and build_seconds, peak RSS, output size, the one-thread / all-threads
# ratio; both settings must write byte-identical files and the report must list 200 "animated" chains;
# then lodkit simplify --ratio 0.1 on the same scene the same way (lod::simplify_batch: each mesh on its
# own, side by side) (bench/lod/parts.py); writes bench/results/parts.json.
#
# crowd: lodkit lod --poses 8 on the humanoid (lodkit_fixtures) drawn by 1, 2, 4, 8, 16 and 32 copies of
# its skeleton playing its clips in step: median wall time and peak RSS, each as a ratio to the crowd
# of one, whose chain every crowd's must be (bench/lod/crowd.py); writes bench/results/crowd.json.
#
# The build is the release preset (build/release); LODKIT_BENCH_BUILD=DIR uses another configured
# build directory instead.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

usage() {
  echo "usage: scripts/bench.sh io [RUNS=5] | simplify [--quick] [RUNS=3] | simplify --requality | simplify --pathological [RUNS=3] | measure [PAIRS=20] | errors [RUNS=3] | lod [RUNS=15] | skin [RUNS=3] | optimize [--quick] [--no-big] [RUNS=5] | render [RUNS=5] | compress [RUNS=5] | morphs [RUNS=3] | instanced [RUNS=3] | turntable [RUNS=3] | parts [RUNS=3] | crowd [RUNS=3]" >&2
  exit 2
}
[ $# -ge 1 ] || usage
area=$1
shift

build=${LODKIT_BENCH_BUILD:-build/release}
configure() {
  if [ -z "${LODKIT_BENCH_BUILD:-}" ]; then
    [ -f build/release/build.ninja ] || cmake --preset release >/dev/null
  else
    [ -f "$build/build.ninja" ] || { echo "bench: $build is not a configured build directory" >&2; exit 1; }
  fi
  # Regenerate when a CMakeLists.txt changed, so the target checks below see the current targets.
  cmake --build "$build" --target build.ninja >/dev/null 2>&1 || cmake "$build" >/dev/null
}
# Builds only the named targets and what they link: a broken test elsewhere should not stop a
# benchmark run. Targets missing from the build (a peer's package is not installed) are skipped.
build_targets() {
  local available=() t log
  for t in "$@"; do
    if grep -q "^build bench/$t:\|^build $t:" "$build/build.ninja"; then available+=("$t"); fi
  done
  [ ${#available[@]} -gt 0 ] || return 0
  log=$(mktemp)
  cmake --build "$build" --target "${available[@]}" >"$log" 2>&1 || { cat "$log" >&2; rm -f "$log"; exit 1; }
  rm -f "$log"
}
# Runs a command under /usr/bin/time -v (its stderr goes with time's report), then prints its peak
# memory; returns the command's status.
with_peak_memory() {
  local log status=0
  log=$(mktemp)
  /usr/bin/time -v "$@" 2>"$log" || status=$?
  echo "peak memory: $(awk -F: '/Maximum resident set size/ {gsub(/ /, "", $2); printf "%.1f MiB", $2 / 1024}' "$log")"
  rm -f "$log"
  return $status
}
# An area's optional count (RUNS or PAIRS): the value given, or DEFAULT; anything else is a usage
# error. Called as `runs=$(count_arg DEFAULT "$@") || exit 2`.
count_arg() {
  local fallback=$1
  shift
  [ $# -le 1 ] || usage
  local n=${1:-$fallback}
  [[ $n =~ ^[1-9][0-9]*$ ]] || usage
  echo "$n"
}
machine_line() {
  machine="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
  echo "machine: $machine, $(date -u +%Y-%m-%dT%H:%MZ), load average $(cut -d' ' -f1-3 /proc/loadavg)"
}

# Before an area's output: the corpus (fetched if missing) and the machine line.
start_run() {
  [ -f data/corpus/bunny00.off ] || scripts/fetch-corpus.sh
  echo
  machine_line
  echo
}

# ---- io ------------------------------------------------------------------------------------------
area_io() {
  local runs
  runs=$(count_arg 5 "$@") || exit 2
  configure
  local bench=$build/bench/lodkit_bench_io
  grep -q '^build bench/lodkit_bench_io:' "$build/build.ninja" ||
    { echo "bench: no lodkit_bench_io target (is libassimp-dev installed? run scripts/setup.sh)" >&2; exit 1; }
  build_targets lodkit_bench_io
  [ -f data/corpus/bunny00.off ] || scripts/fetch-corpus.sh
  local data=build/bench-data
  # A failed writer costs its own file only; its row below is then marked failed.
  "$bench" make-inputs data/corpus/bunny00.off "$data" || echo "bench: make-inputs failed for some input (see above)" >&2

  echo
  machine_line
  echo "runs per loader: $runs timed (after one untimed warm-up load), median reported"
  echo

  mkdir -p bench/results
  local results=() files=("$data/big.ply" "$data/big.obj") file loader line
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
  for file in "${files[@]}"; do
    for loader in lodkit assimp; do
      line=$(measure "$loader" "$file")
      [ -n "$line" ] && results+=("$line")
    done
  done

  # Exits non-zero when a ratio is missing (a failed row) or the loaders disagree on triangles.
  printf '%s\n' "${results[@]}" | python3 bench/io/report.py bench/results/io.json "$machine" "$runs" "${files[@]}"
}

# ---- simplify ------------------------------------------------------------------------------------
area_simplify() {
  local quick="" runs="" requality="" pathological=""
  for a in "$@"; do
    case $a in
      --quick) quick=--quick ;;
      --requality) requality=1 ;;
      --pathological) pathological=1 ;;
      *) [[ $a =~ ^[1-9][0-9]*$ ]] && [ -z "$runs" ] || usage; runs=$a ;;
    esac
  done
  [ -n "$runs" ] || { [ -n "$quick" ] && runs=1 || runs=3; }
  local started=$SECONDS
  configure
  if [ -n "$requality" ]; then
    build_targets lodkit_cli lodkit_bench_simplify
    python3 bench/simplify/requality.py "$build/bench" "$build/lodkit" build/bench-data/simplify
    return
  fi
  if [ -n "$pathological" ]; then
    build_targets lodkit_cli
    python3 bench/simplify/pathological.py "$build/lodkit" build/bench-data/pathological "$runs"
    return
  fi
  # CGAL compiles slowly: the peers are built here, by name, never by a plain build.
  build_targets lodkit_cli lodkit_bench_simplify peer_meshopt peer_cgal peer_openmesh cgal_distance
  [ -x "$build/bench/lodkit_bench_simplify" ] || { echo "bench: lodkit_bench_simplify was not built" >&2; exit 1; }
  [ -f data/corpus/bunny00.off ] || scripts/fetch-corpus.sh
  echo "bench: built in $((SECONDS - started)) s" >&2

  echo
  machine_line
  echo "runs per tool: $runs timed (the input structure is rebuilt untimed before each), median reported${quick:+; quick mode}"
  echo

  mkdir -p bench/results
  python3 bench/simplify/run.py "$build/bench" "$build/lodkit" build/bench-data/simplify bench/results/simplify.jsonl \
    --runs "$runs" $quick
  python3 bench/simplify/report.py bench/results/simplify.jsonl bench/results/simplify.json "$machine" "$runs"
  echo
  echo "whole run: $((SECONDS - started)) s"
}

# ---- measure -------------------------------------------------------------------------------------
area_measure() {
  local pairs
  pairs=$(count_arg 20 "$@") || exit 2
  configure
  build_targets lodkit_cli lodkit_bench_simplify lodkit_bench_compare lodkit_bench_brute_force cgal_distance
  [ -x "$build/bench/cgal_distance" ] || { echo "bench: cgal_distance was not built (libcgal-dev missing?)" >&2; exit 1; }
  "$build/lodkit" compare --help >/dev/null 2>&1 || { echo "bench: this lodkit has no 'compare' subcommand yet" >&2; exit 1; }
  start_run
  mkdir -p bench/results
  python3 bench/simplify/measure.py "$build/bench" "$build/lodkit" build/bench-data/measure bench/results/measure.json "$pairs" "$machine"
}

# ---- errors --------------------------------------------------------------------------------------
area_errors() {
  local runs
  runs=$(count_arg 3 "$@") || exit 2
  configure
  build_targets lodkit_cli peer_meshopt lodkit_bench_compare
  [ -x "$build/bench/peer_meshopt" ] || { echo "bench: peer_meshopt was not built (libmeshoptimizer-dev missing?)" >&2; exit 1; }
  start_run
  mkdir -p bench/results
  python3 bench/lod/errors.py "$build/bench" "$build/lodkit" build/bench-data/errors bench/results/errors.json "$runs" "$machine"
}

# ---- lod -----------------------------------------------------------------------------------------
area_lod() {
  local runs
  runs=$(count_arg 15 "$@") || exit 2
  configure
  build_targets lodkit_bench_morph lodkit_bench_popping lodkit_bench_selection
  start_run
  local status=0
  echo "## geomorph throughput"
  with_peak_memory "$build/bench/lodkit_bench_morph" data/corpus/bunny00.off "$runs"
  echo
  echo "## popping: hard switches against geomorphs"
  "$build/bench/lodkit_bench_popping" data/corpus/bunny00.off data/corpus/fandisk.off data/corpus/armadillo.off || status=1
  if command -v npx >/dev/null; then
    echo
    echo "## the chain against gltfpack 1.3.0 (npm, -si R -noq)"
    build_targets lodkit_cli
    python3 bench/lod/gltfpack.py "$build/lodkit" data/corpus/bunny00.off data/corpus/fandisk.off data/corpus/armadillo.off \
      --out build/bench-data/gltfpack || status=1
  fi
  if [ -x "$build/bench/lodkit_bench_selection" ]; then
    echo
    echo "## selection: LodRuntime::update for 10,000 objects"
    "$build/bench/lodkit_bench_selection" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
  fi
  return $status
}

# ---- optimize ------------------------------------------------------------------------------------
area_optimize() {
  local flags=() runs=""
  for a in "$@"; do
    case $a in
      --quick | --no-big) flags+=("$a") ;;
      *) [[ $a =~ ^[1-9][0-9]*$ ]] && [ -z "$runs" ] || usage; runs=$a ;;
    esac
  done
  local started=$SECONDS
  configure
  build_targets lodkit_cli lodkit_bench_optimize
  [ -x "$build/bench/lodkit_bench_optimize" ] ||
    { echo "bench: lodkit_bench_optimize was not built (is libmeshoptimizer-dev installed?)" >&2; exit 1; }
  start_run
  mkdir -p bench/results
  python3 bench/optimize/run.py "$build/bench" "$build/lodkit" bench/results/optimize.jsonl ${runs:+--runs "$runs"} "${flags[@]}"
  python3 bench/optimize/report.py bench/results/optimize.jsonl bench/results/optimize.json "$machine" "${runs:-5}"
  echo
  echo "whole run: $((SECONDS - started)) s"
}

# ---- compress ------------------------------------------------------------------------------------
area_compress() {
  local runs started=$SECONDS
  runs=$(count_arg 5 "$@") || exit 2
  command -v gltfpack >/dev/null || { echo "bench: gltfpack is not installed (scripts/setup.sh installs it)" >&2; exit 1; }
  command -v draco_transcoder >/dev/null || { echo "bench: draco_transcoder is not installed (scripts/setup.sh installs it)" >&2; exit 1; }
  configure
  build_targets lodkit_cli lodkit_fixtures lodkit_bench_anim_error lodkit_bench_normal_error
  start_run
  mkdir -p bench/results
  python3 bench/compress/run.py "$build/lodkit" "$build/lodkit_fixtures" bench/results/compress.json --runs "$runs" \
    --anim-error "$build/bench/lodkit_bench_anim_error" --normal-error "$build/bench/lodkit_bench_normal_error"
  echo
  echo "whole run: $((SECONDS - started)) s"
}

# ---- instanced, turntable and parts: lod on a scene a Python script writes -----------------------
# instanced: a forest, GPU instances against plain nodes (bench/lod/instanced.py); turntable: meshes
# below one animated node, one group chain against one per mesh (bench/lod/turntable.py, corpus meshes);
# parts: many small animated meshes, one chain each (and simplified each), one thread against all (bench/lod/parts.py);
# crowd: one skinned mesh drawn by 1 to 32 skeletons in step, against the crowd of one (bench/lod/crowd.py).
area_lod_scene() {
  local name=$1
  shift
  local runs started=$SECONDS
  runs=$(count_arg 3 "$@") || exit 2
  configure
  build_targets lodkit_cli
  [ "$name" != crowd ] || build_targets lodkit_fixtures
  [ "$name" != turntable ] || [ -f data/corpus/bunny00.off ] || scripts/fetch-corpus.sh
  echo
  machine_line
  echo
  mkdir -p bench/results
  python3 "bench/lod/$name.py" "$build/lodkit" "bench/results/$name.json" --runs "$runs"
  echo
  echo "whole run: $((SECONDS - started)) s"
}

# ---- morphs: a blend shape carried through simplify (lod::vertex_blends), plain and through the forms
area_morphs() {
  local runs
  runs=$(count_arg 3 "$@") || exit 2
  configure
  build_targets lodkit_bench_morph_transfer
  start_run
  local meshes=()
  for m in bunny00 armadillo elk cow knot hand fandisk camel; do meshes+=("data/corpus/$m.off"); done
  with_peak_memory "$build/bench/lodkit_bench_morph_transfer" "$runs" "${meshes[@]}"
}

# ---- skin ----------------------------------------------------------------------------------------
area_skin() {
  local runs
  runs=$(count_arg 3 "$@") || exit 2
  configure
  build_targets lodkit_bench_skin
  [ -f data/corpus/man.off ] || scripts/fetch-corpus.sh
  echo
  machine_line
  echo
  local status=0
  with_peak_memory "$build/bench/lodkit_bench_skin" data/corpus/man.off "$runs" || status=1
  return $status
}

# ---- render --------------------------------------------------------------------------------------
area_render() {
  local runs
  runs=$(count_arg 5 "$@") || exit 2
  configure
  build_targets lodkit_cli lodkit_bench_render
  [ -x "$build/bench/lodkit_bench_render" ] || { echo "bench: lodkit_bench_render was not built" >&2; exit 1; }
  [ -f data/corpus/bunny00.off ] || scripts/fetch-corpus.sh
  local input=build/bench-data/render/bunny-1m.ply out=build/bench-data/render
  "$build/bench/lodkit_bench_render" make-input data/corpus/bunny00.off "$input"
  echo
  machine_line
  echo
  mkdir -p bench/results
  local log inproc inproc_peak cli=() cli_peaks=() k json
  log=$(mktemp)
  # In one process: upload, draw + readback, PNG, RUNS times after the load and context creation.
  inproc=$(/usr/bin/time -v "$build/bench/lodkit_bench_render" run "$input" "$runs" 1024x768 --json 2>"$log") ||
    { cat "$log" >&2; rm -f "$log"; exit 1; }
  inproc_peak=$(awk -F: '/Maximum resident set size/ {gsub(/ /, "", $2); print $2}' "$log")
  # End to end: the CLI as a user runs it, one process per run.
  for ((k = 0; k < runs; k++)); do
    json=$(/usr/bin/time -v "$build/lodkit" render "$input" -o "$out/bunny-1m.png" --size 1024x768 --json 2>"$log") ||
      { cat "$log" >&2; rm -f "$log"; exit 1; }
    cli+=("$json")
    cli_peaks+=("$(awk -F: '/Maximum resident set size/ {gsub(/ /, "", $2); print $2}' "$log")")
  done
  rm -f "$log"
  python3 - "$machine" "$inproc" "$inproc_peak" "${cli_peaks[*]}" "${cli[@]}" <<'EOF'
import json, statistics, sys
machine, inproc, inproc_peak, peaks = sys.argv[1], json.loads(sys.argv[2]), int(sys.argv[3]), sys.argv[4].split()
cli = [json.loads(j) for j in sys.argv[5:]]
med = lambda key: statistics.median(c[key] for c in cli)
mib = lambda kib: round(int(kib) / 1024, 1)
print(f"input: {inproc['input']}, {inproc['triangles']:,} triangles, {inproc['vertices']:,} vertices; "
      f"{inproc['width']}x{inproc['height']}, {inproc['samples']}x MSAA on {inproc['renderer']}")
print()
print("| step | median (s) | runs |")
print("|---|---:|---:|")
rows = [("in process: upload (normals computed)", inproc["median_upload_seconds"], inproc["runs"]),
        ("in process: draw + resolve + readback", inproc["median_draw_seconds"], inproc["runs"]),
        ("in process: PNG encode", inproc["median_encode_seconds"], inproc["runs"]),
        ("in process: upload + draw + PNG", inproc["median_render_seconds"], inproc["runs"]),
        ("CLI: load PLY", med("load_seconds"), len(cli)),
        ("CLI: context", med("context_seconds"), len(cli)),
        ("CLI: upload", med("upload_seconds"), len(cli)),
        ("CLI: draw + readback", med("render_seconds"), len(cli)),
        ("CLI: write PNG", med("write_seconds"), len(cli)),
        ("**CLI: lodkit render end to end**", med("total_seconds"), len(cli))]
for name, seconds, n in rows:
    print(f"| {name} | {seconds:.3f} | {n} |")
print()
total = med("total_seconds")
print(f"peak memory: CLI {statistics.median(mib(p) for p in peaks)} MiB (median over runs), in-process bench {mib(inproc_peak)} MiB")
print(f"target: end to end under 5 s: {'PASS' if total < 5 else 'FAIL'} ({total:.2f} s)")
json.dump({"machine": machine, "in_process": inproc, "in_process_peak_mib": mib(inproc_peak), "cli": cli,
           "cli_peak_mib": [mib(p) for p in peaks], "median_total_seconds": total, "pass": total < 5},
          open("bench/results/render.json", "w"), indent=2)
sys.exit(0 if total < 5 else 1)
EOF
}

case $area in
  io) area_io "$@" ;;
  skin) area_skin "$@" ;;
  optimize) area_optimize "$@" ;;
  lod) area_lod "$@" ;;
  simplify) area_simplify "$@" ;;
  measure) area_measure "$@" ;;
  errors) area_errors "$@" ;;
  render) area_render "$@" ;;
  compress) area_compress "$@" ;;
  morphs) area_morphs "$@" ;;
  instanced) area_lod_scene instanced "$@" ;;
  turntable) area_lod_scene turntable "$@" ;;
  parts) area_lod_scene parts "$@" ;;
  crowd) area_lod_scene crowd "$@" ;;
  *) usage ;;
esac
