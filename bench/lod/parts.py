#!/usr/bin/env python3
"""`lodkit lod` and `lodkit simplify` on many small animated meshes, side by side: one thread against all.

usage: parts.py LODKIT OUT.json [--runs N] [--meshes N] [--out DIR]

The scene is written here, without lodkit: N small meshes (default 200), mesh k a height field of
12 x 12 quads (288 triangles) over x, y in [0, 1] with z = 0.2 sin(3x + k) cos(2y), each drawn by a
node of its own on a grid 20 wide at spacing 2. One clip "spin" turns every node about z (one
channel per node, keys at 0, 1 and 2 s: 0, pi and 2 pi). A mesh drawn by an animated node gets a
chain of its own in `lodkit lod` (the report's "animated" entries, which must number N), and the
small chains are built side by side, one thread each (lod::build_lod_chains).

`lodkit lod IN -o OUT --json --threads T` runs N times for T = 1 and T = 0 (all cores), the two
settings alternating run by run: the median wall time, the median of the report's build_seconds,
the peak RSS (/usr/bin/time -v, median) and the output's size; and the ratio of the one-thread
time to the all-threads time. Every run's output must be byte-identical to the first (so both
settings write the same file). --out DIR keeps the input and outputs there (else a temporary
directory).

Then `lodkit simplify IN -o OUT --ratio 0.1 --json --threads T` the same way: every mesh simplified
on its own, in one batch, side by side (lod::simplify_batch); the median wall time and
simplify_seconds, peak RSS, output triangles, and the ratio; its outputs must be byte-identical too.
"""
import json
import math
import os
import statistics
import struct
import sys

from common import GlbBuilder, main, run_lod

GRID = 12  # quads per side
ROW = 20  # nodes per row
SPACING = 2.0
SETTINGS = ("1", "0")  # --threads: one, all


def height_field(k):
    positions = []
    for j in range(GRID + 1):
        for i in range(GRID + 1):
            x, y = i / GRID, j / GRID
            positions.append((x, y, 0.2 * math.sin(3 * x + k) * math.cos(2 * y)))
    indices = []
    for j in range(GRID):
        for i in range(GRID):
            v00 = j * (GRID + 1) + i
            v10, v01, v11 = v00 + 1, v00 + GRID + 1, v00 + GRID + 2
            indices += [v00, v10, v11, v00, v11, v01]
    return positions, indices


def write_glb(path, meshes):
    glb = GlbBuilder()
    accessor = glb.accessor

    doc = {"asset": {"version": "2.0", "generator": "bench/lod/parts.py"}, "meshes": [], "nodes": []}
    for k in range(meshes):
        positions, indices = height_field(k)
        bounds = ([min(p[c] for p in positions) for c in range(3)], [max(p[c] for p in positions) for c in range(3)])
        pos = accessor(b"".join(struct.pack("<3f", *p) for p in positions), len(positions), "VEC3", 5126, 34962, bounds)
        idx = accessor(struct.pack(f"<{len(indices)}I", *indices), len(indices), "SCALAR", 5125, 34963)
        doc["meshes"].append({"name": f"part{k}", "primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]})
        doc["nodes"].append({"name": f"part{k}", "mesh": k,
                             "translation": [(k % ROW) * SPACING, (k // ROW) * SPACING, 0.0]})
    times = accessor(struct.pack("<3f", 0.0, 1.0, 2.0), 3, "SCALAR", 5126, bounds=([0.0], [2.0]))
    turns = accessor(b"".join(struct.pack("<4f", 0.0, 0.0, math.sin(a / 2), math.cos(a / 2))
                              for a in (0.0, math.pi, 2 * math.pi)), 3, "VEC4", 5126)
    doc["animations"] = [{"name": "spin", "samplers": [{"input": times, "output": turns}] * meshes,
                          "channels": [{"sampler": k, "target": {"node": k, "path": "rotation"}} for k in range(meshes)]}]
    doc["scenes"] = [{"nodes": list(range(meshes))}]
    doc["scene"] = 0
    glb.write(path, doc)


def simplify_rows(lodkit, src, runs, tmp):
    """`lodkit simplify SRC --ratio 0.1` RUNS times per setting, alternating: per setting, medians;
    and whether every output is byte-identical to the first."""
    results = {t: [] for t in SETTINGS}
    first, identical = None, True
    for r in range(runs):
        for t in SETTINGS:
            out = os.path.join(tmp, f"parts-simplified-threads{t}.glb")
            wall, rss, report = run_lod(lodkit, src, out, ("--ratio", "0.1", "--threads", t), command="simplify")
            data = open(out, "rb").read()
            if first is None:
                first = data
            elif data != first:
                identical = False
                print(f"parts.py: simplify run {r + 1} with --threads {t} wrote a file unlike the first run's", file=sys.stderr)
            results[t].append((wall, rss, report))
    rows = {t: {"seconds": statistics.median(r[0] for r in rs),
                "simplify_seconds": statistics.median(r[2]["simplify_seconds"] for r in rs),
                "peak_rss_mib": statistics.median(r[1] for r in rs),
                "output_triangles": rs[-1][2]["output_triangles"]} for t, rs in results.items()}
    return rows, identical


def run(lodkit, out_json, runs, meshes, tmp):
    src = os.path.join(tmp, "parts.glb")
    write_glb(src, meshes)
    triangles = 2 * GRID * GRID
    results = {t: [] for t in SETTINGS}
    first = None
    identical = True
    for r in range(runs):
        for t in SETTINGS:
            out = os.path.join(tmp, f"parts-lod-threads{t}.glb")
            wall, rss, report = run_lod(lodkit, src, out, ("--threads", t))
            data = open(out, "rb").read()
            if first is None:
                first = data
            elif data != first:
                identical = False
                print(f"parts.py: run {r + 1} with --threads {t} wrote a file unlike the first run's "
                      f"({len(data):,} bytes against {len(first):,})", file=sys.stderr)
            results[t].append((wall, rss, report))

    rows = {}
    for t, rs in results.items():
        report = rs[-1][2]
        animated = report.get("animated") or []
        level_sums = [sum(c["levels"][i]["triangles"] for c in animated) for i in range(len(animated[0]["levels"]))] \
            if animated else []
        rows[t] = {"seconds": statistics.median(r[0] for r in rs),
                   "build_seconds": statistics.median(r[2]["build_seconds"] for r in rs),
                   "peak_rss_mib": statistics.median(r[1] for r in rs),
                   "output_bytes": os.path.getsize(os.path.join(tmp, f"parts-lod-threads{t}.glb")),
                   "animated_chains": len(animated), "level_triangles": level_sums,
                   "all_seconds": [r[0] for r in rs], "all_build_seconds": [r[2]["build_seconds"] for r in rs]}
    simplified, simplify_identical = simplify_rows(lodkit, src, runs, tmp)
    one, every = rows["1"], rows["0"]
    chains_ok = all(r["animated_chains"] == meshes for r in rows.values())
    level0_ok = all(r["level_triangles"][:1] == [meshes * triangles] for r in rows.values())

    print(f"## lod on {meshes} animated parts ({triangles} triangles each, {meshes * triangles:,} in all), "
          f"medians of {runs}")
    print()
    print("| threads | lodkit lod s | build_seconds | peak RSS MiB | output bytes | animated chains |")
    print("|---|---|---|---|---|---|")
    for t, label in (("1", "1"), ("0", f"0 (all: {os.cpu_count()})")):
        r = rows[t]
        print(f"| {label} | {r['seconds']:.3f} | {r['build_seconds']:.3f} | {r['peak_rss_mib']:.0f} | "
              f"{r['output_bytes']:,} | {r['animated_chains']} |")
    print()
    print(f"threads 1 / all threads: wall time {one['seconds'] / every['seconds']:.2f}x, "
          f"build_seconds {one['build_seconds'] / every['build_seconds']:.2f}x")
    print("level triangles, summed over the chains: " + " / ".join(f"{n:,}" for n in one["level_triangles"]))
    print(f"outputs byte-identical (every run, both settings): {'PASS' if identical else 'FAIL'}")
    print(f"{meshes} chains under \"animated\": {'PASS' if chains_ok else 'FAIL'}")
    print(f"level 0 draws the input ({meshes * triangles:,} triangles): {'PASS' if level0_ok else 'FAIL'}")
    print()
    print(f"## simplify --ratio 0.1 on the same scene, medians of {runs}")
    print()
    print("| threads | lodkit simplify s | simplify_seconds | peak RSS MiB | output triangles |")
    print("|---|---|---|---|---|")
    for t, label in (("1", "1"), ("0", f"0 (all: {os.cpu_count()})")):
        r = simplified[t]
        print(f"| {label} | {r['seconds']:.3f} | {r['simplify_seconds']:.3f} | {r['peak_rss_mib']:.0f} | {r['output_triangles']:,} |")
    print()
    print(f"threads 1 / all threads: wall time {simplified['1']['seconds'] / simplified['0']['seconds']:.2f}x, "
          f"simplify_seconds {simplified['1']['simplify_seconds'] / simplified['0']['simplify_seconds']:.2f}x")
    print(f"outputs byte-identical (every run, both settings): {'PASS' if simplify_identical else 'FAIL'}")
    json.dump({"meshes": meshes, "triangles_per_mesh": triangles, "runs": runs, "cores": os.cpu_count(),
               "rows": {f"threads_{t}": r for t, r in rows.items()},
               "ratio_seconds": one["seconds"] / every["seconds"],
               "ratio_build_seconds": one["build_seconds"] / every["build_seconds"],
               "identical": identical, "chains_ok": chains_ok, "level0_ok": level0_ok,
               "simplify": {"rows": {f"threads_{t}": r for t, r in simplified.items()}, "identical": simplify_identical}},
              open(out_json, "w"), indent=2)
    return identical and chains_ok and level0_ok and simplify_identical


if __name__ == "__main__":
    main(__doc__, lambda lodkit, out_json, o, tmp: run(lodkit, out_json, o["runs"], o["meshes"], tmp),
         {"runs": 3, "meshes": 200})
