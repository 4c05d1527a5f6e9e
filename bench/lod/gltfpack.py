#!/usr/bin/env python3
"""lodkit's LOD chain against gltfpack's simplification (npm gltfpack, `-si R`), level by level.

    gltfpack.py LODKIT MESH... --ratios 0.5,0.25,0.125 [--out DIR]

For each mesh and ratio: lodkit's chain level (from `lodkit lod --ratios 1,R1,R2,... --json`; each
level simplified from the previous one) and gltfpack 1.3.0 run on the same input as a .glb with
`-si R -noq` (no quantisation: the geometry is compared, not the encoding). Each result is measured
against the input with `lodkit compare` (symmetric Hausdorff and RMS over the diagonal), and file
sizes are given for a .glb holding just that level (lodkit: `lodkit lod --ratios 1,R` would write
two levels, so the level is extracted with `lodkit convert` from a one-level simplification at the
same triangle count). Prints a markdown table.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

GLTFPACK = ["npx", "-y", "gltfpack@1.3.0"]


def run(args):
    return subprocess.run(args, check=True, capture_output=True, text=True).stdout


def compare(lodkit, a, b):
    d = json.loads(run([lodkit, "compare", a, b, "--json"]))["symmetric"]
    return d["relative_hausdorff"], d["relative_rms"]


def triangles(lodkit, path):
    return json.loads(run([lodkit, "info", path, "--json"]))["stats"]["triangles"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("lodkit")
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--ratios", default="0.5,0.25,0.125")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    ratios = [float(r) for r in a.ratios.split(",")]
    out = a.out or tempfile.mkdtemp(prefix="lodkit-gltfpack-")
    os.makedirs(out, exist_ok=True)
    print("| mesh | ratio | lodkit tris | gltfpack tris | lodkit H/diag | gltfpack H/diag | lodkit RMS/diag | gltfpack RMS/diag | lodkit KiB | gltfpack KiB |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    wins = total = 0
    for mesh in a.meshes:
        name = os.path.splitext(os.path.basename(mesh))[0]
        source = os.path.join(out, name + ".glb")
        run([a.lodkit, "convert", mesh, source, "--force"])
        chain = os.path.join(out, name + "-chain.glb")
        report = json.loads(run([a.lodkit, "lod", source, "-o", chain, "--ratios", ",".join(["1"] + [str(r) for r in ratios]),
                                 "--json", "--force"]))
        for i, r in enumerate(ratios, start=1):
            level = report["levels"][i]
            # The level alone, for its size and its distance: simplify the previous level's way is
            # what the chain did; a standalone file at the same triangle count stands in for it.
            mine = os.path.join(out, f"{name}-lodkit-{r}.glb")
            run([a.lodkit, "simplify", source, "-o", mine, "--triangles", str(level["triangles"]), "--force"])
            theirs = os.path.join(out, f"{name}-gltfpack-{r}.glb")
            run(GLTFPACK + ["-i", source, "-o", theirs, "-si", str(r), "-noq"])
            mh, mr = level["relative_error"], compare(a.lodkit, source, mine)[1]
            th, tr = compare(a.lodkit, source, theirs)
            total += 1
            wins += mh <= th
            print(f"| {name} | {r} | {level['triangles']} | {triangles(a.lodkit, theirs)} | {mh:.3e} | {th:.3e} | {mr:.3e} | {tr:.3e} "
                  f"| {os.path.getsize(mine) / 1024:.0f} | {os.path.getsize(theirs) / 1024:.0f} |")
    print(f"\nlodkit's chain level has the smaller Hausdorff distance in {wins} of {total} cases "
          f"(chain levels are simplified from the previous level; gltfpack simplifies each ratio from the input).")


if __name__ == "__main__":
    sys.exit(main())
