"""Turns the JSON lines of `lodkit_bench_io load ... --json` (plus peak_mib) into the markdown table
scripts/bench.sh prints, and writes bench/results/io.json.

  report.py OUT.json MACHINE RUNS FILE... < json-lines

Every FILE gets a row; a file whose lodkit or Assimp line is missing (the load failed) is marked
failed. Exits 1 when any ratio is missing or the two loaders disagree on the triangle count."""
import datetime
import json
import sys

out_path, machine, runs, files = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:]
rows = [json.loads(line) for line in sys.stdin if line.strip()]
by = {(r["file"], r["loader"]): r for r in rows}
print("| format | triangles | lodkit median s | assimp median s | ratio lodkit/assimp | lodkit peak MiB | assimp peak MiB |")
print("|---|---|---|---|---|---|---|")
ok = True
out = []
for f in files:
    lod, peer = by.get((f, "lodkit")), by.get((f, "assimp"))
    fmt = f.rsplit(".", 1)[1].upper()
    if not lod or not peer:
        failed = " and ".join(name for name, r in (("lodkit", lod), ("assimp", peer)) if not r)
        median = lambda r: f"{r['median_s']:.3f}" if r else "-"
        peak = lambda r: f"{r['peak_mib']:.0f}" if r else "-"
        print(f"| {fmt} | failed ({failed}) | {median(lod)} | {median(peer)} | - | {peak(lod)} | {peak(peer)} |")
        out.append({"format": fmt, "file": f, "failed": failed, "lodkit": lod, "assimp": peer})
        ok = False
        continue
    triangles = f"{lod['triangles']:,}"
    if lod["triangles"] != peer["triangles"]:
        # Not the same work: the ratio is printed but the run fails.
        triangles = f"MISMATCH lodkit {lod['triangles']:,} / assimp {peer['triangles']:,}"
        ok = False
    ratio = lod["median_s"] / peer["median_s"]
    print(f"| {fmt} | {triangles} | {lod['median_s']:.3f} | {peer['median_s']:.3f} | {ratio:.2f} "
          f"| {lod['peak_mib']:.0f} | {peer['peak_mib']:.0f} |")
    out.append({"format": fmt, "file": f, "ratio": ratio, "lodkit": lod, "assimp": peer})
with open(out_path, "w") as fh:
    json.dump({"machine": machine, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
               "runs": runs, "target_ratio": 0.30, "results": out}, fh, indent=2)
print(f"\ntarget: ratio <= 0.30 for both formats; results in {out_path}")
sys.exit(0 if ok else 1)
