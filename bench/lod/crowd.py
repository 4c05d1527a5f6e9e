#!/usr/bin/env python3
"""`lodkit lod` on a crowd: one skinned mesh drawn by N copies of its skeleton, in step.

usage: crowd.py LODKIT OUT.json [--runs N] [--sizes 1,2,4,...] [--out DIR]

The input is the humanoid that `lodkit_fixtures` writes (beside LODKIT in the build folder; 7,520
triangles, 19 joints, a walk and a wave). The crowd is made here, without lodkit: per extra member,
a copy of the skeleton below a node 1.5 further along x, a skin of its own over it (the same
inverse bind matrices) and a node drawing the one mesh with it; the clips drive each copy's joints
with the same samplers. Every member then takes each sampled pose moved as a whole, so the chain
must be the crowd of one's (lod::merge_rigid_poses counts such poses once).
Per size: the median wall time of N runs of `lodkit lod IN -o OUT --json --poses 8`, the peak RSS
(/usr/bin/time -v), both as ratios to the crowd of one (the peer run), and each level's triangles
and error, which must be the crowd of one's.
"""
import copy
import json
import os
import statistics
import struct
import subprocess

from common import main, run_lod


def read_glb(path):
    data = open(path, "rb").read()
    length = struct.unpack("<I", data[12:16])[0]
    return json.loads(data[20:20 + length]), data[20 + length:]


def write_glb(path, doc, rest):
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    with open(path, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + len(rest)))
        f.write(struct.pack("<II", len(text), 0x4E4F534A) + text + rest)


def crowd(doc, members):
    """The document with members - 1 more copies of skin 0's skeleton and drawing node."""
    doc = copy.deepcopy(doc)
    skin = doc["skins"][0]
    joints = skin["joints"]
    drawer = next(i for i, n in enumerate(doc["nodes"]) if n.get("skin") == 0)
    parent = {c: i for i, n in enumerate(doc["nodes"]) for c in n.get("children", [])}
    scene = doc["scenes"][doc.get("scene", 0)]
    for m in range(1, members):
        aside = len(doc["nodes"])
        doc["nodes"].append({"name": f"member{m}", "translation": [1.5 * m, 0, 0], "children": []})
        copy_of = {j: aside + 1 + k for k, j in enumerate(joints)}
        for j in joints:
            node = copy.deepcopy(doc["nodes"][j])
            node["name"] = f"member{m}_{node.get('name', '')}"
            if "children" in node:
                node["children"] = [copy_of[c] for c in node["children"]]
            doc["nodes"].append(node)
            if parent.get(j) not in copy_of:
                doc["nodes"][aside]["children"].append(copy_of[j])
        twin = dict(skin, joints=[copy_of[j] for j in joints])
        if "skeleton" in skin:
            twin["skeleton"] = copy_of[skin["skeleton"]]
        doc["skins"].append(twin)
        doc["nodes"].append({"name": f"member{m}_mesh", "mesh": doc["nodes"][drawer]["mesh"], "skin": len(doc["skins"]) - 1})
        scene["nodes"] += [aside, len(doc["nodes"]) - 1]
        for clip in doc.get("animations", []):
            clip["channels"] += [{"sampler": c["sampler"], "target": {"node": copy_of[c["target"]["node"]], "path": c["target"]["path"]}}
                                 for c in list(clip["channels"]) if c["target"].get("node") in copy_of]
    return doc


def run(lodkit, out_json, runs, sizes, tmp):
    fixtures = os.path.join(os.path.dirname(lodkit), "lodkit_fixtures")
    subprocess.run([fixtures, tmp], check=True, capture_output=True)
    doc, rest = read_glb(os.path.join(tmp, "humanoid.glb"))
    rows = []
    for members in sizes:
        src, out = os.path.join(tmp, f"crowd{members}.glb"), os.path.join(tmp, f"crowd{members}-lod.glb")
        write_glb(src, crowd(doc, members), rest)
        results = [run_lod(lodkit, src, out, ["--poses", "8"]) for _ in range(runs)]
        chain = results[-1][2]["skinned"]["chains"][0]
        rows.append({"members": members, "seconds": statistics.median(r[0] for r in results),
                     "peak_rss_mib": statistics.median(r[1] for r in results),
                     "levels": [(l["triangles"], l["error"]) for l in chain["levels"]]})
    one = rows[0]
    print(f"## lod on a crowd of humanoids in step (--poses 8), medians of {runs}")
    print()
    print("| members | lodkit lod s | ÷ one | peak RSS MiB | ÷ one | level triangles | chain as one's |")
    print("|---|---|---|---|---|---|---|")
    ok = True
    for r in rows:
        same = all(t == u and abs(e - f) <= 1e-6 * max(1.0, abs(f)) for (t, e), (u, f) in zip(r["levels"], one["levels"]))
        same = same and len(r["levels"]) == len(one["levels"])
        ok = ok and same
        print(f"| {r['members']} | {r['seconds']:.3f} | {r['seconds'] / one['seconds']:.2f}x | {r['peak_rss_mib']:.0f} | "
              f"{r['peak_rss_mib'] / one['peak_rss_mib']:.2f}x | {' / '.join(f'{t:,}' for t, _ in r['levels'])} | "
              f"{'yes' if same else 'NO'} |")
    print()
    print(f"every crowd's chain is the crowd of one's: {'PASS' if ok else 'FAIL'}")
    json.dump({"runs": runs, "rows": rows}, open(out_json, "w"), indent=2)
    return ok


if __name__ == "__main__":
    main(__doc__, lambda lodkit, out_json, o, tmp: run(lodkit, out_json, o["runs"], [int(s) for s in o["sizes"].split(",")], tmp),
         {"runs": 3, "sizes": "1,2,4,8,16,32"})
