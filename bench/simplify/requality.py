"""Judges the current lodkit build's quality again, in seconds, against the peers' outputs of the last
full simplify run (scripts/bench.sh simplify), without running the peers or timing anything.

  requality.py BENCH_DIR LODKIT_CLI DATA_DIR [--threads N]

For every corpus case the full run left a meshoptimizer or CGAL-GH output for
(DATA_DIR/out/STEM-TARGET-TOOL.ply), lodkit_bench_simplify simplifies the corpus mesh to the same
target with the default metric (as the full run does; outputs under DATA_DIR/out/requality/), and
`lodkit compare` measures every result against its input. The verdicts follow report.py: lodkit at
most the better of the peers that reached the target, lodkit short of the target counting against
it (verdict.py, shared with report.py). The peers' distances are kept in DATA_DIR/out/peer-distances.json,
keyed by the input's path, the output's file size and time and a digest of the measuring code
(src/measure), so only the first call after a full run or a change to the measure measures them.
Prints the share and worst ratio per target and quantity, the geometric mean of lodkit's value over
the best peer's (cases where both are above the tie level: a share moves by whole cases, the mean
shows smaller changes), and the cases lodkit loses; exits 1 when a tool fails.

Quick feedback while working on quality; the full run remains the reference (it also times and
measures memory)."""
import concurrent.futures
import hashlib
import json
import math
import os
import subprocess
import sys

from run import MIN_TRIANGLES
from verdict import QUALITY_PEERS, TIE, judge, stopped_short

CORPUS = "data/corpus"

bench_dir, cli, data_dir = sys.argv[1], sys.argv[2], sys.argv[3]
threads = sys.argv[sys.argv.index("--threads") + 1] if "--threads" in sys.argv else "0"
out_dir = os.path.join(data_dir, "out")
if not os.path.isdir(out_dir):
    sys.exit(f"requality: {out_dir} does not exist: run `scripts/bench.sh simplify` once first")
own_dir = os.path.join(out_dir, "requality")
os.makedirs(own_dir, exist_ok=True)


def run_json(command):
    """The JSON report a tool prints: all of stdout (`lodkit compare`) or its last line (bench programs)."""
    p = subprocess.run(command, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"requality: {' '.join(command)} failed: {p.stderr.strip()[:300]}")
    try:
        return json.loads(p.stdout)
    except json.JSONDecodeError:
        return json.loads([l for l in p.stdout.splitlines() if l.startswith("{")][-1])


# The full run names its outputs by stem, and two corpus meshes share some stems (pig.off and
# pig.stl): the mesh is the one the full run simplified, the one with at least MIN_TRIANGLES.
by_stem = {}
for f in sorted(os.listdir(CORPUS)):
    stem, _, ext = f.rpartition(".")
    if ext.lower() in ("off", "ply", "stl"):
        by_stem.setdefault(stem, []).append(os.path.join(CORPUS, f))
inputs = {}
for stem, paths in by_stem.items():
    if len(paths) > 1:
        paths = [path for path in paths if run_json([cli, "info", path, "--json"])["stats"]["triangles"] >= MIN_TRIANGLES]
        if len(paths) > 1:
            sys.exit(f"requality: {' and '.join(paths)} share a name: the full run's outputs do not say which")
    if paths:
        inputs[stem] = paths[0]

cases = set()
for f in os.listdir(out_dir):
    for peer in QUALITY_PEERS:
        if f.endswith(f"-{peer}.ply"):
            stem, _, target = f[: -len(f"-{peer}.ply")].rpartition("-")
            if stem in inputs and target.isdigit():
                cases.add((stem, int(target)))
cases = sorted(cases)
if not cases:
    sys.exit(f"requality: no peer outputs under {out_dir}: run `scripts/bench.sh simplify` once first")


def distance(input_path, output_path):
    j = run_json([cli, "compare", input_path, output_path, "--json"])
    return {"hausdorff": j["symmetric"]["relative_hausdorff"], "rms": j["symmetric"]["relative_rms"],
            "triangles": j["b_triangles"]}


# A fix to the measure changes the peers' distances too: its sources are part of every key.
measure_digest = hashlib.sha1()
for f in sorted(os.listdir("src/measure")):
    measure_digest.update(f.encode() + open(os.path.join("src/measure", f), "rb").read())
measure_digest = measure_digest.hexdigest()[:12]
cache_path = os.path.join(out_dir, "peer-distances.json")
cache = json.load(open(cache_path)) if os.path.exists(cache_path) else {}


def peer_distances(case):
    stem, target = case
    found = {}
    for peer in QUALITY_PEERS:
        path = os.path.join(out_dir, f"{stem}-{target}-{peer}.ply")
        if not os.path.exists(path):
            continue
        st = os.stat(path)
        key = f"{inputs[stem]}:{os.path.basename(path)}:{st.st_size}:{int(st.st_mtime)}:{measure_digest}"
        found[peer] = cache[key] if key in cache else distance(inputs[stem], path)
        found[peer]["key"] = key
    return found


def lodkit_distances(case):
    stem, target = case
    path = os.path.join(own_dir, f"{stem}-{target}-lodkit.ply")
    run_json([os.path.join(bench_dir, "lodkit_bench_simplify"), "cqem", inputs[stem], path, str(target), "1", "--json",
              "--threads", threads])
    return distance(inputs[stem], path)


with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
    peers = list(pool.map(peer_distances, cases))
    mine = list(pool.map(lodkit_distances, cases))
cache = {}  # only this run's keys: stale ones would pile up
for found in peers:
    for d in found.values():
        cache[d["key"]] = {k: v for k, v in d.items() if k != "key"}
with open(cache_path + ".tmp", "w") as f:
    json.dump(cache, f)
os.replace(cache_path + ".tmp", cache_path)

# The 10% and 1% targets of a mesh: the larger of its two is 10%.
targets = {}
for stem, target in cases:
    targets.setdefault(stem, []).append(target)
lines = []
for level, label in ((0, "10%"), (1, "1%")):
    for what in ("hausdorff", "rms"):
        judged = good = 0
        worst, losses, logs = (0.0, None), [], []
        for case, found, own in zip(cases, peers, mine):
            stem, target = case
            if sorted(targets[stem], reverse=True).index(target) != level:
                continue
            reached = [d[what] for d in found.values() if not stopped_short(d["triangles"], target)]
            verdict, ratio = judge(own[what], reached, stopped_short(own["triangles"], target))
            if verdict is None:
                continue
            judged += 1
            best = min(reached)
            if verdict != "short" and best > TIE and own[what] > TIE:
                logs.append(math.log(own[what] / best))
            if verdict == "ok":
                good += 1
            elif verdict == "short":
                losses.append(f"{stem} (lodkit short)")
            else:
                losses.append(f"{stem} {ratio:.2f}x")
                worst = max(worst, (ratio, stem))
        share = good / judged if judged else 0
        lines.append(f"{label:>3} {what:<9} lodkit <= best(GH, mo) on {good}/{judged} = {share:.0%}, worst "
                     f"{worst[0]:.2f}x {worst[1] or ''}; lodkit / best geometric mean "
                     f"{math.exp(sum(logs) / len(logs)) if logs else math.nan:.3f} over {len(logs)}")
        if losses:
            lines.append("      loses: " + ", ".join(losses))
print("\n".join(lines))
