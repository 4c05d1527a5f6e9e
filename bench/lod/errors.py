"""Levels by error: lodkit lod --errors against meshoptimizer's error limit (target_error), on corpus
meshes, each asked for a Hausdorff distance E (a fraction of the bounding-box diagonal).

  errors.py BENCH_DIR LODKIT_CLI WORK_DIR OUT.json RUNS MACHINE

Per mesh and limit E:
- lodkit: `lodkit lod IN --errors 0,E --json` (level 1 from the input); its triangles, its certified
  bound (the table's bound column) and the build's wall time (search and certification included),
  median of RUNS processes;
- meshoptimizer: peer_meshopt IN OUT 0 RUNS --error E (meshopt_simplify with target_error = E x
  diagonal / meshopt_simplifyScale, no triangle target); its triangles and the call's median time,
  then its output measured by lod::compare with certified refinement (lodkit_bench_compare --refine),
  the same measurement lodkit's levels get;
- the same distance: lodkit asked for meshoptimizer's measured bound (`--errors 0,B`), so that both
  results are within the same certified distance: the triangles each needs there.
Writes OUT.json with every case and prints Markdown tables and a summary: the share of cases within
their limit for each tool, and the geometric mean of lodkit's triangles over meshoptimizer's at the
same distance (below 1: lodkit needs fewer)."""
import json
import math
import os
import statistics
import subprocess
import sys

from common import run_lod

# The measure bench's meshes (bench/simplify/measure.py).
MESHES = ("bunny00.off", "armadillo.off", "refined_elephant.off", "fandisk_large.off", "man.off", "bear.off",
          "camel.off", "turbine.off", "cheese.off", "lion-head.off", "blade.off", "bull.off", "homer.off",
          "femur.off", "dino.off")
LIMITS = (0.002, 0.01)

bench_dir, lodkit_cli, work_dir, out_path, runs, machine = sys.argv[1:7]
runs = int(runs)
os.makedirs(work_dir, exist_ok=True)


def run_json(command):
    p = subprocess.run(command, capture_output=True, text=True, timeout=1800)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(command[:3])}: {(p.stderr.strip().splitlines() or ['failed'])[0]}")
    return json.loads(p.stdout)


def lodkit_level(mesh, limit, repeat):
    """Level 1 of `lod --errors 0,limit`: (triangles, bound relative to the diagonal, median seconds)."""
    out = os.path.join(work_dir, "lodkit.glb")
    seconds, report = [], None
    for _ in range(repeat):
        wall, _, report = run_lod(lodkit_cli, mesh, out, ["--errors", f"0,{limit!r}"])
        seconds.append(wall)
    level = report["levels"][1]
    return level["triangles"], level["error_bound"] / report["diagonal"], statistics.median(seconds)


cases = []
print(f"machine: {machine}; lodkit `lod --errors 0,E` against meshopt_simplify with target_error E (both as a fraction "
      f"of the diagonal); bounds certified by lod::compare's refinement; times: medians of {runs}\n")
print("| mesh | E | lodkit triangles | lodkit bound | within | lodkit s | meshopt triangles | meshopt bound | within | "
      "meshopt s | lodkit triangles at meshopt's bound | ratio |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for name in MESHES:
    mesh = os.path.join("data/corpus", name)
    if not os.path.exists(mesh):
        continue
    for limit in LIMITS:
        try:
            l_tris, l_bound, l_seconds = lodkit_level(mesh, limit, runs)
            m_out = os.path.join(work_dir, "meshopt.ply")
            m = run_json([os.path.join(bench_dir, "peer_meshopt"), mesh, m_out, "0", str(runs), "--json", "--error",
                          repr(limit)])
            d = run_json([os.path.join(bench_dir, "lodkit_bench_compare"), mesh, m_out, "--refine", "--json"])
            m_bound = d["hausdorff_bound_relative"]
            # lodkit held to the distance meshoptimizer reached (at least its own limit).
            same_tris, same_bound, _ = lodkit_level(mesh, max(m_bound, limit), 1)
        except (RuntimeError, subprocess.TimeoutExpired) as e:
            print(f"| {name} | {limit} | failed: {e} |" + " |" * 9)
            cases.append({"mesh": name, "limit": limit, "failed": str(e)})
            continue
        case = {"mesh": name, "limit": limit,
                "lodkit": {"triangles": l_tris, "bound_relative": l_bound, "seconds": l_seconds, "within": l_bound <= limit},
                "meshopt": {"triangles": m["triangles_out"], "bound_relative": m_bound,
                            "hausdorff_relative": d["hausdorff_relative"], "seconds": m["median_s"],
                            "result_error": m.get("result_error_relative"), "within": m_bound <= limit},
                "same_distance": {"limit": max(m_bound, limit), "lodkit_triangles": same_tris,
                                  "lodkit_bound_relative": same_bound,
                                  "ratio": same_tris / max(1, m["triangles_out"])}}
        cases.append(case)
        yes = lambda b: "yes" if b else "**no**"
        print(f"| {name} | {limit:.1%} | {l_tris} | {l_bound:.3%} | {yes(case['lodkit']['within'])} | {l_seconds:.2f} | "
              f"{m['triangles_out']} | {m_bound:.3%} | {yes(case['meshopt']['within'])} | {m['median_s']:.4f} | "
              f"{same_tris} ({same_bound:.3%}) | {case['same_distance']['ratio']:.3f} |", flush=True)

done = [c for c in cases if "failed" not in c]
summary = {}
for limit in LIMITS:
    at = [c for c in done if c["limit"] == limit]
    if not at:
        continue
    summary[str(limit)] = {
        "cases": len(at),
        "lodkit_within": sum(c["lodkit"]["within"] for c in at),
        "meshopt_within": sum(c["meshopt"]["within"] for c in at),
        "meshopt_bound_over_limit_median": statistics.median(c["meshopt"]["bound_relative"] / limit for c in at),
        "same_distance_triangle_ratio_geomean": math.exp(statistics.mean(math.log(c["same_distance"]["ratio"]) for c in at)),
    }
print()
for limit, s in summary.items():
    print(f"E = {float(limit):.1%}: within the limit lodkit {s['lodkit_within']}/{s['cases']}, meshoptimizer "
          f"{s['meshopt_within']}/{s['cases']} (its bound over the limit, median {s['meshopt_bound_over_limit_median']:.2f}x); "
          f"at meshoptimizer's own bound lodkit needs {s['same_distance_triangle_ratio_geomean']:.3f}x its triangles "
          "(geometric mean)")
json.dump({"machine": machine, "runs": runs, "limits": LIMITS, "summary": summary, "cases": cases},
          open(out_path, "w"), indent=2)
sys.exit(1 if len(done) < len(cases) else 0)
