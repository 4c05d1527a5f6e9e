"""Runs the optimize benchmark: lodkit and meshoptimizer on every corpus mesh and the 3.3M-triangle
input, one (tool, operation, input) per process under /usr/bin/time -v. scripts/bench.sh optimize
calls it; bench/optimize/report.py turns its output into tables.

  run.py BENCH_DIR LODKIT_CLI RESULTS.jsonl [--quick] [--runs N] [--no-big]

BENCH_DIR holds lodkit_bench_optimize. Each line of RESULTS.jsonl is one record:
  {"kind": "input", ...}  an input and its triangle count, or why it was skipped
  {"kind": "run", ...}    one process: the program's JSON line plus peak_mib, or "failed"
  {"kind": "note", ...}   anything the report should say
"""
import json
import os
import subprocess
import sys
import time

# Operations per tool. meshoptimizer's vertex-cache optimizer takes no cache size, so its one order
# is measured at FIFO 16 and 32 (the program reports both); its Tipsify (meshopt-fifo) is told the
# size and is shown for information. overdraw: the cache order then the overdraw order, both tools
# (information: the issue makes overdraw optional and sets no target).
JOBS = (
    ("lodkit", "vcache16"), ("lodkit", "vcache32"),
    ("meshopt", "vcache16"),
    ("meshopt-fifo", "vcache16"), ("meshopt-fifo", "vcache32"),
    ("lodkit", "strip"), ("lodkit", "strip-restart"),
    ("meshopt", "strip"), ("meshopt", "strip-restart"),
    ("lodkit", "sgi"), ("lodkit", "sgi-restart"),
    ("lodkit", "overdraw"), ("meshopt", "overdraw"),
)
BIG_BASE, BIG_LEVEL = "armadillo.off", 3     # 52,000 x 64 = 3,328,000 triangles
QUICK_MESHES = ("elephant.off", "fandisk.off", "bunny00.off")
MIN_SECONDS = 0.2                            # timed runs per process add up to at least this (max 1000 runs)
PROCESS_TIMEOUT = 600


def main():
    args = sys.argv[1:]
    quick = "--quick" in args
    no_big = "--no-big" in args or quick
    runs = 1 if quick else 5
    if "--runs" in args:
        runs = int(args[args.index("--runs") + 1])
    positional = [a for i, a in enumerate(args) if not a.startswith("--") and (i == 0 or args[i - 1] != "--runs")]
    bench_dir, lodkit_cli, out_path = positional
    os.makedirs(os.path.dirname(out_path) or ".", exist_ok=True)
    out = open(out_path, "w")
    program = os.path.join(bench_dir, "lodkit_bench_optimize")

    def emit(record):
        out.write(json.dumps(record) + "\n")
        out.flush()

    def note(text):
        print(f"bench: {text}", file=sys.stderr)
        emit({"kind": "note", "text": text})

    # ---- inputs -------------------------------------------------------------------------------------
    corpus = "data/corpus"
    names = sorted(f for f in os.listdir(corpus) if f.rsplit(".", 1)[-1].lower() in ("off", "ply", "stl", "obj"))
    if quick:
        names = [n for n in QUICK_MESHES if n in names]
    inputs = []
    for name in names:
        path = os.path.join(corpus, name)
        info = subprocess.run([lodkit_cli, "info", path, "--json"], capture_output=True, text=True)
        if info.returncode != 0:
            reason = (info.stderr.strip().splitlines() or ["unreadable"])[0]
            emit({"kind": "input", "name": name, "path": path, "skipped": f"cannot be read: {reason}"})
            continue
        triangles = json.loads(info.stdout)["stats"]["triangles"]
        if triangles == 0:
            emit({"kind": "input", "name": name, "path": path, "triangles": 0, "skipped": "no triangles"})
            continue
        emit({"kind": "input", "name": name, "path": path, "triangles": triangles, "group": "corpus"})
        inputs.append((name, path, triangles, "corpus"))
    if not no_big:
        big = f"build/bench-data/simplify/{BIG_BASE.rsplit('.', 1)[0]}-s{BIG_LEVEL}.ply"
        if not os.path.exists(big):
            big = f"build/bench-data/optimize/{BIG_BASE.rsplit('.', 1)[0]}-s{BIG_LEVEL}.ply"
            made = subprocess.run([program, "make-input", os.path.join(corpus, BIG_BASE), big, str(BIG_LEVEL)],
                                  capture_output=True, text=True)
            if made.returncode != 0:
                note(f"could not make {big}: {made.stderr.strip()}")
                big = None
        if big:
            triangles = 52000 * 4 ** BIG_LEVEL
            emit({"kind": "input", "name": os.path.basename(big), "path": big, "triangles": triangles, "group": "big"})
            inputs.append((os.path.basename(big), big, triangles, "big"))

    # ---- runs ---------------------------------------------------------------------------------------
    started = time.monotonic()
    for k, (name, path, triangles, group) in enumerate(inputs):
        big = group == "big"
        for tool, op in JOBS:
            command = ["/usr/bin/time", "-v", program, tool, op, path, str(3 if big else runs), "--json"]
            if not big:
                command[-1:-1] = ["--min-seconds", str(MIN_SECONDS)]
            record = {"kind": "run", "name": name, "group": group, "tool": tool, "op": op}
            try:
                p = subprocess.run(command, capture_output=True, text=True, timeout=PROCESS_TIMEOUT)
            except subprocess.TimeoutExpired:
                record["failed"] = f"ran past {PROCESS_TIMEOUT} s"
                emit(record)
                continue
            if p.returncode != 0:
                lines = [l for l in p.stderr.splitlines() if not l.startswith("\t")]
                record["failed"] = " ".join(lines[:3]) or f"exit {p.returncode}"
                emit(record)
                continue
            record.update(json.loads(p.stdout.strip().splitlines()[-1]))
            for line in p.stderr.splitlines():
                if "Maximum resident set size" in line:
                    record["peak_mib"] = round(int(line.split(":")[1]) / 1024, 1)
            emit(record)
        if big or (k + 1) % 20 == 0:
            print(f"bench: {k + 1}/{len(inputs)} inputs, {time.monotonic() - started:.0f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
