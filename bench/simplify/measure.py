"""`lodkit compare` against CGAL's distance (cgal_distance) on (mesh, simplified mesh) pairs, at the
same number of area samples per direction: the values and the time of each (issue 4's bench).

  measure.py BENCH_DIR LODKIT_CLI WORK_DIR OUT.json PAIRS MACHINE

The pairs are corpus meshes simplified by lodkit (qem) to 10% and 1%. Both tools sample every vertex
plus SAMPLES random area samples per direction (lodkit also samples edges; CGAL's soup sampler has no
edge samples). Time is each tool's own report, loading excluded: lodkit's compare_seconds (both BVHs,
sampling and queries) with all threads and with one, cgal_distance's seconds (sampling, AABB trees,
queries; single-threaded)."""
import datetime
import json
import os
import statistics
import subprocess
import sys

MESHES = ("bunny00.off", "armadillo.off", "refined_elephant.off", "fandisk_large.off", "man.off", "bear.off",
          "camel.off", "turbine.off", "cheese.off", "lion-head.off", "blade.off", "bull.off", "homer.off",
          "femur.off", "dino.off")
AGREEMENT = 0.02  # issue 4: within 2%

bench_dir, lodkit_cli, work_dir, out_path, pairs, machine = sys.argv[1:7]
pairs = int(pairs)
os.makedirs(work_dir, exist_ok=True)
meshes = [m for m in MESHES if os.path.exists(os.path.join("data/corpus", m))]
cases = [(m, f) for m in meshes for f in (0.10, 0.01)][:pairs]


def run_json(command):
    p = subprocess.run(command, capture_output=True, text=True, timeout=900)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(command[:3])}: {(p.stderr.strip().splitlines() or ['failed'])[0]}")
    return json.loads(p.stdout)


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-30)


rows = []
print("| pair | triangles | area samples / direction | lodkit H | CGAL H | H diff | lodkit RMS | CGAL RMS | RMS diff "
      "| lodkit s | lodkit 1t s | CGAL s | CGAL / lodkit | CGAL / lodkit 1t |")
print("|" + "---|" * 14)
for name, fraction in cases:
    source = os.path.join("data/corpus", name)
    info = run_json([lodkit_cli, "info", source, "--json"])
    triangles = info["stats"]["triangles"]
    target = max(4, round(triangles * fraction))
    simplified = os.path.join(work_dir, f"{name.rsplit('.', 1)[0]}-{target}.ply")
    try:
        if not os.path.exists(simplified) or os.path.getmtime(simplified) < os.path.getmtime(source):
            run_json([os.path.join(bench_dir, "lodkit_bench_simplify"), "qem", source, simplified, str(target), "1", "--json"])
        samples = min(2_000_000, max(10_000, 10 * triangles))  # lodkit compare's default rule
        lod = run_json([lodkit_cli, "compare", source, simplified, "--samples", str(samples), "--json"])
        lod1 = run_json([lodkit_cli, "compare", source, simplified, "--samples", str(samples), "--threads", "1", "--json"])
        cgal = run_json([os.path.join(bench_dir, "cgal_distance"), source, simplified, "--samples", str(samples), "--json"])
    except (RuntimeError, subprocess.TimeoutExpired) as e:
        print(f"| {name} {fraction:.0%} | failed: {e} |" + " |" * 12)
        rows.append({"pair": f"{name} {fraction:.0%}", "failed": str(e)})
        continue
    s = lod["symmetric"]
    row = {"pair": f"{name} {fraction:.0%}", "mesh": name, "fraction": fraction, "triangles": triangles, "target": target,
           "samples": samples,
           "lodkit": {"hausdorff_relative": s["relative_hausdorff"], "rms_relative": s["relative_rms"],
                      "seconds": lod["compare_seconds"], "seconds_1t": lod1["compare_seconds"],
                      "queries": lod.get("queries")},
           "cgal": {"hausdorff_relative": cgal["hausdorff_relative"], "rms_relative": cgal["rms_relative"],
                    "seconds": cgal["seconds"]}}
    row["hausdorff_diff"] = rel(row["lodkit"]["hausdorff_relative"], row["cgal"]["hausdorff_relative"])
    row["rms_diff"] = rel(row["lodkit"]["rms_relative"], row["cgal"]["rms_relative"])
    row["speedup"] = cgal["seconds"] / lod["compare_seconds"]
    row["speedup_1t"] = cgal["seconds"] / lod1["compare_seconds"]
    rows.append(row)
    print(f"| {row['pair']} | {triangles:,} -> {target:,} | {samples:,} | {row['lodkit']['hausdorff_relative']:.4e} "
          f"| {row['cgal']['hausdorff_relative']:.4e} | {row['hausdorff_diff']:.2%} | {row['lodkit']['rms_relative']:.4e} "
          f"| {row['cgal']['rms_relative']:.4e} | {row['rms_diff']:.2%} | {lod['compare_seconds']:.3f} "
          f"| {lod1['compare_seconds']:.3f} | {cgal['seconds']:.3f} | {row['speedup']:.1f} | {row['speedup_1t']:.1f} |",
          flush=True)

good = [r for r in rows if "failed" not in r]
summary = {}
if good:
    agree = [r for r in good if r["hausdorff_diff"] <= AGREEMENT and r["rms_diff"] <= AGREEMENT]
    summary = {"pairs": len(good), "agree_within_2pct": len(agree),
               "max_hausdorff_diff": max(r["hausdorff_diff"] for r in good),
               "max_rms_diff": max(r["rms_diff"] for r in good),
               "median_speedup": statistics.median(r["speedup"] for r in good),
               "min_speedup": min(r["speedup"] for r in good),
               "median_speedup_1t": statistics.median(r["speedup_1t"] for r in good)}
    print(f"\nagreement: Hausdorff and RMS within {AGREEMENT:.0%} of CGAL on {len(agree)} of {len(good)} pairs "
          f"(largest differences: Hausdorff {summary['max_hausdorff_diff']:.2%}, RMS {summary['max_rms_diff']:.2%}): "
          f"{'PASS' if len(agree) == len(good) else 'FAIL'}")
    print(f"speed: CGAL time / lodkit time, median {summary['median_speedup']:.1f}x (min {summary['min_speedup']:.1f}x) "
          f"with all threads, {summary['median_speedup_1t']:.1f}x with one thread (target >= 10x): "
          f"{'PASS' if summary['min_speedup'] >= 10 else 'FAIL'}")
    print("Both sample the same number of random area points per direction plus every vertex; lodkit adds edge samples "
          "and places its area samples by stratified (per-triangle) allocation, CGAL by area-weighted random choice, "
          "so a Hausdorff maximum that falls between samples can differ a little.")
with open(out_path, "w") as fh:
    json.dump({"machine": machine, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
               "summary": summary, "pairs": rows}, fh, indent=1)
print(f"\nresults in {out_path}")
sys.exit(0 if good and len(good) == len(rows) else 1)
