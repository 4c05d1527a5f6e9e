#!/usr/bin/env python3
"""glTF compression (`-c`, EXT_meshopt_compression) and quantization (`-q`, KHR_mesh_quantization)
against gltfpack.

usage: run.py LODKIT FIXTURES OUT.json [--runs N] [--anim-error PROGRAM] [--normal-error PROGRAM]

For each input (corpus meshes of at least 20,000 triangles, the two skinned test characters with
their clips, the humanoid with a 20 s clip baked at 60 Hz, bunny00 textured (below), and bunny00's
LOD chain as `lodkit lod` writes it):
  - lodkit: `lodkit optimize IN --lru` (vertex cache and fetch order) written plain, with -c, and
    with -c -q (gltfpack's default bit depths: 14-bit positions, 8-bit normals);
  - gltfpack (Debian, 0.18) on the same plain file: -noq (its reordering, no quantization), -c -noq
    (the same compression lodkit writes), and -c (its defaults: quantized, lossy).
  - lodkit -c and -c -q with --meshopt-khr (KHR_meshopt_compression, vertex codec version 1) against
    the same EXT ones and gltfpack's, with load times;
  - UVs in N bits (inputs with UVs: the textured bunny, bunny00 with a spherical mapping and a base
    colour texture, written here without lodkit): `optimize --lru -c -q --uv-bits N` against
    gltfpack's `-c -vt N` of the plain file, N = 10, 12, 16: sizes;
  - normals in N bits (inputs with normals, with --normal-error PROGRAM): `optimize --lru --cc
    --normal-bits N` against gltfpack's `-cc -vn N` of the plain file, N = 8, 12, 16: sizes and the
    normals' error from the plain file (lodkit_bench_normal_error);
  - Draco: `lodkit convert --draco` of the plain file against Debian's draco_transcoder (libdraco
    1.5.5, the same library) on it at the same bit depths (14-bit positions, 10-bit normals, 12-bit
    UVs, tangents and weights, 8-bit colours) and its default compression level, as lodkit uses.
Sizes raw and after gzip -9 (what a web server sends), the ratios lodkit -c / gltfpack -c -noq and
lodkit -c -q / gltfpack -c, the quantized files' symmetric Hausdorff distance from the plain file
(`lodkit compare`, relative to the bounding-box diagonal), and lodkit's load time (median of N
`lodkit info --json` load_seconds) and peak RSS, plain against -c and -c -q. Every lodkit -c and
-c -q file must read back with the plain file's triangle and vertex counts. For Draco: sizes, the
encoding time (median of N runs of each command, process start and file writing included), lodkit's
load time of each file (decoding included) and each file's Hausdorff distance from the plain one.
"""
import gzip
import json
import math
import os
import statistics
import struct
import subprocess
import sys
import tempfile
import time

BAKED_CLIP = "dance (baked)"  # humanoid_baked.glb's third clip (tests/skin/fixtures.h)
CORPUS = ["bunny00.off", "armadillo.off", "ChineseDragon-10kv.off", "fandisk_large.off", "elephant.off",
          "mushroom.off", "man.off", "refined_elephant.off", "femur.off", "cylinder.off"]


def kib(row, tool):
    """A file's size in KiB, and gzipped in brackets."""
    return f"{row['bytes'][tool] / 1024:.0f} ({row['gzip'][tool] / 1024:.0f})"


def spread(ratios):
    return f"median {statistics.median(ratios):.3f} ({min(ratios):.3f}-{max(ratios):.3f})"


def run(args, **kw):
    r = subprocess.run(args, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(args)}: {r.stderr.strip()[:300]}")
    return r.stdout


def gz(path):
    with open(path, "rb") as f:
        return len(gzip.compress(f.read(), 9, mtime=0))


def info(lodkit, path):
    return json.loads(run([lodkit, "info", "--json", path]))


def load(lodkit, path, runs):
    times = [info(lodkit, path)["load_seconds"] for _ in range(runs)]
    log = subprocess.run(["/usr/bin/time", "-v", lodkit, "info", "--json", path], capture_output=True, text=True)
    rss = next(int(l.split(":")[1]) for l in log.stderr.splitlines() if "Maximum resident set size" in l)
    return statistics.median(times), rss / 1024


def timed(args, runs):
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        run(args)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


NORMAL_BITS = [8, 12, 16]
UV_BITS = [10, 12, 16]
# A 1x1 PNG for the textured input's base colour.
PNG = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="


def textured_bunny(off, out):
    """bunny00 as a .glb with TEXCOORD_0 from a spherical mapping about its centroid (uneven, as
    unwrapped UVs are) and a base colour texture sampling it, written without lodkit."""
    lines = [l for l in open(off).read().split("\n") if l.strip() and not l.startswith("#")]
    nv, nf = map(int, lines[1].split()[:2])
    points = [tuple(map(float, l.split()[:3])) for l in lines[2:2 + nv]]
    faces = [tuple(map(int, l.split()[1:4])) for l in lines[2 + nv:2 + nv + nf]]
    c = [sum(p[k] for p in points) / nv for k in range(3)]
    uvs = []
    for p in points:
        d = [p[k] - c[k] for k in range(3)]
        r = math.sqrt(sum(x * x for x in d)) or 1.0
        uvs.append((0.5 + math.atan2(d[2], d[0]) / (2 * math.pi), math.acos(max(-1.0, min(1.0, d[1] / r))) / math.pi))
    pos = b"".join(struct.pack("<3f", *p) for p in points)
    uv = b"".join(struct.pack("<2f", *t) for t in uvs)
    idx = b"".join(struct.pack("<3I", *f) for f in faces)
    data = pos + uv + idx
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
           "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
           "textures": [{"source": 0}], "images": [{"uri": "data:image/png;base64," + PNG}],
           "buffers": [{"byteLength": len(data)}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos), "target": 34962},
                           {"buffer": 0, "byteOffset": len(pos), "byteLength": len(uv), "target": 34962},
                           {"buffer": 0, "byteOffset": len(pos) + len(uv), "byteLength": len(idx), "target": 34963}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3",
                          "min": [min(p[k] for p in points) for k in range(3)], "max": [max(p[k] for p in points) for k in range(3)]},
                         {"bufferView": 1, "componentType": 5126, "count": nv, "type": "VEC2"},
                         {"bufferView": 2, "componentType": 5125, "count": 3 * nf, "type": "SCALAR"}]}
    text = json.dumps(doc).encode()
    text += b" " * ((4 - len(text) % 4) % 4)
    with open(out, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(data)) + struct.pack("<II", len(text), 0x4E4F534A) + text +
                struct.pack("<II", len(data), 0x004E4942) + data)
DRACO_BITS = ["-qp", "14", "-qn", "10", "-qt", "12", "-qtg", "12", "-qw", "12", "-qg", "12", "-qc", "8"]


def hausdorff(lodkit, a, b):
    """Symmetric Hausdorff distance between two files' scenes (flattened), over the diagonal."""
    report = json.loads(run([lodkit, "compare", a, b, "--json"]))
    return max(report["a_to_b"]["relative_hausdorff"], report["b_to_a"]["relative_hausdorff"])


def main():
    lodkit, fixtures, out = sys.argv[1:4]
    runs = int(sys.argv[sys.argv.index("--runs") + 1]) if "--runs" in sys.argv else 5
    anim_error = sys.argv[sys.argv.index("--anim-error") + 1] if "--anim-error" in sys.argv else None
    normal_error = sys.argv[sys.argv.index("--normal-error") + 1] if "--normal-error" in sys.argv else None
    tmp = tempfile.mkdtemp(prefix="lodkit-bench-compress-")
    inputs = []
    for name in CORPUS:
        path = os.path.join("data/corpus", name)
        if not os.path.exists(path):
            continue
        glb = os.path.join(tmp, name.rsplit(".", 1)[0] + ".glb")
        run([lodkit, "convert", path, glb])
        if info(lodkit, glb)["stats"]["triangles"] >= 20000:
            inputs.append((name, glb))
    characters = os.path.join(tmp, "fixtures")  # (its man.glb is not the corpus man's)
    os.makedirs(characters)
    run([fixtures, characters, "data/corpus/man.off"])
    inputs.append(("humanoid (skinned, 2 clips)", os.path.join(characters, "humanoid.glb")))
    # A third clip baked at 60 Hz on every joint for 20 s (as exporters write animation): -q's key
    # reduction and dropped still channels against gltfpack's 30 Hz resampling.
    inputs.append(("humanoid (skinned, + 20 s baked at 60 Hz)", os.path.join(characters, "humanoid_baked.glb")))
    if os.path.exists(os.path.join(characters, "man.glb")):
        inputs.append(("man (skinned, 2 clips)", os.path.join(characters, "man.glb")))
    textured = os.path.join(tmp, "bunny-textured.glb")
    textured_bunny("data/corpus/bunny00.off", textured)
    inputs.append(("bunny00 textured (spherical UVs)", textured))
    chain = os.path.join(tmp, "bunny-lod.glb")
    run([lodkit, "lod", "data/corpus/bunny00.off", "-o", chain])
    inputs.append(("bunny00 LOD chain (4 levels)", chain))

    rows = []
    for name, src in inputs:
        stem = os.path.join(tmp, "x")
        files = {
            "lodkit": stem + "-opt.glb",
            "lodkit -c": stem + "-opt-c.glb",
            "lodkit -c -q": stem + "-opt-cq.glb",
            "gltfpack -noq": stem + "-gp.glb",
            "gltfpack -c -noq": stem + "-gp-c-noq.glb",
            "gltfpack -c": stem + "-gp-c.glb",
            "gltfpack -cc": stem + "-gp-cc.glb",
            "lodkit -c khr": stem + "-opt-ck.glb",
            "lodkit -c -q khr": stem + "-opt-cqk.glb",
            "lodkit --cc": stem + "-opt-cc.glb",
        }
        # --lru: the LRU-style order (lodkit's Forsyth-like walk), which the meshopt codecs favour;
        # the default FIFO order costs -c about 5% (bunny00: 438 against 415 KiB).
        run([lodkit, "optimize", src, "-o", files["lodkit"], "--lru"])
        run([lodkit, "optimize", src, "-o", files["lodkit -c"], "--lru", "-c"])
        run([lodkit, "optimize", src, "-o", files["lodkit -c -q"], "--lru", "-c", "-q"])
        # KHR_meshopt_compression, vertex codec version 1 (lodkit's own encoder and decoder).
        run([lodkit, "optimize", src, "-o", files["lodkit -c khr"], "--lru", "-c", "--meshopt-khr"])
        run([lodkit, "optimize", src, "-o", files["lodkit -c -q khr"], "--lru", "-c", "-q", "--meshopt-khr"])
        # --cc: -c -q and octahedral normals and tangents, gltfpack -cc's filters.
        run([lodkit, "optimize", src, "-o", files["lodkit --cc"], "--lru", "--cc"])
        run(["gltfpack", "-i", files["lodkit"], "-o", files["gltfpack -noq"], "-noq"])
        run(["gltfpack", "-i", files["lodkit"], "-o", files["gltfpack -c -noq"], "-c", "-noq"])
        run(["gltfpack", "-i", files["lodkit"], "-o", files["gltfpack -c"], "-c"])
        # -cc: gltfpack's smaller form (strip order for the codecs, octahedral normals, quaternion
        # filter with per-joint bits).
        run(["gltfpack", "-i", files["lodkit"], "-o", files["gltfpack -cc"], "-cc"])
        plain = info(lodkit, files["lodkit"])["stats"]
        for flags in ["-c", "-c -q", "-c khr", "-c -q khr"]:
            packed = info(lodkit, files["lodkit " + flags])["stats"]
            if (plain["triangles"], plain["vertices"]) != (packed["triangles"], packed["vertices"]):
                raise RuntimeError(f"{name}: {flags} read back {packed['triangles']} triangles, {packed['vertices']} vertices")
        row = {"input": name, "triangles": plain["triangles"], "bytes": {}, "gzip": {}}
        for tool, path in files.items():
            row["bytes"][tool] = os.path.getsize(path)
            row["gzip"][tool] = gz(path)
        row["load_plain_s"], row["rss_plain_mib"] = load(lodkit, files["lodkit"], runs)
        row["load_c_s"], row["rss_c_mib"] = load(lodkit, files["lodkit -c"], runs)
        row["load_cq_s"], row["rss_cq_mib"] = load(lodkit, files["lodkit -c -q"], runs)
        row["load_ck_s"], _ = load(lodkit, files["lodkit -c khr"], runs)
        row["load_cqk_s"], _ = load(lodkit, files["lodkit -c -q khr"], runs)
        # (A skinned character is compared at rest, its bind pose: flatten places a quantized one
        # by the grid its joints carry.)
        row["hausdorff"] = {tool: hausdorff(lodkit, files["lodkit"], files[tool]) for tool in ["lodkit -c -q", "gltfpack -c", "gltfpack -cc", "lodkit --cc"]}
        # The baked clip's animation error (lodkit_bench_anim_error: the largest joint distance in
        # world space at 240 Hz), which the sizes trade against: -q drops keys, gltfpack resamples.
        if anim_error and src.endswith("humanoid_baked.glb"):
            row["anim_error_m"] = {tool: json.loads(run([anim_error, src, files[tool], BAKED_CLIP]))["joint_error"]
                                   for tool in ["lodkit -c", "lodkit -c -q", "lodkit -c -q khr", "lodkit --cc", "gltfpack -c", "gltfpack -cc"]}
        # -c -q --uv-bits N against gltfpack -c -vt N on inputs with UVs (sizes), --cc --normal-bits N
        # against gltfpack -cc -vn N on inputs with normals (sizes, and the normals' error from the
        # plain file: lodkit_bench_normal_error).
        streams = info(lodkit, files["lodkit"])["streams"]
        if "uv0" in streams:
            row["uv_bits"] = bits_sweep(lodkit, src, files["lodkit"], stem, UV_BITS, ["-c", "-q", "--uv-bits"], ["-c", "-vt"])
        if normal_error and "normal" in streams:
            row["normal_bits"] = bits_sweep(lodkit, src, files["lodkit"], stem, NORMAL_BITS, ["--cc", "--normal-bits"], ["-cc", "-vn"],
                                            normal_error)
        # Draco, from the same plain file.
        draco = {"lodkit --draco": stem + "-draco.glb", "draco_transcoder": stem + "-transcoder.glb"}
        commands = {"lodkit --draco": [lodkit, "convert", files["lodkit"], draco["lodkit --draco"], "--draco"],
                    "draco_transcoder": ["draco_transcoder", "-i", files["lodkit"], "-o", draco["draco_transcoder"]] + DRACO_BITS}
        row["draco"] = {}
        for tool, path in draco.items():
            seconds = timed(commands[tool], runs)
            report = info(lodkit, path)
            back = report["stats"]
            load_s, rss = load(lodkit, path, runs)
            row["draco"][tool] = {"bytes": os.path.getsize(path), "gzip": gz(path), "encode_s": seconds, "load_s": load_s,
                                  "rss_mib": rss, "hausdorff": hausdorff(lodkit, files["lodkit"], path),
                                  "triangles": back["triangles"], "primitives": report["gltf"]["primitives"]}
            if back["triangles"] != plain["triangles"]:
                raise RuntimeError(f"{name}: {tool} read back {back['triangles']} triangles")
        # draco_transcoder keeps only the meshes the scene's node tree draws: a chain's coarser
        # levels (MSFT_lod nodes outside the tree) are lost, so no ratio is given then.
        row["draco_same_content"] = row["draco"]["lodkit --draco"]["primitives"] == row["draco"]["draco_transcoder"]["primitives"]
        rows.append(row)
        print(f"  {name}: done", file=sys.stderr)

    tools = ["lodkit", "lodkit -c", "lodkit -c -q", "gltfpack -noq", "gltfpack -c -noq", "gltfpack -c"]
    print("| input | triangles | " + " | ".join(f"{t} KiB (gzip)" for t in tools) +
          " | lodkit -c ÷ gltfpack -c -noq (gzip) | lodkit -c -q ÷ gltfpack -c (gzip) | Hausdorff / diagonal, lodkit -c -q / gltfpack -c |"
          " load plain / -c / -c -q | peak RSS plain / -c / -c -q |")
    print("|---|---|" + "---|" * len(tools) + "---|---|---|---|---|")
    ratios, qratios = [], []
    for r in rows:
        ratio = r["bytes"]["lodkit -c"] / r["bytes"]["gltfpack -c -noq"]
        gratio = r["gzip"]["lodkit -c"] / r["gzip"]["gltfpack -c -noq"]
        qratio = r["bytes"]["lodkit -c -q"] / r["bytes"]["gltfpack -c"]
        qgratio = r["gzip"]["lodkit -c -q"] / r["gzip"]["gltfpack -c"]
        ratios.append(ratio)
        qratios.append(qratio)
        cells = " | ".join(f"{r['bytes'][t] / 1024:.0f} ({r['gzip'][t] / 1024:.0f})" for t in tools)
        h = r["hausdorff"]
        print(f"| {r['input']} | {r['triangles']:,} | {cells} | {ratio:.3f} ({gratio:.3f}) | {qratio:.3f} ({qgratio:.3f}) | "
              f"{h['lodkit -c -q']:.2e} / {h['gltfpack -c']:.2e} | "
              f"{r['load_plain_s'] * 1000:.1f} / {r['load_c_s'] * 1000:.1f} / {r['load_cq_s'] * 1000:.1f} ms | "
              f"{r['rss_plain_mib']:.0f} / {r['rss_c_mib']:.0f} / {r['rss_cq_mib']:.0f} MiB |")
    print()
    print(f"lodkit -c ÷ gltfpack -c -noq, raw size: median {statistics.median(ratios):.3f}, "
          f"min {min(ratios):.3f}, max {max(ratios):.3f} over {len(ratios)} inputs (runs per load time: {runs})")
    print(f"lodkit -c -q ÷ gltfpack -c, raw size: median {statistics.median(qratios):.3f}, "
          f"min {min(qratios):.3f}, max {max(qratios):.3f}")
    for r in rows:
        if "anim_error_m" in r:
            e = r["anim_error_m"]
            print(f"{r['input']}: clip '{BAKED_CLIP}', largest joint error (world space, 240 Hz): " +
                  ", ".join(f"{tool} {e[tool] * 1000:.3f} mm" for tool in e))
    print()
    print("Against gltfpack -cc (its smaller form: strip order for the codecs, octahedral normals, quaternion filter"
          " with per-joint bits; Hausdorff distance from the plain file over the diagonal):")
    print()
    print("| input | gltfpack -cc KiB (gzip) | lodkit --cc KiB (gzip) | lodkit --cc ÷ it (gzip) | lodkit -c -q ÷ it (gzip) |"
          " lodkit -c -q --meshopt-khr ÷ it (gzip) | Hausdorff, lodkit --cc / gltfpack -cc |")
    print("|---|---|---|---|---|---|---|")
    against = {"lodkit --cc": [], "lodkit -c -q": [], "lodkit -c -q khr": []}
    for r in rows:
        cells = []
        for tool, ratios in against.items():
            ratios.append(r["bytes"][tool] / r["bytes"]["gltfpack -cc"])
            cells.append(f"{ratios[-1]:.3f} ({r['gzip'][tool] / r['gzip']['gltfpack -cc']:.3f})")
        print(f"| {r['input']} | {kib(r, 'gltfpack -cc')} | {kib(r, 'lodkit --cc')} | {' | '.join(cells)} | "
              f"{r['hausdorff']['lodkit --cc']:.2e} / {r['hausdorff']['gltfpack -cc']:.2e} |")
    print()
    print("÷ gltfpack -cc, raw size: " + "; ".join(f"{tool} {spread(ratios)}" for tool, ratios in against.items()))
    print()
    print("KHR_meshopt_compression with vertex codec version 1 (`--meshopt-khr`, lodkit's own encoder and decoder), against"
          " EXT_meshopt_compression (version 0, meshoptimizer's) from lodkit and gltfpack:")
    print()
    print("| input | -c --meshopt-khr KiB (gzip) | ÷ lodkit -c | ÷ gltfpack -c -noq | -c -q --meshopt-khr KiB (gzip) | ÷ lodkit -c -q |"
          " ÷ gltfpack -c | load -c / -c --meshopt-khr | load -c -q / -c -q --meshopt-khr |")
    print("|---|---|---|---|---|---|---|---|---|")
    kratios, kqratios = [], []
    for r in rows:
        b = r["bytes"]
        kratios.append(b["lodkit -c khr"] / b["gltfpack -c -noq"])
        kqratios.append(b["lodkit -c -q khr"] / b["gltfpack -c"])
        print(f"| {r['input']} | {kib(r, 'lodkit -c khr')} | "
              f"{b['lodkit -c khr'] / b['lodkit -c']:.3f} | {kratios[-1]:.3f} | "
              f"{kib(r, 'lodkit -c -q khr')} | {b['lodkit -c -q khr'] / b['lodkit -c -q']:.3f} | "
              f"{kqratios[-1]:.3f} | {r['load_c_s'] * 1000:.1f} / {r['load_ck_s'] * 1000:.1f} ms | "
              f"{r['load_cq_s'] * 1000:.1f} / {r['load_cqk_s'] * 1000:.1f} ms |")
    print()
    print(f"-c --meshopt-khr ÷ gltfpack -c -noq: {spread(kratios)}; -c -q --meshopt-khr ÷ gltfpack -c: {spread(kqratios)}")
    print()
    print("| input | lodkit --draco KiB (gzip) | draco_transcoder KiB (gzip) | lodkit ÷ transcoder | encode lodkit / transcoder |"
          " load (lodkit) --draco / transcoder's | Hausdorff / diagonal, lodkit / transcoder |")
    print("|---|---|---|---|---|---|---|")
    dratios = []
    for r in rows:
        a, b = r["draco"]["lodkit --draco"], r["draco"]["draco_transcoder"]
        ratio = f"{a['bytes'] / b['bytes']:.3f}"
        if r["draco_same_content"]:
            dratios.append(a["bytes"] / b["bytes"])
        else:
            ratio = f"— (transcoder kept {b['primitives']} of {a['primitives']} primitives)"
        print(f"| {r['input']} | {a['bytes'] / 1024:.0f} ({a['gzip'] / 1024:.0f}) | {b['bytes'] / 1024:.0f} ({b['gzip'] / 1024:.0f}) | "
              f"{ratio} | {a['encode_s'] * 1000:.0f} / {b['encode_s'] * 1000:.0f} ms | "
              f"{a['load_s'] * 1000:.1f} / {b['load_s'] * 1000:.1f} ms | {a['hausdorff']:.2e} / {b['hausdorff']:.2e} |")
    print()
    print(f"lodkit --draco ÷ draco_transcoder, raw size: median {statistics.median(dratios):.3f}, "
          f"min {min(dratios):.3f}, max {max(dratios):.3f} over the {len(dratios)} inputs both write whole")
    print_bits_sweep(rows, "uv_bits", "UVs in N bits: `lodkit optimize --lru -c -q --uv-bits N` against `gltfpack -c -vt N` of the"
                     " `--lru` file (inputs with UVs):")
    print_bits_sweep(rows, "normal_bits", "Normals in N bits: `lodkit optimize --lru --cc --normal-bits N` against `gltfpack -cc -vn N`"
                     " of the `--lru` file (inputs with normals); normal error from the plain file in degrees, max / mean"
                     " (lodkit_bench_normal_error):")
    morphs = geomorph_chain(lodkit, tmp, runs)
    print()
    print("bunny00's geomorph chain (`lodkit lod data/corpus/bunny00.off --morph`, four levels, three geomorph targets), per output form:")
    print()
    print("| form | KiB (gzip) | ÷ plain | write | load | primitives, morph targets read back | Hausdorff / diagonal from the plain chain |")
    print("|---|---|---|---|---|---|---|")
    plain_bytes = morphs[0]["bytes"]
    for m in morphs:
        print(f"| {m['form']} | {m['bytes'] / 1024:.0f} ({m['gzip'] / 1024:.0f}) | {m['bytes'] / plain_bytes:.3f} | "
              f"{m['write_s']:.2f} s | {m['load_s'] * 1000:.1f} ms | {m['primitives']}, {m['morph_targets']} | {m['hausdorff']:.2e} |")
    with open(out, "w") as f:
        json.dump({"runs": runs, "rows": rows, "geomorph_chain": morphs}, f, indent=1)


def bits_sweep(lodkit, src, plain, stem, bit_list, ours, theirs, error=None):
    """Per bit depth N: `lodkit optimize SRC --lru OURS N` against `gltfpack -i PLAIN THEIRS N`, the
    sizes raw and gzipped, and with `error` (a program given the plain file and the output) its JSON."""
    out = {}
    for bits in bit_list:
        paths = {"lodkit": f"{stem}-{ours[-1].strip('-')}{bits}.glb", "gltfpack": f"{stem}-gp-{theirs[-1].strip('-')}{bits}.glb"}
        run([lodkit, "optimize", src, "-o", paths["lodkit"], "--lru"] + ours + [str(bits)])
        run(["gltfpack", "-i", plain, "-o", paths["gltfpack"]] + theirs + [str(bits)])
        out[bits] = {tool: {"bytes": os.path.getsize(path), "gzip": gz(path), **(json.loads(run([error, plain, path])) if error else {})}
                     for tool, path in paths.items()}
    return out


def print_bits_sweep(rows, key, title):
    """bits_sweep's results as a table, with the error columns where it measured them."""
    sweeps = [(r["input"], bits, t) for r in rows for bits, t in r.get(key, {}).items()]
    errors = any("max_degrees" in t["lodkit"] for _, _, t in sweeps)
    print()
    print(title)
    print()
    print("| input | N | lodkit KiB (gzip) | gltfpack KiB (gzip) | lodkit ÷ gltfpack (gzip) |" + (" error lodkit | error gltfpack |" if errors else ""))
    print("|---|---|---|---|---|" + ("---|---|" if errors else ""))
    for name, bits, t in sweeps:
        a, b = t["lodkit"], t["gltfpack"]
        line = (f"| {name} | {bits} | {a['bytes'] / 1024:.1f} ({a['gzip'] / 1024:.1f}) | {b['bytes'] / 1024:.1f} ({b['gzip'] / 1024:.1f}) | "
                f"{a['bytes'] / b['bytes']:.3f} ({a['gzip'] / b['gzip']:.3f}) |")
        if errors:
            line += f" {a['max_degrees']:.4f} / {a['mean_degrees']:.4f} | {b['max_degrees']:.4f} / {b['mean_degrees']:.4f} |"
        print(line)


# bunny00's LOD chain with geomorphs written in each form lodkit offers (and gltfpack's -c of the
# plain one): sizes, write and load times, what reads back, and the distance from the plain chain
# (all levels flattened together).
def geomorph_chain(lodkit, tmp, runs):
    forms = [("plain", []), ("-c", ["-c"]), ("-c -q", ["-c", "-q"]), ("-c --meshopt-khr", ["-c", "--meshopt-khr"]),
             ("-c -q --meshopt-khr", ["-c", "-q", "--meshopt-khr"]), ("--draco", ["--draco"]),
             ("--draco -c", ["--draco", "-c"]), ("--draco -q -c", ["--draco", "-q", "-c"])]
    out = []
    plain = None
    for form, flags in forms:
        path = os.path.join(tmp, "morph-" + form.replace(" ", "").replace("-", "_") + ".glb")
        seconds = timed([lodkit, "lod", "data/corpus/bunny00.off", "-o", path, "--morph"] + flags, runs)
        plain = plain or path
        report = info(lodkit, path)
        load_s, _ = load(lodkit, path, runs)
        out.append({"form": "lodkit " + form, "bytes": os.path.getsize(path), "gzip": gz(path), "write_s": seconds,
                    "load_s": load_s, "primitives": report["gltf"]["primitives"], "morph_targets": report["gltf"]["morph_targets"],
                    "hausdorff": hausdorff(lodkit, plain, path)})
    path = os.path.join(tmp, "morph-gltfpack-c.glb")
    seconds = timed(["gltfpack", "-i", plain, "-o", path, "-c"], runs)
    report = info(lodkit, path)
    load_s, _ = load(lodkit, path, runs)
    out.append({"form": "gltfpack -c (of the plain chain)", "bytes": os.path.getsize(path), "gzip": gz(path), "write_s": seconds,
                "load_s": load_s, "primitives": report["gltf"]["primitives"], "morph_targets": report["gltf"]["morph_targets"],
                "hausdorff": hausdorff(lodkit, plain, path)})
    return out


if __name__ == "__main__":
    main()
