#!/usr/bin/env python3
"""`lodkit lod` on a forest: one mesh drawn many times, as GPU instances against as plain nodes.

usage: instanced.py LODKIT OUT.json [--runs N] [--trees N] [--out DIR]

The forest is written here, without lodkit: a torus of 64 x 32 quads (4,096 triangles) on a grid of
N trees (default 100), each turned and scaled a little. Two files describe the same scene:
  - instanced.glb: one node with EXT_mesh_gpu_instancing (gltfpack -mi's form), which `lodkit lod`
    gives a chain of its own, built once in the torus's space;
  - nodes.glb: N plain nodes drawing the torus, which `lodkit lod` flattens into one world-space
    chain (what it did with instances too before they had their own chain).
Per file: the median wall time of N runs of `lodkit lod IN -o OUT --json`, the peak RSS
(/usr/bin/time -v), the output's size, each level's triangles (per tree for the instanced chain),
and a check that level 0 draws the input (`lodkit compare` of input and output, symmetric
Hausdorff over the diagonal, must be below 1e-5).
"""
import json
import math
import os
import statistics
import struct
import subprocess

from common import GlbBuilder, main, run_lod


def torus(segments=64, sides=32, major=1.0, minor=0.3):
    positions, indices = [], []
    for i in range(segments):
        a = 2 * math.pi * i / segments
        for j in range(sides):
            b = 2 * math.pi * j / sides
            r = major + minor * math.cos(b)
            positions.append((r * math.cos(a), r * math.sin(a), minor * math.sin(b)))
    for i in range(segments):
        for j in range(sides):
            v00 = i * sides + j
            v10 = ((i + 1) % segments) * sides + j
            v01 = i * sides + (j + 1) % sides
            v11 = ((i + 1) % segments) * sides + (j + 1) % sides
            indices += [v00, v10, v11, v00, v11, v01]
    return positions, indices


def write_glb(path, instanced, trees):
    positions, indices = torus()
    side = math.ceil(math.sqrt(trees))
    places = []
    for k in range(trees):
        angle = 0.37 * k
        places.append((((k % side) * 3.0, (k // side) * 3.0, 0.0),
                       (0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)), 1.0 + 0.002 * (k % 50)))
    glb = GlbBuilder()
    accessor = glb.accessor

    lo = [min(p[c] for p in positions) for c in range(3)]
    hi = [max(p[c] for p in positions) for c in range(3)]
    pos = accessor(b"".join(struct.pack("<3f", *p) for p in positions), len(positions), "VEC3", 5126, 34962, (lo, hi))
    idx = accessor(struct.pack(f"<{len(indices)}I", *indices), len(indices), "SCALAR", 5125, 34963)
    doc = {"asset": {"version": "2.0", "generator": "bench/lod/instanced.py"},
           "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}]}
    if instanced:
        t = accessor(b"".join(struct.pack("<3f", *p[0]) for p in places), trees, "VEC3", 5126)
        r = accessor(b"".join(struct.pack("<4f", *p[1]) for p in places), trees, "VEC4", 5126)
        s = accessor(b"".join(struct.pack("<3f", p[2], p[2], p[2]) for p in places), trees, "VEC3", 5126)
        doc["nodes"] = [{"name": "trees", "mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {
            "attributes": {"TRANSLATION": t, "ROTATION": r, "SCALE": s}}}}]
        doc["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
    else:
        doc["nodes"] = [{"name": f"tree{k}", "mesh": 0, "translation": list(p[0]), "rotation": list(p[1]),
                         "scale": [p[2]] * 3} for k, p in enumerate(places)]
    doc["scenes"] = [{"nodes": list(range(len(doc["nodes"])))}]
    doc["scene"] = 0
    glb.write(path, doc)


def lod(lodkit, src, out):
    return run_lod(lodkit, src, out)


def run(lodkit, out_json, runs, trees, tmp):
    rows = {}
    for name, instanced in (("instanced", True), ("nodes", False)):
        src = os.path.join(tmp, f"{name}.glb")
        out = os.path.join(tmp, f"{name}-lod.glb")
        write_glb(src, instanced, trees)
        results = [lod(lodkit, src, out) for _ in range(runs)]
        report = results[-1][2]
        chain = report["instanced"][0] if report.get("instanced") else report
        compare = json.loads(subprocess.run([lodkit, "compare", src, out, "--json"], capture_output=True, text=True,
                                            check=True).stdout)
        h = max(compare["a_to_b"]["relative_hausdorff"], compare["b_to_a"]["relative_hausdorff"])
        rows[name] = {"input_bytes": os.path.getsize(src), "seconds": statistics.median(r[0] for r in results),
                      "peak_rss_mib": statistics.median(r[1] for r in results), "output_bytes": os.path.getsize(out),
                      "levels": [l["triangles"] for l in chain["levels"]], "level0_hausdorff": h}
    print(f"## lod on a forest of {trees} tori (4,096 triangles each), medians of {runs}")
    print()
    print("| input | lodkit lod s | peak RSS MiB | output KiB | level triangles | level 0 vs input (Hausdorff / diag) |")
    print("|---|---|---|---|---|---|")
    for name, r in rows.items():
        levels = " / ".join(f"{t:,}" for t in r["levels"]) + (" per tree" if name == "instanced" else "")
        print(f"| {name} | {r['seconds']:.3f} | {r['peak_rss_mib']:.0f} | {r['output_bytes'] / 1024:,.0f} | {levels} | "
              f"{r['level0_hausdorff']:.1e} |")
    a, b = rows["instanced"], rows["nodes"]
    print()
    print(f"instanced / nodes: time {a['seconds'] / b['seconds']:.3f}x, peak RSS {a['peak_rss_mib'] / b['peak_rss_mib']:.3f}x, "
          f"output {a['output_bytes'] / b['output_bytes']:.3f}x")
    ok = all(r["level0_hausdorff"] < 1e-5 for r in rows.values())
    print(f"level 0 draws the input: {'PASS' if ok else 'FAIL'}")
    json.dump({"trees": trees, "runs": runs, "rows": rows}, open(out_json, "w"), indent=2)
    return ok


if __name__ == "__main__":
    main(__doc__, lambda lodkit, out_json, o, tmp: run(lodkit, out_json, o["runs"], o["trees"], tmp), {"runs": 3, "trees": 100})
