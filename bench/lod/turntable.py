#!/usr/bin/env python3
"""`lodkit lod` on a turntable: meshes below one animated node, one chain for the rigid group against one per mesh.

usage: turntable.py LODKIT OUT.json [--runs N] [--corpus DIR] [--models a,b,...] [--out DIR]

The scene is written here, without lodkit: OFF meshes from the corpus (default bunny00, cow, elephant,
camel, bull, armadillo), each scaled to a unit bounding box (largest extent 1, min corner at 0), as the
children of a root node "turntable", placed in a ring of radius 2 by translation only. A clip "turn"
spins the root about z (keys at 0, 2 and 4 s: 0, pi and 2 pi). The children move together below the
one animated node and are drawn nowhere else, so `lodkit lod` makes them a rigid group: ONE chain for
all of them in the root's space (the report's "animated" entry, whose group_nodes must be the number
of meshes). Each mesh is also written alone, at the origin and without animation: its static chain is
the chain the mesh had of its own before rigid groups.

`lodkit lod IN -o OUT --ratios 1,0.1,0.01,0.002 --json` runs N times on the turntable (median wall
time, peak RSS by /usr/bin/time -v) and once more with -c -q; once on each single-mesh file, plain
and with -c -q. Per level, the table sets the group's triangles and measured Hausdorff error
("error", object units) against the per-mesh chains' summed triangles and largest error. The errors
are comparable because only translations place the meshes below the root. Level 0 must draw the
input: its triangles must equal the input's total and its error must be 0. Output sizes (file and
BIN chunk) and the index component types of the outputs are reported for both forms.
"""
import json
import math
import os
import statistics
import struct
import sys

from common import GlbBuilder, main, run_lod

RATIOS = "1,0.1,0.01,0.002"
MODELS = ["bunny00", "cow", "elephant", "camel", "bull", "armadillo"]
RADIUS = 2.0


def read_off(path):
    """Vertices (x, y, z) and triangles (polygons as fans) of an ASCII OFF file; '#' comments skipped,
    headers OFF, COFF, NOFF, CNOFF, STOFF... accepted (extra per-vertex values ignored)."""
    lines = []
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].split()
            if line:
                lines.append(line)
    header = lines[0][0] if lines else ""
    if not header.endswith("OFF") or header.startswith("4") or header.startswith("n"):
        raise ValueError(f"{path}: not a 3D ASCII OFF file (header {header!r})")
    rest = lines[0][1:]
    at = 1
    if not rest:
        rest, at = lines[1], 2
    nv, nf = int(rest[0]), int(rest[1])
    positions = []
    for line in lines[at:at + nv]:
        positions.append(tuple(float(x) for x in line[:3]))
    at += nv
    triangles = []
    for line in lines[at:at + nf]:
        n = int(line[0])
        ids = [int(x) for x in line[1:1 + n]]
        if len(ids) != n or any(i < 0 or i >= nv for i in ids):
            raise ValueError(f"{path}: bad face {' '.join(line)}")
        for k in range(1, n - 1):
            triangles.append((ids[0], ids[k], ids[k + 1]))
    if len(positions) != nv or len(lines) < at + nf:
        raise ValueError(f"{path}: file ends early")
    return positions, triangles


def unit_box(positions):
    lo = [min(p[c] for p in positions) for c in range(3)]
    hi = [max(p[c] for p in positions) for c in range(3)]
    s = 1.0 / max(h - l for h, l in zip(hi, lo))
    return [tuple((p[c] - lo[c]) * s for c in range(3)) for p in positions]


def write_glb(path, meshes, turntable):
    """meshes: [(name, positions, triangles)]. turntable: the ring below an animated root; else the
    first mesh alone at the origin, without animation."""
    glb = GlbBuilder()
    accessor = glb.accessor

    doc = {"asset": {"version": "2.0", "generator": "bench/lod/turntable.py"}, "meshes": []}
    for name, positions, triangles in meshes:
        bounds = ([min(p[c] for p in positions) for c in range(3)], [max(p[c] for p in positions) for c in range(3)])
        pos = accessor(b"".join(struct.pack("<3f", *p) for p in positions), len(positions), "VEC3", 5126, 34962, bounds)
        flat = [i for t in triangles for i in t]
        idx = accessor(struct.pack(f"<{len(flat)}I", *flat), len(flat), "SCALAR", 5125, 34963)
        doc["meshes"].append({"name": name, "primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]})
    if turntable:
        doc["nodes"] = [{"name": "turntable", "children": list(range(1, len(meshes) + 1))}]
        for k, (name, _, _) in enumerate(meshes):
            a = 2 * math.pi * k / len(meshes)
            doc["nodes"].append({"name": name, "mesh": k, "translation": [RADIUS * math.cos(a), RADIUS * math.sin(a), 0.0]})
        times = accessor(struct.pack("<3f", 0.0, 2.0, 4.0), 3, "SCALAR", 5126, bounds=([0.0], [4.0]))
        turns = accessor(b"".join(struct.pack("<4f", 0.0, 0.0, math.sin(a / 2), math.cos(a / 2))
                                  for a in (0.0, math.pi, 2 * math.pi)), 3, "VEC4", 5126)
        doc["animations"] = [{"name": "turn", "samplers": [{"input": times, "output": turns}],
                              "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}]}]
    else:
        doc["nodes"] = [{"name": meshes[0][0], "mesh": 0}]
    doc["scenes"] = [{"nodes": [0]}]
    doc["scene"] = 0
    glb.write(path, doc)


def glb_facts(path):
    """File size, BIN chunk size and the component types of the index accessors of a .glb."""
    data = open(path, "rb").read()
    json_len = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + json_len])
    bin_len = struct.unpack_from("<I", data, 20 + json_len)[0] if len(data) > 20 + json_len else 0
    kinds = {5121: "u8", 5123: "u16", 5125: "u32"}
    index_types = [kinds[doc["accessors"][p["indices"]]["componentType"]]
                   for m in doc.get("meshes", []) for p in m["primitives"] if "indices" in p]
    return {"bytes": len(data), "bin_bytes": bin_len, "index_types": index_types}


def lod(lodkit, src, out, extra=()):
    return run_lod(lodkit, src, out, ("--ratios", RATIOS, *extra))


def count_types(types):
    return ", ".join(f"{types.count(t)} {t}" for t in ("u8", "u16", "u32") if t in types)


def run(lodkit, out_json, runs, corpus, models, tmp):
    meshes = []
    for name in models:
        positions, triangles = read_off(os.path.join(corpus, f"{name}.off"))
        meshes.append((name, unit_box(positions), triangles))
    input_triangles = sum(len(m[2]) for m in meshes)
    src = os.path.join(tmp, "turntable.glb")
    write_glb(src, meshes, True)

    out = os.path.join(tmp, "turntable-lod.glb")
    results = [lod(lodkit, src, out) for _ in range(runs)]
    report = results[-1][2]
    animated = report.get("animated") or []
    if len(animated) != 1 or animated[0].get("group_nodes") != len(meshes):
        sys.exit(f"turntable.py: expected one rigid group of {len(meshes)} nodes in the report's 'animated', got "
                 f"{[(a.get('node'), a.get('group_nodes')) for a in animated]}")
    group = animated[0]
    out_cq = os.path.join(tmp, "turntable-lod-cq.glb")
    cq = lod(lodkit, src, out_cq, ("-c", "-q"))
    group_cq = (cq[2].get("animated") or [{}])[0]

    singles = []
    for name, positions, triangles in meshes:
        one = os.path.join(tmp, f"{name}.glb")
        write_glb(one, [(name, positions, triangles)], False)
        plain = lod(lodkit, one, os.path.join(tmp, f"{name}-lod.glb"))
        comp = lod(lodkit, one, os.path.join(tmp, f"{name}-lod-cq.glb"), ("-c", "-q"))
        if plain[2]["levels"][0]["triangles"] != len(triangles):
            sys.exit(f"turntable.py: {name}'s level 0 has {plain[2]['levels'][0]['triangles']} triangles, "
                     f"the input {len(triangles)}")
        singles.append({"name": name, "input_triangles": len(triangles), "seconds": plain[0], "peak_rss_mib": plain[1],
                        "levels": plain[2]["levels"], "output": glb_facts(os.path.join(tmp, f"{name}-lod.glb")),
                        "output_cq": glb_facts(os.path.join(tmp, f"{name}-lod-cq.glb"))})

    levels = []
    for k, g in enumerate(group["levels"]):
        per = [s["levels"][k] for s in singles]
        worst = max(per, key=lambda l: l["error"])
        pm_error = worst["error"]
        levels.append({"level": k, "group_triangles": g["triangles"], "group_vertices": g["vertices"],
                       "group_error": g["error"], "per_mesh_triangles": sum(l["triangles"] for l in per),
                       "per_mesh_vertices": sum(l["vertices"] for l in per),
                       "per_mesh_largest_vertices": max(l["vertices"] for l in per),
                       "per_mesh_max_error": pm_error,
                       "per_mesh_max_error_model": singles[per.index(worst)]["name"],
                       "error_ratio": g["error"] / pm_error if pm_error > 0 else None})
    level0_ok = levels[0]["group_triangles"] == input_triangles and levels[0]["group_error"] == 0
    sizes = {"group": glb_facts(out), "group_cq": glb_facts(out_cq),
             "per_mesh": {key: sum(s["output"][key] for s in singles) for key in ("bytes", "bin_bytes")},
             "per_mesh_cq": {key: sum(s["output_cq"][key] for s in singles) for key in ("bytes", "bin_bytes")}}
    sizes["per_mesh"]["index_types"] = [t for s in singles for t in s["output"]["index_types"]]
    sizes["per_mesh_cq"]["index_types"] = [t for s in singles for t in s["output_cq"]["index_types"]]
    timing = {"group_seconds": statistics.median(r[0] for r in results),
              "group_peak_rss_mib": statistics.median(r[1] for r in results),
              "per_mesh_seconds_sum": sum(s["seconds"] for s in singles),
              "per_mesh_peak_rss_mib_max": max(s["peak_rss_mib"] for s in singles)}

    print(f"## lod on a turntable of {len(meshes)} corpus meshes ({input_triangles:,} triangles), ratios {RATIOS}")
    print()
    print(f"rigid group below node {group['node']!r}: {group['group_nodes']} nodes, one chain "
          f"(the per-mesh chains: each mesh alone at the origin, static)")
    print()
    print("| level | group triangles | per-mesh triangles (sum) | group vertices | per-mesh vertices (sum / largest) "
          "| group error | per-mesh max error | group / per-mesh |")
    print("|---|---|---|---|---|---|---|---|")
    for l in levels:
        ratio = f"{l['error_ratio']:.2f}" if l["error_ratio"] is not None else "-"
        model = f" ({l['per_mesh_max_error_model']})" if l["per_mesh_max_error"] > 0 else ""
        print(f"| {l['level']} | {l['group_triangles']:,} | {l['per_mesh_triangles']:,} | {l['group_vertices']:,} | "
              f"{l['per_mesh_vertices']:,} / {l['per_mesh_largest_vertices']:,} | {l['group_error']:.3g} | "
              f"{l['per_mesh_max_error']:.3g}{model} | {ratio} |")
    print()
    print("| output | bytes | BIN bytes | -c -q bytes | -c -q BIN bytes | index types (plain) |")
    print("|---|---|---|---|---|---|")
    for label, a, b in (("turntable, one group chain", sizes["group"], sizes["group_cq"]),
                        (f"{len(singles)} single-mesh files, summed", sizes["per_mesh"], sizes["per_mesh_cq"])):
        print(f"| {label} | {a['bytes']:,} | {a['bin_bytes']:,} | {b['bytes']:,} | {b['bin_bytes']:,} | "
              f"{count_types(a['index_types'])} |")
    print()
    print(f"group / per-mesh BIN bytes: plain {sizes['group']['bin_bytes'] / sizes['per_mesh']['bin_bytes']:.3f}x, "
          f"-c -q {sizes['group_cq']['bin_bytes'] / sizes['per_mesh_cq']['bin_bytes']:.3f}x")
    print(f"turntable: lodkit lod {timing['group_seconds']:.2f} s (median of {runs}), peak RSS "
          f"{timing['group_peak_rss_mib']:.0f} MiB; single-mesh files: {timing['per_mesh_seconds_sum']:.2f} s summed "
          f"(one run each), peak RSS up to {timing['per_mesh_peak_rss_mib_max']:.0f} MiB")
    print(f"level 0 draws the input ({input_triangles:,} triangles, error 0): {'PASS' if level0_ok else 'FAIL'}")
    json.dump({"models": models, "ratios": RATIOS, "runs": runs, "input_triangles": input_triangles,
               "group": {"node": group["node"], "group_nodes": group["group_nodes"], "levels": group["levels"],
                         "levels_cq": group_cq.get("levels")},
               "levels": levels, "sizes": sizes, "timing": timing, "singles": singles, "level0_ok": level0_ok},
              open(out_json, "w"), indent=2)
    return level0_ok


if __name__ == "__main__":
    main(__doc__, lambda lodkit, out_json, o, tmp: run(lodkit, out_json, o["runs"], o["corpus"], o["models"].split(","), tmp),
         {"runs": 3, "corpus": os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "data", "corpus"),
          "models": ",".join(MODELS)})
