"""What the lod bench scripts share: their inputs as .glb written by hand (no lodkit, no glTF
library), a timed `lodkit lod` run, and their command line (main).

GlbBuilder: accessors go into one buffer, each in a view of its own (4-byte aligned); write() adds
the views, accessors and buffer to the given glTF JSON and writes the GLB container.
"""
import json
import os
import struct
import subprocess
import sys
import tempfile
import time


def run_lod(lodkit, src, out, extra=(), command="lod"):
    """`lodkit COMMAND SRC -o OUT --json EXTRA...` (lod unless told) under /usr/bin/time -v: wall
    seconds, peak RSS in MiB and the parsed report. Raises on failure."""
    start = time.monotonic()
    r = subprocess.run(["/usr/bin/time", "-v", lodkit, command, src, "-o", out, "--json", *extra], capture_output=True, text=True)
    wall = time.monotonic() - start
    if r.returncode != 0:
        raise RuntimeError(f"lodkit {command} {src}: {r.stderr.strip()[-300:]}")
    rss = next(int(l.split(":")[1]) for l in r.stderr.splitlines() if "Maximum resident set size" in l)
    return wall, rss / 1024, json.loads(r.stdout)


def main(doc, run, defaults):
    """The scripts' command line, `LODKIT OUT.json [--NAME VALUE]... [--out DIR]`: calls
    run(lodkit, out_json, options, work_dir), options keyed by the names in `defaults`, each as its
    default's type; work_dir is DIR (made if needed) or a temporary folder removed afterwards. Exits
    0 when run returns true, 1 otherwise; with fewer than two arguments, prints `doc`."""
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(doc)
    option = lambda name, default: type(default)(args[args.index(f"--{name}") + 1]) if f"--{name}" in args else default
    options = {name: option(name, default) for name, default in defaults.items()}
    out_dir = option("out", "")
    if out_dir:
        os.makedirs(out_dir, exist_ok=True)
        ok = run(args[0], args[1], options, out_dir)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            ok = run(args[0], args[1], options, tmp)
    sys.exit(0 if ok else 1)


class GlbBuilder:
    def __init__(self):
        self.chunks, self.views, self.accessors = [], [], []

    def accessor(self, data, count, kind, component, target=None, bounds=None):
        """The accessor's index. data: its bytes, tightly packed; target: the view's (34962 vertex
        data, 34963 indices); bounds: (min, max), which POSITION and animation inputs must have."""
        offset = sum(len(c) for c in self.chunks)
        self.chunks.append(data + b"\0" * (-len(data) % 4))
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(data)}
        if target:
            view["target"] = target
        self.views.append(view)
        a = {"bufferView": len(self.views) - 1, "componentType": component, "count": count, "type": kind}
        if bounds:
            a["min"], a["max"] = bounds
        self.accessors.append(a)
        return len(self.accessors) - 1

    def write(self, path, doc):
        doc["bufferViews"], doc["accessors"] = self.views, self.accessors
        binary = b"".join(self.chunks)
        doc["buffers"] = [{"byteLength": len(binary)}]
        text = json.dumps(doc, separators=(",", ":")).encode()
        text += b" " * (-len(text) % 4)
        with open(path, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(binary)))
            f.write(struct.pack("<II", len(text), 0x4E4F534A) + text)
            f.write(struct.pack("<II", len(binary), 0x004E4942) + binary)
