#!/usr/bin/env python3
"""Re-counts the reliability issue's classes against the `deferred` binary, by hand.

    python3 xtask/hostile_recount.py target/release/deferred ../shared/fixtures [--cases N]

Runs the binary (under `strace`, a 6 GiB address-space cap and a 60 s limit) on truncated and
byte-flipped copies of fixture scenes (Cornell OBJ + MTL, DamagedHelmet GLB, the dragon PLY,
Sponza glTF + bin), on hand-written hostile files and on invalid command-line values, and
prints per class: clean errors, panics (status 101 or "panicked"), crashes (a signal), hangs
(the limit), exit 0 on input known to be invalid, and opens of files outside the case's
scene folder (decoys planted beside it, /etc/passwd, /dev/zero). Mutated files that are still
valid may render (exit 0); that is not counted against the program.
"""
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

if len(sys.argv) < 3:
    sys.exit(__doc__)
BIN = os.path.abspath(sys.argv[1])
FIX = os.path.abspath(sys.argv[2])
CASES = int(sys.argv[sys.argv.index("--cases") + 1]) if "--cases" in sys.argv else 40
ROOT = tempfile.mkdtemp(prefix="recount-")
for decoy in ["decoy.bin", "decoy.mtl", "decoy.png"]:
    open(os.path.join(ROOT, decoy), "wb").write(b"\0" * 64)

counts = {}


def bump(cls, outcome):
    counts.setdefault(cls, {}).setdefault(outcome, 0)
    counts[cls][outcome] += 1


def run(args, case_dir, invalid, cls):
    trace = os.path.join(case_dir, "strace.txt")
    cmd = ["strace", "-f", "-qq", "-e", "trace=open,openat", "-o", trace, BIN] + args
    env = dict(os.environ)
    env.pop("RUST_BACKTRACE", None)
    try:
        p = subprocess.run(
            ["sh", "-c", 'ulimit -v 6291456; exec "$@"', "sh"] + cmd,
            capture_output=True, timeout=60, env=env, cwd=case_dir,
        )
    except subprocess.TimeoutExpired:
        bump(cls, "hang")
        return
    err = p.stderr.decode(errors="replace")
    if p.returncode == 101 or "panicked" in err:
        bump(cls, "panic")
    elif p.returncode < 0 or p.returncode > 128:
        bump(cls, "crash")
    elif p.returncode == 0:
        bump(cls, "exit 0 on invalid input" if invalid else "rendered (valid after mutation)")
    else:
        bump(cls, "clean error")
    scene_dir = os.path.join(case_dir, "scene")
    for line in open(trace, errors="replace"):
        m = re.search(r'open(?:at)?\((?:AT_FDCWD, )?"([^"]+)"', line)
        if not m or "= -1" in line:
            continue
        path = os.path.realpath(os.path.join(case_dir, m.group(1)))
        inside_root = path.startswith(ROOT + os.sep)
        outside_case = inside_root and not path.startswith(scene_dir + os.sep) and not path.startswith(os.path.join(case_dir, "out"))
        # /etc/passwd is also read by the Vulkan driver (its cache folder): judged on --cpu runs.
        named = "--cpu" in args and path in ("/etc/passwd", "/dev/zero")
        if (outside_case and "strace" not in path) or named:
            bump(cls, "read outside the scene folder")
            print(f"  outside: {path} ({' '.join(args)})", file=sys.stderr)
            break


def case(name):
    d = os.path.join(ROOT, name)
    os.makedirs(os.path.join(d, "scene"))
    return d


def mutate(data, rng):
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        i = rng.randrange(len(b))
        k = rng.randrange(4)
        if k == 0:
            b[i] ^= 1 << rng.randrange(8)
        elif k == 1:
            b[i] = rng.randrange(256)
        elif k == 2:
            b[i:i] = str(rng.randrange(10**rng.randint(1, 24))).encode()
        else:
            del b[i:i + rng.randint(1, 16)]
    return bytes(b)


SOURCES = [
    ("cornell/CornellBox-Original.obj", ["cornell/CornellBox-Original.mtl"]),
    ("gltf/DamagedHelmet/DamagedHelmet.glb", []),
    ("stanford/dragon-100k.ply", []),
    ("sponza/dabrovic/sponza.gltf", ["sponza/dabrovic/sponza.bin"]),
]
rng = random.Random(20)
n = 0
for src, companions in SOURCES:
    path = os.path.join(FIX, src)
    if not os.path.exists(path):
        continue
    data = open(path, "rb").read()
    variants = [data[: k * len(data) // CASES] for k in range(CASES)]
    variants += [mutate(data, rng) for _ in range(CASES)]
    for v in variants:
        n += 1
        d = case(f"c{n}")
        for c in companions:
            shutil.copy(os.path.join(FIX, c), os.path.join(d, "scene", os.path.basename(c)))
        target = os.path.join(d, "scene", os.path.basename(src))
        open(target, "wb").write(v)
        run(["--cpu", "--size", "32x24", "--scene", target, "--out", os.path.join(d, "out")],
            d, False, "mutated " + src.rsplit(".", 1)[1])

TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
HAND = {
    "t.gltf": '{"asset":{"version":"2.0"},"buffers":[{"uri":"../decoy.bin","byteLength":36}]}',
    "u.gltf": '{"asset":{"version":"2.0"},"buffers":[{"uri":"..%2F..%2Fdecoy.bin","byteLength":36}]}',
    "v.gltf": '{"asset":{"version":"2.0"},"buffers":[{"uri":"file:///etc/passwd","byteLength":36}]}',
    "w.gltf": '{"asset":{"version":"2.0"},"buffers":[{"uri":"/dev/zero","byteLength":36}]}',
    "x.gltf": '{"asset":{"version":"2.0"},"images":[{"uri":"/etc/passwd"}],"textures":[{"source":0}]}',
    "cyc.gltf": '{"asset":{"version":"2.0"},"nodes":[{"children":[0]}],"scenes":[{"nodes":[0]}]}',
    "a.obj": "mtllib ../decoy.mtl\n" + TRI + "f 1 2 3\n",
    "b.obj": "mtllib /etc/passwd\n" + TRI + "f 1 2 3\n",
    "c.obj": TRI + "f 1 2\n",
    "d.obj": TRI + "f 1 2 9\n",
    "e.obj": "v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "f.obj": "mtllib m.mtl\n" + TRI + "usemtl m\nf 1 2 3\n",
    "g.ply": "ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n",
    "h.ply": "ply\nformat ascii 1.0\nelement x 100\nend_header\n",
}
for name, text in HAND.items():
    n += 1
    d = case(f"h{n}")
    if name == "f.obj":
        open(os.path.join(d, "scene", "m.mtl"), "w").write("newmtl m\nKd 0.5\n")
    target = os.path.join(d, "scene", name)
    open(target, "w").write(text)
    run(["--cpu", "--size", "32x24", "--scene", target, "--out", os.path.join(d, "out")],
        d, True, "hand-written scenes")

VALUES = [
    ["--size", "0x0"], ["--size", "16384x16384", "--cpu"], ["--size", "axb"],
    ["--lights", "100000000"], ["--fov", "1e-30"], ["--fov", "nan"], ["--fov", "200"],
    ["--blur", "4"], ["--vpls", "64", "--blur", "4", "--cpu"], ["--vpls", "0", "--cpu"],
    ["--vpls", "64", "--pattern", "0x1", "--cpu"], ["--tile", "3", "--cpu"],
    ["--eye", "nan,0,0"], ["--eye", "0,1,0", "--target", "0,1,0", "--cpu"],
    ["--ambient", "1,2"], ["--light", "point:0,0,0,-1"], ["--builtin", "x"],
    ["--vpl-shadows", "manylod"], ["--indirect-only"], ["--heatmap-max", "-1"],
    ["--vpls", "64", "--vpl-clamp", "-1", "--cpu"], ["--ssaa", "0"],
    ["--subdiv", "100", "--cpu"], ["--subdiv", "0", "--cpu"],
    ["subdivide", "/nonexistent.obj", "--level", "1", "-o", "x.obj"],
]
for args in VALUES:
    n += 1
    d = case(f"v{n}")
    run(["--out", os.path.join(d, "out")] + args if args[0] != "subdivide" else args,
        d, True, "command-line values")

for cls, outcomes in counts.items():
    print(f"{cls}: " + ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items())))
shutil.rmtree(ROOT, ignore_errors=True)
