"""Tables and the issue 5 targets from bench/optimize/run.py's records.

  report.py RESULTS.jsonl SUMMARY.json MACHINE RUNS

Prints markdown tables (vertex cache, strips, the big input) and each target with PASS or FAIL, and
writes SUMMARY.json (summary, per-input cases, raw records). Exits 1 when a run failed or a target
has no data.
"""
import json
import math
import statistics
import sys

TIME_MIN_TRIANGLES = 10000  # the big-input time target; the smaller corpus inputs have their own (microseconds per run)


def load(path):
    inputs, runs, notes = [], {}, []
    for line in open(path):
        r = json.loads(line)
        if r["kind"] == "input":
            inputs.append(r)
        elif r["kind"] == "run":
            runs[(r["name"], r["tool"], r["op"])] = r
        else:
            notes.append(r["text"])
    return inputs, runs, notes


def fmt(x, digits=3):
    return "—" if x is None else f"{x:.{digits}f}"


def ms(x):
    return "—" if x is None else (f"{x * 1e3:.3f}" if x < 0.01 else f"{x * 1e3:.1f}")


def geomean(values):
    values = [v for v in values if v and v > 0]
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else None


def main():
    path, summary_path, machine, runs_asked = sys.argv[1:5]
    inputs, runs, notes = load(path)
    failed = [r for r in runs.values() if "failed" in r]
    get = lambda name, tool, op, key: (runs.get((name, tool, op)) or {}).get(key)
    used = [i for i in inputs if "skipped" not in i]
    corpus = [i for i in used if i["group"] == "corpus"]
    big = [i for i in used if i["group"] == "big"]
    for n in notes:
        print(f"note: {n}")
    skipped = [i for i in inputs if "skipped" in i]
    if skipped:
        print(f"skipped inputs: {', '.join(i['name'] + ' (' + i['skipped'] + ')' for i in skipped)}")
    print(f"inputs: {len(corpus)} corpus meshes{' + ' + ', '.join(i['name'] for i in big) if big else ''}; "
          f"times are medians over at least {runs_asked} runs (small meshes: runs adding up to 0.2 s)")
    print()

    cases = []
    # ---- vertex cache ------------------------------------------------------------------------------
    print("### Vertex cache (ACMR = misses per triangle, FIFO; lower is better; ratio = lodkit ÷ meshoptimizer)")
    print()
    print("| input | triangles | input ACMR 16 | lodkit 16 | meshopt 16 | ratio | lodkit 32 | meshopt 32 | ratio | "
          "Tipsify 16 / 32 | ATVR 16 lodkit / meshopt | time lodkit 16 / 32 ms | meshopt ms | time ratio (of minima) | peak MiB lodkit / meshopt |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for i in used:
        n = i["name"]
        c = {"name": n, "group": i["group"], "triangles": i["triangles"]}
        c["input_acmr16"] = get(n, "lodkit", "vcache16", "acmr_input_fifo16")
        c["lodkit_acmr16"] = get(n, "lodkit", "vcache16", "acmr_fifo16")
        c["lodkit_acmr32"] = get(n, "lodkit", "vcache32", "acmr_fifo32")
        c["meshopt_acmr16"] = get(n, "meshopt", "vcache16", "acmr_fifo16")
        c["meshopt_acmr32"] = get(n, "meshopt", "vcache16", "acmr_fifo32")
        c["tipsify_acmr16"] = get(n, "meshopt-fifo", "vcache16", "acmr_fifo16")
        c["tipsify_acmr32"] = get(n, "meshopt-fifo", "vcache32", "acmr_fifo32")
        c["lodkit_atvr16"] = get(n, "lodkit", "vcache16", "atvr_fifo16")
        c["lodkit_atvr32"] = get(n, "lodkit", "vcache32", "atvr_fifo32")
        c["meshopt_atvr16"] = get(n, "meshopt", "vcache16", "atvr_fifo16")
        c["meshopt_atvr32"] = get(n, "meshopt", "vcache16", "atvr_fifo32")
        c["lodkit_s16"] = get(n, "lodkit", "vcache16", "median_s")
        c["lodkit_s32"] = get(n, "lodkit", "vcache32", "median_s")
        c["meshopt_s"] = get(n, "meshopt", "vcache16", "median_s")
        c["lodkit_peak_mib"] = get(n, "lodkit", "vcache32", "peak_mib")
        c["meshopt_peak_mib"] = get(n, "meshopt", "vcache16", "peak_mib")
        for k in (16, 32):
            a, b = c[f"lodkit_acmr{k}"], c[f"meshopt_acmr{k}"]
            c[f"acmr_ratio{k}"] = a / b if a is not None and b else None
        slow = max([t for t in (c["lodkit_s16"], c["lodkit_s32"]) if t is not None], default=None)
        c["time_ratio"] = slow / c["meshopt_s"] if slow is not None and c["meshopt_s"] else None
        # The fastest runs too: on a loaded machine a median can catch a burst of someone else's work.
        fast = max([t for t in (get(n, "lodkit", "vcache16", "min_s"), get(n, "lodkit", "vcache32", "min_s")) if t is not None], default=None)
        meshopt_min = get(n, "meshopt", "vcache16", "min_s")
        c["time_ratio_min"] = fast / meshopt_min if fast is not None and meshopt_min else None
        cases.append(c)
        print(f"| {n} | {i['triangles']:,} | {fmt(c['input_acmr16'])} | {fmt(c['lodkit_acmr16'])} | {fmt(c['meshopt_acmr16'])} | "
              f"{fmt(c['acmr_ratio16'])} | {fmt(c['lodkit_acmr32'])} | {fmt(c['meshopt_acmr32'])} | {fmt(c['acmr_ratio32'])} | "
              f"{fmt(c['tipsify_acmr16'])} / {fmt(c['tipsify_acmr32'])} | {fmt(c['lodkit_atvr16'])} / {fmt(c['meshopt_atvr16'])} | "
              f"{ms(c['lodkit_s16'])} / {ms(c['lodkit_s32'])} | {ms(c['meshopt_s'])} | {fmt(c['time_ratio'], 2)} ({fmt(c['time_ratio_min'], 2)}) | "
              f"{fmt(c['lodkit_peak_mib'], 1)} / {fmt(c['meshopt_peak_mib'], 1)} |")
    print()

    # ---- strips ------------------------------------------------------------------------------------
    print("### Strips (indices per triangle, lower is better; lodkit best ÷ meshoptimizer; SGI is the course's baseline)")
    print()
    print("| input | triangles | lodkit degenerate | meshopt degenerate | ratio | lodkit restart | meshopt restart | ratio | "
          "SGI degenerate / restart | strips lodkit / meshopt / SGI (restart) | strip ACMR 16 lodkit / meshopt | time lodkit / meshopt ms |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    by_name = {c["name"]: c for c in cases}
    for i in used:
        n, c = i["name"], by_name[i["name"]]
        for join, op in (("degenerate", "strip"), ("restart", "strip-restart")):
            c[f"lodkit_ipt_{join}"] = get(n, "lodkit", op, "indices_per_triangle")
            c[f"meshopt_ipt_{join}"] = get(n, "meshopt", op, "indices_per_triangle")
            c[f"sgi_ipt_{join}"] = get(n, "lodkit", "sgi" + op[5:], "indices_per_triangle")
            a, b = c[f"lodkit_ipt_{join}"], c[f"meshopt_ipt_{join}"]
            c[f"strip_ratio_{join}"] = a / b if a is not None and b else None
        c["strips_restart"] = [get(n, "lodkit", "strip-restart", "strips"), get(n, "meshopt", "strip-restart", "strips"),
                               get(n, "lodkit", "sgi-restart", "strips")]
        c["strip_acmr16"] = [get(n, "lodkit", "strip", "acmr_fifo16"), get(n, "meshopt", "strip", "acmr_fifo16")]
        c["strip_s"] = [get(n, "lodkit", "strip", "median_s"), get(n, "meshopt", "strip", "median_s")]
        s = c["strips_restart"]
        print(f"| {n} | {i['triangles']:,} | {fmt(c['lodkit_ipt_degenerate'])} | {fmt(c['meshopt_ipt_degenerate'])} | "
              f"{fmt(c['strip_ratio_degenerate'])} | {fmt(c['lodkit_ipt_restart'])} | {fmt(c['meshopt_ipt_restart'])} | "
              f"{fmt(c['strip_ratio_restart'])} | {fmt(c['sgi_ipt_degenerate'])} / {fmt(c['sgi_ipt_restart'])} | "
              f"{s[0]} / {s[1]} / {s[2]} | {fmt(c['strip_acmr16'][0])} / {fmt(c['strip_acmr16'][1])} | "
              f"{ms(c['strip_s'][0])} / {ms(c['strip_s'][1])} |")
    print()

    # ---- overdraw (optional in issue 5: information, no target) ---------------------------------------
    for c in cases:
        n = c["name"]
        c["overdraw"] = {
            "lodkit_cache": get(n, "lodkit", "vcache16", "overdraw"), "lodkit": get(n, "lodkit", "overdraw", "overdraw"),
            "meshopt_cache": get(n, "meshopt", "vcache16", "overdraw"), "meshopt": get(n, "meshopt", "overdraw", "overdraw"),
            "lodkit_meshopt_analyzer": get(n, "lodkit", "overdraw", "overdraw_meshopt_analyzer"),
            "meshopt_meshopt_analyzer": get(n, "meshopt", "overdraw", "overdraw_meshopt_analyzer"),
            "lodkit_acmr16": get(n, "lodkit", "overdraw", "acmr_fifo16"), "meshopt_acmr16": get(n, "meshopt", "overdraw", "acmr_fifo16"),
            "lodkit_s": get(n, "lodkit", "overdraw", "median_s"), "meshopt_s": get(n, "meshopt", "overdraw", "median_s"),
        }
    print("### Overdraw (shaded ÷ covered pixels, 14 orthographic views, lodkit's analyzer; [meshoptimizer's analyzer]; "
          "overdraw order = cache order (FIFO 16) then the overdraw pass at threshold 1.05)")
    print()
    print("| input | lodkit cache order | lodkit overdraw order | meshopt cache order | meshopt overdraw order | "
          "ACMR 16 after, lodkit / meshopt | time (both passes) lodkit / meshopt ms |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    overdraw_summary = {}
    overdraw_rows = [("corpus (geometric mean)", [c for c in cases if c["group"] == "corpus"])] + \
                    [(c["name"], [c]) for c in cases if c["group"] == "big"]
    for label, group in overdraw_rows:
        g = {k: geomean([c["overdraw"][k] for c in group]) for k in group[0]["overdraw"]} if group else {}
        if label.startswith("corpus"):
            overdraw_summary = g
        print(f"| {label} | {fmt(g.get('lodkit_cache'))} | {fmt(g.get('lodkit'))} [{fmt(g.get('lodkit_meshopt_analyzer'))}] | "
              f"{fmt(g.get('meshopt_cache'))} | {fmt(g.get('meshopt'))} [{fmt(g.get('meshopt_meshopt_analyzer'))}] | "
              f"{fmt(g.get('lodkit_acmr16'))} / {fmt(g.get('meshopt_acmr16'))} | {ms(g.get('lodkit_s'))} / {ms(g.get('meshopt_s'))} |")
    at_or_below = sum(1 for c in cases if c["group"] == "corpus" and c["overdraw"]["lodkit"] is not None and c["overdraw"]["meshopt"] is not None
                      and c["overdraw"]["lodkit"] <= c["overdraw"]["meshopt"] + 1e-12)
    print()
    print(f"lodkit's overdraw order at or below meshoptimizer's on {at_or_below}/{len([c for c in cases if c['group'] == 'corpus'])} "
          f"corpus meshes (lodkit's analyzer); times of corpus meshes are geometric means")
    print()

    # ---- summary and targets -----------------------------------------------------------------------
    corpus_cases = [c for c in cases if c["group"] == "corpus"]
    summary = {"machine": machine, "runs": int(runs_asked), "corpus_meshes": len(corpus_cases), "failed_runs": len(failed),
               "overdraw": overdraw_summary}
    print("### Summary (geometric means over the corpus)")
    print()
    print("| quantity | lodkit | meshoptimizer | ratio |")
    print("|---|---:|---:|---:|")
    for label, a, b in (("ACMR FIFO 16", "lodkit_acmr16", "meshopt_acmr16"), ("ACMR FIFO 32", "lodkit_acmr32", "meshopt_acmr32"),
                        ("ATVR FIFO 16", "lodkit_atvr16", "meshopt_atvr16"), ("ATVR FIFO 32", "lodkit_atvr32", "meshopt_atvr32"),
                        ("strip indices/triangle, degenerate", "lodkit_ipt_degenerate", "meshopt_ipt_degenerate"),
                        ("strip indices/triangle, restart", "lodkit_ipt_restart", "meshopt_ipt_restart")):
        ga, gb = geomean([c[a] for c in corpus_cases]), geomean([c[b] for c in corpus_cases])
        summary[label] = {"lodkit": ga, "meshopt": gb}
        print(f"| {label} | {fmt(ga)} | {fmt(gb)} | {fmt(ga / gb if ga and gb else None)} |")
    sgi = geomean([c["sgi_ipt_restart"] for c in corpus_cases])
    print(f"| SGI strip indices/triangle, restart (baseline) | {fmt(sgi)} | | |")
    print()

    ok = True

    def target(label, values, limit, what):
        nonlocal ok
        values = [(n, v) for n, v in values if v is not None]
        if not values:
            print(f"- {label}: NO DATA")
            ok = False
            return
        bad = [(n, v) for n, v in values if v > limit + 1e-12]
        worst = max(values, key=lambda x: x[1])
        verdict = "PASS" if not bad else "FAIL"
        print(f"- {label}: **{verdict}** — {len(values) - len(bad)}/{len(values)} {what}; worst {worst[0]} at {worst[1]:.4f}"
              + (f"; over: {', '.join(f'{n} {v:.4f}' for n, v in bad[:8])}{' …' if len(bad) > 8 else ''}" if bad else ""))
        summary.setdefault("targets", {})[label] = {"pass": not bad, "worst": worst, "over": bad}

    print("### Targets (issue 5)")
    print()
    for k in (16, 32):
        target(f"ACMR FIFO {k} ≤ meshoptimizer on every corpus mesh", [(c["name"], c[f"acmr_ratio{k}"]) for c in corpus_cases], 1.0,
               "meshes at or below")
    timed = [c for c in cases if c["triangles"] >= TIME_MIN_TRIANGLES]
    target(f"vertex-cache time ≤ 2× meshoptimizer (inputs ≥ {TIME_MIN_TRIANGLES:,} triangles, slower of lodkit's 16 and 32, medians)",
           [(c["name"], c["time_ratio"]) for c in timed], 2.0, "inputs within")
    fastest = [c["time_ratio_min"] for c in timed if c["time_ratio_min"] is not None]
    if fastest:
        print(f"  (the same from each process's fastest run: worst {max(fastest):.2f}, "
              f"{sum(1 for r in fastest if r <= 2.0)}/{len(fastest)} within 2×)")
    # The rest of the corpus: microseconds per run, where lodkit's fixed per-call cost shows.
    small = [c for c in corpus_cases if c["triangles"] < TIME_MIN_TRIANGLES]
    target(f"vertex-cache time ≤ 2× meshoptimizer (corpus inputs < {TIME_MIN_TRIANGLES:,} triangles, slower of lodkit's 16 and 32, medians)",
           [(c["name"], c["time_ratio"]) for c in small], 2.0, "inputs within")
    for label, key in (("medians", "time_ratio"), ("fastest runs", "time_ratio_min")):
        ratios = sorted(c[key] for c in small if c[key] is not None)
        if ratios:
            print(f"  (per-mesh time ratio over these {len(ratios)} inputs, {label}: "
                  f"median {statistics.median(ratios):.2f}, worst {ratios[-1]:.2f}, {sum(1 for r in ratios if r <= 2.0)} within 2×)")
            summary.setdefault("small_time_ratio", {})[label] = {"median": statistics.median(ratios), "worst": ratios[-1]}
    total_l = sum(max(c["lodkit_s16"] or 0, c["lodkit_s32"] or 0) for c in corpus_cases)
    total_m = sum(c["meshopt_s"] or 0 for c in corpus_cases)
    if total_m:
        print(f"  (whole corpus: lodkit {total_l * 1e3:.1f} ms against meshoptimizer {total_m * 1e3:.1f} ms, ratio {total_l / total_m:.2f})")
        summary["corpus_time_ratio"] = total_l / total_m
    for join in ("degenerate", "restart"):
        target(f"strip indices per triangle ≤ meshoptimizer on every corpus mesh ({join} joins)",
               [(c["name"], c[f"strip_ratio_{join}"]) for c in corpus_cases], 1.0, "meshes at or below")
    worse = sum(1 for c in corpus_cases if (c["sgi_ipt_restart"] or 0) > (c["lodkit_ipt_restart"] or 0))
    print(f"- SGI baseline: more indices than lodkit best on {worse}/{len(corpus_cases)} corpus meshes (restart joins); "
          f"geometric mean {fmt(sgi)} against {fmt(summary['strip indices/triangle, restart']['lodkit'])}")
    if failed:
        print(f"- failed runs: {len(failed)}: " + "; ".join(f"{r['name']} {r['tool']} {r['op']}: {r['failed']}" for r in failed[:5]))
        ok = False
    json.dump({"summary": summary, "cases": cases, "records": list(runs.values())}, open(summary_path, "w"), indent=1)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
