"""Turns the JSON lines of `lodkit_bench_io load ... --json` (plus peak_mib) into the markdown table
scripts/bench.sh prints, and writes bench/results/io.json. Exits 1 when a row is missing."""
import json
import sys

rows = [json.loads(line) for line in sys.stdin if line.strip()]
by = {(r["file"], r["loader"]): r for r in rows}
print("| format | triangles | lodkit median s | assimp median s | ratio lodkit/assimp | lodkit peak MiB | assimp peak MiB |")
print("|---|---|---|---|---|---|---|")
ok = True
out = []
for f in sorted({r["file"] for r in rows}, key=lambda f: f.endswith(".obj")):
    lod, peer = by.get((f, "lodkit")), by.get((f, "assimp"))
    fmt = f.rsplit(".", 1)[1].upper()
    if not lod or not peer:
        print(f"| {fmt} | failed | | | | | |")
        ok = False
        continue
    if lod["triangles"] != peer["triangles"]:
        print(f"warning: {fmt}: lodkit loaded {lod['triangles']} triangles, assimp {peer['triangles']}", file=sys.stderr)
    ratio = lod["median_s"] / peer["median_s"]
    print(f"| {fmt} | {lod['triangles']:,} | {lod['median_s']:.3f} | {peer['median_s']:.3f} | {ratio:.2f} "
          f"| {lod['peak_mib']:.0f} | {peer['peak_mib']:.0f} |")
    out.append({"format": fmt, "file": f, "ratio": ratio, "lodkit": lod, "assimp": peer})
with open(sys.argv[1], "w") as fh:
    json.dump(out, fh, indent=2)
print(f"\ntarget: ratio <= 0.30 for both formats; results in {sys.argv[1]}")
sys.exit(0 if ok and len(out) == 2 else 1)
