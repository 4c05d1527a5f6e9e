"""Times `lodkit simplify` on inputs built to be hard for the engine's per-position work: one
position with thousands of faces (the centre of a triangle fan, inside a disc or on the border of a
half disc). Work that walks a whole star per edge is quadratic there.

  python3 bench/simplify/pathological.py LODKIT_CLI [OUT_DIR=build/bench-data/pathological] [RUNS=3]

Writes the inputs as OFF files into OUT_DIR, simplifies each to 10% RUNS times under /usr/bin/time,
and prints the median wall time and the peak RSS per input."""
import math
import os
import statistics
import subprocess
import sys


def fan(path, n, closed):
    """n triangles around the origin: a closed disc, or a half disc whose centre is on the border."""
    rim = n if closed else n + 1
    with open(path, "w") as f:
        f.write(f"OFF\n{rim + 1} {n} 0\n0 0 0\n")
        for i in range(rim):
            a = (2 * math.pi * i / rim) if closed else (math.pi * i / n)
            f.write(f"{math.cos(a):.9g} {math.sin(a):.9g} 0\n")
        for i in range(n):
            f.write(f"3 0 {1 + i} {1 + (i + 1) % rim}\n")


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    cli = sys.argv[1]
    out_dir = sys.argv[2] if len(sys.argv) > 2 else "build/bench-data/pathological"
    runs = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    os.makedirs(out_dir, exist_ok=True)
    cases = [("fan-2000", 2000, True), ("fan-20000", 20000, True), ("fan-100000", 100000, True),
             ("half-fan-20000", 20000, False)]
    print(f"| input | triangles | median s (of {runs}) | peak RSS MiB |")
    print("|---|---|---|---|")
    for name, n, closed in cases:
        path = os.path.join(out_dir, name + ".off")
        if not os.path.exists(path):
            fan(path, n, closed)
        times, peaks = [], []
        for _ in range(runs):
            p = subprocess.run(["/usr/bin/time", "-f", "%e %M", cli, "simplify", path, "-o",
                                os.path.join(out_dir, name + "-out.off"), "--ratio", "0.1", "--force"],
                               capture_output=True, text=True)
            if p.returncode != 0:
                sys.exit(f"pathological: {name} failed: {p.stderr.strip()[-300:]}")
            seconds, kib = p.stderr.strip().splitlines()[-1].split()
            times.append(float(seconds))
            peaks.append(int(kib) / 1024)
        print(f"| {name} | {n} | {statistics.median(times):.2f} | {max(peaks):.0f} |")


if __name__ == "__main__":
    main()
