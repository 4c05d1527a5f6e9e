"""Turns bench/simplify/run.py's records into the markdown tables scripts/bench.sh simplify prints,
bench/results/simplify.json, and the rate-distortion plot (gnuplot; PNG and SVG).

  report.py RESULTS.jsonl OUT.json MACHINE RUNS

Tables: time and memory per case, quality per case, lodkit's five metrics, then the issue 3 targets
with PASS / FAIL. Exits 1 when lodkit failed on a case or a table could not be made; a missed target
is reported, not an error (the benchmark measures, it does not gate)."""
import datetime
import json
import math
import os
import shutil
import subprocess
import sys

from verdict import QUALITY_PEERS, judge, stopped_short

TOOLS = ("lodkit", "lodkit-1t", "meshopt", "cgal-gh", "cgal-lt", "openmesh")
PEERS = ("meshopt", "cgal-gh", "cgal-lt", "openmesh")
METRICS = ("edge", "qem", "cqem", "memoryless", "cmemoryless")

results_path, out_path, machine, runs = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
records = [json.loads(l) for l in open(results_path) if l.strip()]
inputs = [r for r in records if r["kind"] == "input"]
used = [r for r in inputs if "skipped" not in r]
notes = [r["text"] for r in records if r["kind"] == "note"]
run = {(r["name"], r["fraction"], r["key"]): r for r in records if r["kind"] == "run"}
dist = {(r["name"], r["fraction"], r["key"]): r for r in records if r["kind"] == "distance"}
fractions = sorted({r["fraction"] for r in run.values()}, reverse=True)
cases = [(i["name"], f) for i in used for f in fractions if (i["name"], f, "lodkit") in run]
group = {i["name"]: i["group"] for i in used}
status = 0


def ok(key):
    return key in run and "median_s" in run[key]


def seconds(key):
    return run[key]["median_s"] if ok(key) else None


def quality(key, what):
    d = dist.get(key)
    return d.get(what + "_relative") if d else None


def fmt_s(v):
    if v is None:
        return "-"
    return f"{v:.3f}" if v >= 0.1 else f"{v * 1000:.1f} ms"


def fmt_e(v):
    return "-" if v is None else f"{v:.2e}"


def ratio(a, b):
    return a / b if a is not None and b and b > 0 else None


def fmt_r(v):
    return "-" if v is None else f"{v:.2f}"


def label(name, fraction):
    return f"{name} {fraction:.0%}"


def triangles_out(key):
    return run[key]["triangles_out"] if ok(key) else None


# ---- time and memory -------------------------------------------------------------------------
print("### Time and memory (median of the timed runs; peak RSS of the whole process)\n")
head = ["case", "triangles in", "target", "triangles out (" + " / ".join(TOOLS[:1] + PEERS) + ")"]
head += [f"{t} s" for t in TOOLS] + ["lodkit / meshopt", "lodkit 1t / meshopt"]
head += [f"{t} MiB" for t in ("lodkit", "lodkit-1t", "meshopt")] + ["RSS lodkit / meshopt"]
print("| " + " | ".join(head) + " |")
print("|" + "---|" * len(head))
rows = []
for name, f in cases:
    k = lambda t: (name, f, t)
    lod = run[k("lodkit")]
    if not ok(k("lodkit")) or not ok(k("lodkit-1t")):
        status = 1
    target = lod.get("target")
    outs = " / ".join(str(triangles_out(k(t))) if ok(k(t)) else "-" for t in ("lodkit",) + PEERS)
    peak = lambda t: run[k(t)].get("peak_mib") if ok(k(t)) else None
    row = {"case": label(name, f), "name": name, "fraction": f, "group": group.get(name), "target": target,
           "triangles_in": lod.get("triangles_in"),
           "seconds": {t: seconds(k(t)) for t in TOOLS}, "peak_mib": {t: peak(t) for t in TOOLS},
           "triangles_out": {t: triangles_out(k(t)) for t in TOOLS},
           "time_ratio": ratio(seconds(k("lodkit")), seconds(k("meshopt"))),
           "time_ratio_1t": ratio(seconds(k("lodkit-1t")), seconds(k("meshopt"))),
           "rss_ratio": ratio(peak("lodkit"), peak("meshopt"))}
    rows.append(row)
    cells = [row["case"], f"{row['triangles_in']:,}" if row["triangles_in"] else "-", str(target), outs]
    def time_cell(t):
        r = run.get(k(t), {})
        fewer = ok(k(t)) and r.get("runs", 0) < r.get("runs_asked", 0)
        return fmt_s(row["seconds"][t]) + (f" ({r['runs']} run{'s' if r['runs'] > 1 else ''})" if fewer else "")
    cells += [time_cell(t) for t in TOOLS]
    cells += [fmt_r(row["time_ratio"]), fmt_r(row["time_ratio_1t"])]
    cells += ["-" if peak(t) is None else f"{peak(t):.0f}" for t in ("lodkit", "lodkit-1t", "meshopt")]
    cells += [fmt_r(row["rss_ratio"])]
    print("| " + " | ".join(cells) + " |")

print("\n(N runs): the per-process budget of timed runs was spent before RUNS runs; the median is over N. "
      "'-': not run (CGAL and OpenMesh skip the 3.3M input) or failed (listed at the end).")

# ---- quality ---------------------------------------------------------------------------------
print("\n### Quality (symmetric Hausdorff and RMS distance to the input, divided by its bounding-box diagonal)\n")
quality_tools = ("lodkit",) + PEERS
head = ["case"] + [f"{t} H" for t in quality_tools] + [f"{t} RMS" for t in quality_tools]
head += ["H lodkit / best(GH, mo)", "RMS lodkit / best(GH, mo)"]
print("| " + " | ".join(head) + " |")
print("|" + "---|" * len(head))
for row in rows:
    name, f = row["name"], row["fraction"]
    k = lambda t: (name, f, t)
    h = {t: quality(k(t), "hausdorff") for t in quality_tools}
    r = {t: quality(k(t), "rms") for t in quality_tools}
    short = lambda t: ok(k(t)) and stopped_short(triangles_out(k(t)), row["target"])
    verdict = lambda values: judge(values["lodkit"], [values[t] for t in QUALITY_PEERS if values[t] is not None
                                                      and not short(t)], short("lodkit"))
    (vh, rh), (vr, rr) = verdict(h), verdict(r)
    row.update({"hausdorff": h, "rms": r, "hausdorff_verdict": vh, "hausdorff_ratio": rh, "rms_verdict": vr,
                "rms_ratio": rr, "lodkit_short": short("lodkit"),
                "lodkit_1t_same_output": dist.get(k("lodkit-1t"), {}).get("same_as") == "lodkit"})
    cell = lambda t, v: fmt_e(v) + (" (short)" if short(t) else "")
    cells = [row["case"]] + [cell(t, h[t]) for t in quality_tools] + [cell(t, r[t]) for t in quality_tools]
    shown = lambda v, x: fmt_r(x) if v in ("ok", "worse") else ("lodkit short" if v == "short" else "n/a")
    cells += [shown(vh, rh), shown(vr, rr)]
    print("| " + " | ".join(cells) + " |")
print("\n(short): that tool stopped more than 5% above the target triangle count; it is left out of "
      "\"best(GH, mo)\". A ratio of 1.00 means lodkit is at least as good as the better peer; \"lodkit short\": "
      "lodkit stopped short where a peer did not (counts against lodkit); n/a: neither peer reached the target.")
different = [row["case"] for row in rows if (row["name"], row["fraction"], "lodkit-1t") in dist
             and not row["lodkit_1t_same_output"]]
if different:
    print(f"\n**lodkit's output differs between 1 thread and all threads** on: {', '.join(different)}")

# ---- metric family ---------------------------------------------------------------------------
metric_cases = [(n, f) for n, f in ((i["name"], f) for i in used for f in fractions) if (n, f, "metric-qem") in run]
metric_rows = []
if metric_cases:
    print("\n### lodkit's metrics (one thread; median time, Hausdorff / diag, RMS / diag)\n")
    head = ["case"] + [f"{m} s" for m in METRICS] + [f"{m} H" for m in METRICS] + [f"{m} RMS" for m in METRICS]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for name, f in metric_cases:
        k = lambda m: (name, f, "metric-" + m)
        row = {"case": label(name, f), "seconds": {m: seconds(k(m)) for m in METRICS},
               "hausdorff": {m: quality(k(m), "hausdorff") for m in METRICS},
               "rms": {m: quality(k(m), "rms") for m in METRICS}}
        metric_rows.append(row)
        cells = [row["case"]] + [fmt_s(row["seconds"][m]) for m in METRICS]
        cells += [fmt_e(row["hausdorff"][m]) for m in METRICS] + [fmt_e(row["rms"][m]) for m in METRICS]
        print("| " + " | ".join(cells) + " |")


def geomean(values):
    values = [v for v in values if v is not None and v > 0]
    return math.exp(sum(map(math.log, values)) / len(values)) if values else None


# ---- targets ---------------------------------------------------------------------------------
print("\n### Issue 3 targets\n")
summary = {}
lines = []
corpus_rows = [r for r in rows if r["group"] == "corpus"]
quality_pass = True
for f in fractions:
    part = [r for r in corpus_rows if r["fraction"] == f]
    for what in ("hausdorff", "rms"):
        judged = [r for r in part if r[what + "_verdict"] is not None]
        if not judged:
            lines.append(f"- quality {what} at {f:.0%}: no comparable cases")
            quality_pass = False
            continue
        n_ok = sum(1 for r in judged if r[what + "_verdict"] == "ok")
        worse = [r for r in judged if r[what + "_verdict"] == "worse"]
        shorts = [r["case"] for r in judged if r[what + "_verdict"] == "short"]
        share = n_ok / len(judged)
        worst = max(worse, key=lambda r: r[what + "_ratio"], default=None)
        worst_ratio = worst[what + "_ratio"] if worst else 1.0
        good = share >= 0.9 and worst_ratio <= 1.2
        quality_pass &= good
        summary[f"quality_{what}_{f}"] = {"share_at_most_best_peer": share, "worst_ratio": worst_ratio,
                                          "worst_case": worst["case"] if worst else None, "cases": len(judged),
                                          "lodkit_short": shorts, "pass": good}
        lines.append(f"- quality {what} at {f:.0%}: lodkit <= the better of CGAL-GH and meshopt on {share:.0%} of "
                     f"{len(judged)} corpus cases (target >= 90%); worst "
                     + (f"{worst_ratio:.2f}x on {worst['case']}" if worst else "1.00x") + " (target <= 1.2x)"
                     + (f"; lodkit short of the target on {', '.join(shorts)}" if shorts else "")
                     + f": {'PASS' if good else 'FAIL'}")
    excluded = [r["case"] for r in part if r["hausdorff_verdict"] is None and r["rms_verdict"] is None]
    if excluded:
        lines.append(f"  - not judged at {f:.0%} (neither peer reached the target, or missing): {', '.join(excluded)}")
big_rows = [r for r in rows if r["group"] == "big"]
speed_pass = rss_pass = bool(big_rows)
for r in big_rows:
    t, t1, m = r["time_ratio"], r["time_ratio_1t"], r["rss_ratio"]
    m1 = ratio(r["peak_mib"]["lodkit-1t"], r["peak_mib"]["meshopt"])
    good_t = t is not None and t <= 1.0 and t1 is not None and t1 <= 1.5
    good_m = m is not None and m <= 2.0
    speed_pass &= good_t
    rss_pass &= good_m
    lines.append(f"- speed on {r['case']} ({r['triangles_in']:,} triangles): lodkit / meshopt {fmt_r(t)} all threads "
                 f"(target <= 1.0), {fmt_r(t1)} one thread (target <= 1.5): {'PASS' if good_t else 'FAIL'}; "
                 f"peak RSS lodkit / meshopt {fmt_r(m)} (target <= 2.0; one thread {fmt_r(m1)}): {'PASS' if good_m else 'FAIL'}")
if not big_rows:
    lines.append("- speed and memory: no big inputs in this run (quick mode?): not judged")
corpus_rss = [r["rss_ratio"] for r in corpus_rows if r["rss_ratio"] is not None]
if corpus_rss:
    lines.append(f"- peak RSS lodkit / meshopt on the corpus (small meshes: mostly process baseline): "
                 f"max {max(corpus_rss):.2f}, median {sorted(corpus_rss)[len(corpus_rss) // 2]:.2f}")
ordering = None
if metric_rows:
    mean_time = {m: geomean([row["seconds"][m] for row in metric_rows]) for m in METRICS}
    if all(v is not None for v in mean_time.values()):
        order = sorted(METRICS, key=lambda m: mean_time[m])
        e, q, c, ml, cml = (mean_time[m] for m in METRICS)
        # Houle: SEM < QEM ~ constrained < memoryless < constrained memoryless (QEM ~ CQEM within 25%).
        ordering = e < min(q, c) and max(q, c) <= 1.25 * min(q, c) and max(q, c) < ml < cml
        lines.append("- metric family, geometric-mean time (one thread): " +
                     ", ".join(f"{m} {fmt_s(mean_time[m])}" for m in METRICS) +
                     f"; fastest to slowest: {' < '.join(order)}; Houle's ordering "
                     f"(edge < qem ~ cqem < memoryless < cmemoryless): {'reproduced' if ordering else 'NOT reproduced'}")
        summary["metric_time_geomean"] = mean_time
summary.update({"quality_pass": quality_pass, "speed_pass": speed_pass if big_rows else None,
                "rss_pass": rss_pass if big_rows else None, "metric_ordering_reproduced": ordering})
print("\n".join(lines))
verdict = lambda v: "not judged" if v is None else ("PASS" if v else "FAIL")
print(f"\n**Summary: quality {verdict(quality_pass)}, speed {verdict(summary['speed_pass'])}, "
      f"memory {verdict(summary['rss_pass'])}, metric ordering "
      f"{'not judged' if ordering is None else ('reproduced' if ordering else 'not reproduced')}.**")

skipped = [i for i in inputs if "skipped" in i]
if skipped:
    reasons = {}
    for i in skipped:
        reasons.setdefault(i["skipped"], []).append(i["name"])
    for reason, names in reasons.items():
        print(f"\nSkipped, {reason} ({len(names)}): {', '.join(names)}")
failed = [r for r in run.values() if "failed" in r]
if failed:
    print("\nFailed runs: " + "; ".join(f"{r['key']} on {label(r['name'], r['fraction'])}: {r['failed']}" for r in failed))
dropped = [r for r in run.values() if r.get("faces_dropped")]
if dropped:
    print("\nTriangles a halfedge peer refused (non-manifold; distances are still to the full input): " +
          "; ".join(f"{r['key']} on {r['name']}: {r['faces_dropped']}" for r in dropped if r["fraction"] == fractions[0]))
for n in notes:
    print(f"\nNote: {n}")

# ---- plot ------------------------------------------------------------------------------------
out_dir = os.path.dirname(out_path) or "."
plot_files = []
plot_names = [i["name"] for i in used if any((i["name"], f, "lodkit") in dist for f in fractions)]
if plot_names and shutil.which("gnuplot"):
    data_path = os.path.join(out_dir, "simplify-rd.dat")
    plot_tools = ("lodkit",) + PEERS
    with open(data_path, "w") as fh:
        # One gnuplot data block per (mesh, tool): triangles out, Hausdorff / diag.
        for name in plot_names:
            for t in plot_tools:
                fh.write(f"# {name} {t}\n")
                for f in fractions:
                    h = quality((name, f, t), "hausdorff")
                    if h and ok((name, f, t)):
                        fh.write(f"{triangles_out((name, f, t))} {h}\n")
                fh.write("\n\n")
    columns = 6
    rows_n = (len(plot_names) + columns - 1) // columns
    script = [f"set multiplot layout {rows_n},{columns} title 'Hausdorff / bbox diagonal against triangles out (log-log)'",
              "set logscale xy", "set format x '%.0s%c'", "set format y '%.0e'", "set key top right font ',7'",
              "set tics font ',7'", "set title font ',9'"]
    colors = ("#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e")
    for i, name in enumerate(plot_names):
        base = i * len(plot_tools)
        script.append(f"set title '{name}' noenhanced")
        parts = []
        for j, t in enumerate(plot_tools):
            title = f"title '{t}'" if i == 0 else "notitle"  # only the first panel carries the key
            parts.append(f"'{data_path}' index {base + j} using 1:2 with linespoints lc rgb '{colors[j]}' pt 7 ps 0.5 {title}")
        script.append("plot " + ", ".join(parts))
    script.append("unset multiplot")
    body = "\n".join(script)
    for term, ext in (("pngcairo size {w},{h} font ',8'", "png"), ("svg size {w},{h} font 'sans,8'", "svg")):
        path = os.path.join(out_dir, f"simplify-rd.{ext}")
        full = f"set terminal {term.format(w=columns * 320, h=rows_n * 260 + 40)}\nset output '{path}'\n{body}\n"
        p = subprocess.run(["gnuplot"], input=full, capture_output=True, text=True)
        if p.returncode == 0 and os.path.exists(path):
            plot_files.append(path)
        else:
            print(f"\nNote: gnuplot failed for {ext}: {p.stderr.strip().splitlines()[:2]}")
elif plot_names:
    print("\nNote: gnuplot not found (Debian gnuplot-nox); no plot")

with open(out_path, "w") as fh:
    json.dump({"machine": machine, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
               "runs": runs, "summary": summary, "cases": rows, "metric_cases": metric_rows, "notes": notes,
               "plots": plot_files, "records": records}, fh, indent=1)
print(f"\nresults in {out_path}" + (f"; plots {', '.join(plot_files)}" if plot_files else ""))
sys.exit(status)
