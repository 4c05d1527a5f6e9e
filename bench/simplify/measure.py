"""lodkit's distance (lod::compare) against CGAL's (cgal_distance) and a brute-force reference
(lodkit_bench_brute_force) on (mesh, simplified mesh) pairs, at the same number of area samples per
direction: the values and the time of each (issue 4's bench).

  measure.py BENCH_DIR LODKIT_CLI WORK_DIR OUT.json PAIRS MACHINE

The pairs are corpus meshes simplified by lodkit (qem) to 10% and 1%. lodkit and CGAL sample every vertex
plus SAMPLES random area points per direction (10 per triangle of the larger mesh, lodkit's default);
lodkit's default also samples edges, CGAL's soup sampler cannot, so lodkit runs twice through
lodkit_bench_compare (lod::compare, loading excluded, median of 3 runs): by default ("lodkit", all
threads) and with --no-edges ("lodkit =", CGAL's sampling scheme and query count: area points and
vertices; all threads and one). "lodkit ref." is the default call with --refine, whose certified
refinement pushes the maximum towards the true one.
Brute force (only when both meshes have <= BRUTE_MAX triangles): a dense grid on every triangle
against every triangle of the other mesh, then certified refinement of the maximum, so the true
Hausdorff distance lies in [brute H, brute bound]; RMS by the midpoint rule on the grid.
Agreement (2%): lodkit's Hausdorff (its default call) and RMS against CGAL's, and lodkit (refined) Hausdorff
and lodkit RMS against brute force. Every sampled Hausdorff value is the distance from one point of a
surface to the other, so it is a lower bound of the true value: where lodkit's exceeds CGAL's by more
than 2%, the point lodkit reports is measured again by brute force (lodkit_bench_brute_force --point);
if that certified distance is more than 2% above CGAL's value, CGAL's sample missed the maximum by more
than 2% of the truth, which no exact tool can agree with: the pair counts as "CGAL low (certified)",
not as a failure. A lodkit value more than 2% below CGAL's always fails. The same-sampling comparison
("lodkit =" against CGAL) is reported beside it.
Speed at equal sample counts (target 10x): the time of the function the issue names,
PMP::approximate_Hausdorff_distance, both directions ("CGAL fn": cgal_distance --pmp; same face samples
plus every vertex), divided by "lodkit =" time: one thread each (CGAL's Sequential_tag) and all threads
each (CGAL's Parallel_tag, TBB). The pass/fail uses all threads each, on every pair. The emulation's time
(cgal_distance's own loop over a Triangle_3 AABB tree, which also yields RMS; faster than CGAL's function)
over lodkit's is reported too."""
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
BRUTE_MAX = 20_000  # triangles of the larger mesh for the brute-force reference

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



def lodkit(source, simplified, samples, *extra):
    return run_json([os.path.join(bench_dir, "lodkit_bench_compare"), source, simplified, "--samples", str(samples),
                     "--json", *extra])


def fmt(x, spec=".4e"):
    return "-" if x is None else format(x, spec)


rows = []
print("| pair | triangles | samples / dir | lodkit H | lodkit = H | lodkit ref. H | CGAL H | brute H [bound] "
      "| H lodkit =/CGAL | H lodkit/CGAL | certified H | CGAL verdict | H ref./brute | lodkit = RMS | CGAL RMS | brute RMS | RMS lodkit =/CGAL | RMS lodkit/brute "
      "| lodkit s | lodkit = s | lodkit = 1t s | CGAL s | CGAL fn 1t s | CGAL fn s | CGAL fn/lodkit =, 1t | CGAL fn/lodkit =, all "
      "| CGAL/lodkit = | CGAL/lodkit = 1t |")
print("|" + "---|" * 28)
for name, fraction in cases:
    source = os.path.join("data/corpus", name)
    info = run_json([lodkit_cli, "info", source, "--json"])
    triangles = info["stats"]["triangles"]
    target = max(4, round(triangles * fraction))
    simplified = os.path.join(work_dir, f"{name.rsplit('.', 1)[0]}-{target}.ply")
    samples = min(2_000_000, max(10_000, 10 * triangles))  # lodkit compare's default rule
    try:
        if not os.path.exists(simplified) or os.path.getmtime(simplified) < os.path.getmtime(source):
            run_json([os.path.join(bench_dir, "lodkit_bench_simplify"), "qem", source, simplified, str(target), "1", "--json"])
        lod = lodkit(source, simplified, samples, "--runs", "3")
        same = lodkit(source, simplified, samples, "--runs", "3", "--no-edges")
        same1 = lodkit(source, simplified, samples, "--runs", "3", "--no-edges", "--threads", "1")
        ref = lodkit(source, simplified, samples, "--refine")
        cgal = run_json([os.path.join(bench_dir, "cgal_distance"), source, simplified, "--samples", str(samples), "--pmp",
                         "--json"])
        brute = None
        if triangles <= BRUTE_MAX:
            brute = run_json([os.path.join(bench_dir, "lodkit_bench_brute_force"), source, simplified, "--json"])
    except (RuntimeError, subprocess.TimeoutExpired) as e:
        print(f"| {name} {fraction:.0%} | failed: {e} |" + " |" * 26)
        rows.append({"pair": f"{name} {fraction:.0%}", "failed": str(e)})
        continue
    row = {"pair": f"{name} {fraction:.0%}", "mesh": name, "fraction": fraction, "triangles": triangles, "target": target,
           "samples": samples,
           "lodkit": {"hausdorff_relative": lod["hausdorff_relative"], "rms_relative": lod["rms_relative"],
                      "refined_hausdorff_relative": ref["hausdorff_relative"],
                      "refined_bound_relative": ref["hausdorff_bound_relative"],
                      "seconds": lod["seconds"], "queries": lod["queries"],
                      "refined_seconds": ref["seconds"]},
           "lodkit_same_sampling": {"hausdorff_relative": same["hausdorff_relative"], "rms_relative": same["rms_relative"],
                                    "seconds": same["seconds"], "seconds_1t": same1["seconds"], "queries": same["queries"]},
           "cgal": {"hausdorff_relative": cgal["hausdorff_relative"], "rms_relative": cgal["rms_relative"],
                    "seconds": cgal["seconds"], "function_seconds_1t": cgal["pmp_seconds"],
                    # Without TBB, CGAL's function has only its sequential form.
                    "function_seconds": cgal.get("pmp_parallel_seconds", cgal["pmp_seconds"]),
                    "function_hausdorff_relative": cgal["pmp_hausdorff_relative"]}}
    row["hausdorff_diff"] = rel(same["hausdorff_relative"], row["cgal"]["hausdorff_relative"])
    row["rms_diff"] = rel(same["rms_relative"], row["cgal"]["rms_relative"])
    row["hausdorff_diff_default"] = rel(row["lodkit"]["hausdorff_relative"], row["cgal"]["hausdorff_relative"])
    row["rms_diff_default"] = rel(row["lodkit"]["rms_relative"], row["cgal"]["rms_relative"])
    row["cgal_verdict"] = "agree" if row["hausdorff_diff_default"] <= AGREEMENT else "lodkit low"
    if row["lodkit"]["hausdorff_relative"] > row["cgal"]["hausdorff_relative"] * (1 + AGREEMENT):
        # Certify lodkit's maximum: the brute-force distance from the point it reports to the other surface.
        forward = lod["a_to_b"]["hausdorff"] >= lod["b_to_a"]["hausdorff"]
        worst = lod["a_to_b" if forward else "b_to_a"]["worst"]
        files = [source, simplified] if forward else [simplified, source]
        check = run_json([os.path.join(bench_dir, "lodkit_bench_brute_force"), *files, "--point", *map(repr, worst), "--json"])
        certified = check["distance"] / lod["diagonal"]
        row["certified_hausdorff_relative"] = certified
        row["cgal_verdict"] = ("CGAL low (certified)"
                               if certified >= row["cgal"]["hausdorff_relative"] * (1 + AGREEMENT)
                               and rel(row["lodkit"]["hausdorff_relative"], certified) <= AGREEMENT else "lodkit high")
    if row["rms_diff_default"] > AGREEMENT:
        row["cgal_verdict"] = "RMS differs"
    if brute:
        row["brute"] = {"hausdorff_relative": brute["hausdorff_relative"], "bound_relative": brute["hausdorff_bound_relative"],
                        "rms_relative": brute["rms_relative"], "seconds": brute["seconds"]}
        row["hausdorff_diff_brute"] = rel(row["lodkit"]["refined_hausdorff_relative"], brute["hausdorff_relative"])
        row["hausdorff_diff_brute_unrefined"] = rel(row["lodkit"]["hausdorff_relative"], brute["hausdorff_relative"])
        row["cgal_hausdorff_diff_brute"] = rel(row["cgal"]["hausdorff_relative"], brute["hausdorff_relative"])
        row["rms_diff_brute"] = rel(row["lodkit"]["rms_relative"], brute["rms_relative"])
    row["speedup"] = cgal["seconds"] / same["seconds"]
    row["speedup_1t"] = cgal["seconds"] / same1["seconds"]
    row["speedup_default"] = cgal["seconds"] / lod["seconds"]
    row["speedup_function_1t"] = row["cgal"]["function_seconds_1t"] / same1["seconds"]
    row["speedup_function"] = row["cgal"]["function_seconds"] / same["seconds"]
    rows.append(row)
    b = row.get("brute")
    print(f"| {row['pair']} | {triangles:,} -> {target:,} | {samples:,} | {fmt(row['lodkit']['hausdorff_relative'])} "
          f"| {fmt(same['hausdorff_relative'])} | {fmt(row['lodkit']['refined_hausdorff_relative'])} "
          f"| {fmt(row['cgal']['hausdorff_relative'])} "
          f"| {fmt(b and b['hausdorff_relative'])} [{fmt(b and b['bound_relative'])}] | {row['hausdorff_diff']:.2%} "
          f"| {row['hausdorff_diff_default']:.2%} | {fmt(row.get('certified_hausdorff_relative'))} | {row['cgal_verdict']} "
          f"| {fmt(row.get('hausdorff_diff_brute'), '.2%')} | {fmt(same['rms_relative'])} "
          f"| {fmt(row['cgal']['rms_relative'])} | {fmt(b and b['rms_relative'])} | {row['rms_diff']:.2%} "
          f"| {fmt(row.get('rms_diff_brute'), '.2%')} | {lod['seconds']:.3f} | {same['seconds']:.3f} "
          f"| {same1['seconds']:.3f} | {cgal['seconds']:.3f} | {row['cgal']['function_seconds_1t']:.3f} "
          f"| {row['cgal']['function_seconds']:.3f} | {row['speedup_function_1t']:.1f} | {row['speedup_function']:.1f} "
          f"| {row['speedup']:.1f} | {row['speedup_1t']:.1f} |", flush=True)

good = [r for r in rows if "failed" not in r]
summary = {}
verdicts = []
if good:
    brute_rows = [r for r in good if "brute" in r]
    agree = [r for r in good if r["cgal_verdict"] == "agree"]
    certified = [r for r in good if r["cgal_verdict"] == "CGAL low (certified)"]
    agree_same = [r for r in good if r["hausdorff_diff"] <= AGREEMENT and r["rms_diff"] <= AGREEMENT]
    agree_brute = [r for r in brute_rows if r["hausdorff_diff_brute"] <= AGREEMENT and r["rms_diff_brute"] <= AGREEMENT]
    summary = {"pairs": len(good), "agree_cgal_within_2pct": len(agree), "cgal_low_certified": len(certified),
               "cgal_failed": [r["pair"] + ": " + r["cgal_verdict"] for r in good if r not in agree + certified],
               "agree_cgal_same_sampling_within_2pct": len(agree_same),
               "max_hausdorff_diff_default": max(r["hausdorff_diff_default"] for r in good),
               "max_rms_diff_default": max(r["rms_diff_default"] for r in good),
               "max_hausdorff_diff": max(r["hausdorff_diff"] for r in good),
               "max_rms_diff": max(r["rms_diff"] for r in good),
               "brute_pairs": len(brute_rows), "agree_brute_within_2pct": len(agree_brute),
               "max_hausdorff_diff_brute": max((r["hausdorff_diff_brute"] for r in brute_rows), default=None),
               "max_hausdorff_diff_brute_unrefined": max((r["hausdorff_diff_brute_unrefined"] for r in brute_rows), default=None),
               "max_cgal_hausdorff_diff_brute": max((r["cgal_hausdorff_diff_brute"] for r in brute_rows), default=None),
               "max_rms_diff_brute": max((r["rms_diff_brute"] for r in brute_rows), default=None),
               "median_speedup": statistics.median(r["speedup"] for r in good),
               "min_speedup": min(r["speedup"] for r in good),
               "median_speedup_1t": statistics.median(r["speedup_1t"] for r in good),
               "median_speedup_default": statistics.median(r["speedup_default"] for r in good),
               "min_speedup_1t": min(r["speedup_1t"] for r in good),
               "median_speedup_function": statistics.median(r["speedup_function"] for r in good),
               "min_speedup_function": min(r["speedup_function"] for r in good),
               "median_speedup_function_1t": statistics.median(r["speedup_function_1t"] for r in good),
               "min_speedup_function_1t": min(r["speedup_function_1t"] for r in good)}
    ok_cgal = len(agree) + len(certified) == len(good)
    ok_brute = bool(brute_rows) and len(agree_brute) == len(brute_rows)
    ok_speed = summary["min_speedup_function"] >= 10
    print(f"\nagreement with CGAL: lodkit's Hausdorff and RMS within {AGREEMENT:.0%} on {len(agree)} of {len(good)} pairs; "
          f"CGAL's Hausdorff certified more than {AGREEMENT:.0%} below the true value on {len(certified)} "
          f"({', '.join(r['pair'] for r in certified) or 'none'}); failed: {', '.join(summary['cgal_failed']) or 'none'} "
          f"(largest differences: Hausdorff {summary['max_hausdorff_diff_default']:.2%}, RMS {summary['max_rms_diff_default']:.2%})")
    print(f"at the same sampling (lodkit =, CGAL's scheme, different random points): within {AGREEMENT:.0%} on {len(agree_same)} "
          f"of {len(good)} (largest: Hausdorff {summary['max_hausdorff_diff']:.2%}, RMS {summary['max_rms_diff']:.2%})")
    if brute_rows:
        print(f"agreement with brute force: refined Hausdorff and RMS within {AGREEMENT:.0%} on {len(agree_brute)} of "
              f"{len(brute_rows)} pairs (largest: refined H {summary['max_hausdorff_diff_brute']:.2%}, unrefined H "
              f"{summary['max_hausdorff_diff_brute_unrefined']:.2%}, CGAL H {summary['max_cgal_hausdorff_diff_brute']:.2%}, "
              f"RMS {summary['max_rms_diff_brute']:.2%})")
    print(f"speed: CGAL's approximate_Hausdorff_distance time / lodkit time at equal sample counts (lodkit =), "
          f"all threads each: median {summary['median_speedup_function']:.1f}x (min {summary['min_speedup_function']:.1f}x); "
          f"one thread each: median {summary['median_speedup_function_1t']:.1f}x (min {summary['min_speedup_function_1t']:.1f}x)")
    print(f"against the emulation (one thread, faster than CGAL's function): median {summary['median_speedup']:.1f}x (min {summary['min_speedup']:.1f}x) "
          f"with all threads, median {summary['median_speedup_1t']:.1f}x (min {summary['min_speedup_1t']:.1f}x) with one, "
          f"at equal sample counts (lodkit =); lodkit's default (edge samples too, ~35% more queries) median "
          f"{summary['median_speedup_default']:.1f}x")
    summary.update({"pass_cgal": ok_cgal, "pass_brute": ok_brute, "pass_speed": ok_speed})
    print(f"SUMMARY: agreement with CGAL within 2%: {'PASS' if ok_cgal else 'FAIL'}; with brute force within 2%: "
          f"{'PASS' if ok_brute else 'FAIL'}; lodkit >= 10x faster than CGAL's approximate_Hausdorff_distance (all threads each, every pair): {'PASS' if ok_speed else 'FAIL'}")
    print("Sampled Hausdorff distances are lower bounds: at equal sample counts both tools can miss a maximum "
          "that lies between samples. lodkit also samples every edge (where maxima on creases sit), CGAL does not, "
          "so lodkit's H is higher when the maximum is on an edge; the brute-force bound brackets the true value.")
with open(out_path, "w") as fh:
    json.dump({"machine": machine, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
               "summary": summary, "pairs": rows}, fh, indent=1)
print(f"\nresults in {out_path}")
sys.exit(0 if good and len(good) == len(rows) else 1)
