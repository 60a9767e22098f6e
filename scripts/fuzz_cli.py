#!/usr/bin/env python3
"""Fuzz the scene parser and the solver through the CLI, as a user would meet them.

Mutates the shipped scene files (values, keys, types, truncation, junk) and argument sets,
runs `rodloop solve ... --accuracy fast` on each (and, on a fraction DIAGRAMS of the runs,
`rodloop diagram ... --accuracy fast` over a short length range) with a time limit, and
counts outcomes: success, clean error (non-zero exit with a one-line "error:" message),
panic, abort (killed by a signal), over the time limit. Prints the counts and the first
examples of anything but success/clean error. Every state a successful run writes is
checked by scripts/state_check.py: solve's config.csv by check_state (closed, on the sphere,
energy recomputed from config.csv, branch), every file of a diagram's states/ by
check_diagram (closed, on the sphere or inside the ball, energy recomputed from the file
against its row of branches.csv) and check_diagram_branches (the branch named by the file's
own periods against its row), and a diagram's labels by scripts/label_check.py (against its
own energies); a success whose files fail a check is counted under that problem instead.

Usage: scripts/fuzz_cli.py [N=10000] [BIN=target/release/rodloop] [SECONDS=20] [VALID=0.8]
                          [DIAGRAMS=0.05]
"""
import os, random, shutil, subprocess, sys, tempfile, collections, glob

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from state_check import check_state, check_diagram, check_diagram_branches  # noqa: E402
from label_check import check as check_labels  # noqa: E402

N = int(sys.argv[1]) if len(sys.argv) > 1 else 10000
BIN = sys.argv[2] if len(sys.argv) > 2 else "target/release/rodloop"
LIMIT = float(sys.argv[3]) if len(sys.argv) > 3 else 20.0
# Fraction of runs with a valid (branch, length) pair, so that mutated scenes reach the solver.
VALID = float(sys.argv[4]) if len(sys.argv) > 4 else 0.8
# Fraction of runs that draw a diagram instead of solving one state.
DIAGRAMS = float(sys.argv[5]) if len(sys.argv) > 5 else 0.05
rng = random.Random(20261123)
# The shipped scenes, found beside this script whatever the working directory.
SCENES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "scenes", "*.toml")
scenes = [open(p).read() for p in sorted(glob.glob(SCENES))]
NUMS = ["0", "-1", "1e-300", "1e300", "nan", "inf", "-inf", "0.5", "1", "2", "1e9", "1e-9",
        "200", "2000", "0.001", "3", "\"x\"", "[1, 2]", "true", "0.3", "0.8", "1.0e3"]
KEYS = ["radius", "d", "d0", "d1", "s0", "s1", "gamma", "kind", "lbar_min", "lbar_max",
        "accuracy", "confinement", "s", "name", "bogus"]

def mutate(text):
    lines = text.splitlines()
    for _ in range(rng.randint(1, 2)):
        op = rng.random()
        i = rng.randrange(len(lines)) if lines else 0
        if op < 0.45 and lines and "=" in lines[i]:
            k = lines[i].split("=")[0]
            lines[i] = f"{k}= {rng.choice(NUMS)}"
        elif op < 0.6:
            lines.insert(i, f"{rng.choice(KEYS)} = {rng.choice(NUMS)}")
        elif op < 0.7 and lines:
            del lines[i]
        elif op < 0.8 and lines:
            cut = rng.randrange(len(lines[i]) + 1)
            lines[i] = lines[i][:cut]
        elif op < 0.9:
            lines.insert(i, "".join(chr(rng.randrange(32, 127)) for _ in range(rng.randint(1, 20))))
        else:
            lines.insert(i, "[stiffness]\nkind = \"table\"\ns = [0.0, 0.5]\nd = [1.0, " + rng.choice(NUMS) + "]")
    return "\n".join(lines) + "\n"

def args_for(scene_path, out):
    if rng.random() < VALID:
        # A length inside the branch's range (branch 1: 1 < L̄ < 3, 2: 0 < L̄ < 2, 3: 2 < L̄ < 4).
        branch, lo, hi = rng.choice([("1", 1.0, 3.0), ("2", 0.05, 2.0), ("3", 2.0, 4.0)])
        lbar = f"{rng.uniform(lo + 0.02, hi - 0.02):.4f}"
    else:
        lbar = rng.choice(["1.2", "1.5", "2.2", "0.5", "-1", "0", "nan", "1e300", "2.9", "1.05", "3.5"])
        branch = rng.choice(["1", "2", "3", "0", "4", "99999999999"])
    a = [BIN, "solve", "--scene", scene_path, "--lbar", lbar, "--branch", branch,
         "--accuracy", "fast", "--out", out]
    if rng.random() < 0.05:
        a[a.index("fast")] = rng.choice(["slow", "", "high"])
    return a

def diagram_args(scene_path, out):
    """A diagram over a short range (0.1 to 0.3 wide) inside 0.5 <= L̄ <= 3."""
    lo = rng.uniform(0.5, 2.7)
    hi = lo + rng.uniform(0.1, 0.3)
    return [BIN, "diagram", "--scene", scene_path, "--lbar-min", f"{lo:.3f}",
            "--lbar-max", f"{hi:.3f}", "--accuracy", "fast", "--out", out]


counts = collections.Counter()
examples = collections.defaultdict(list)
with tempfile.TemporaryDirectory() as tmp:
    for i in range(N):
        path = os.path.join(tmp, "scene.toml")
        with open(path, "w") as f:
            f.write(mutate(rng.choice(scenes)))
        is_diagram = rng.random() < DIAGRAMS
        out = os.path.join(tmp, "diagram" if is_diagram else "out")
        shutil.rmtree(out, ignore_errors=True)
        cmd = diagram_args(path, out) if is_diagram else args_for(path, out)
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=LIMIT)
            err = p.stderr
            if p.returncode == 0 and is_diagram:
                text = open(path).read()
                enclosed = 'confinement = "enclosed"' in text.replace("'", '"')
                found = check_diagram(out, enclosed)[0] + check_diagram_branches(out)[0]
                probs = {why.split(":")[0] for _, why in found}
                # The labels against the diagram's own energies (scripts/label_check.py).
                probs |= {"label " + b.split(":")[0] for b in check_labels(out)}
                probs = sorted(probs)
                kind = "success" if not probs else "written state: " + ", ".join(probs)
            elif p.returncode == 0:
                text = open(path).read()
                try:
                    branch = int(cmd[cmd.index("--branch") + 1])
                except ValueError:
                    branch = None
                probs = check_state(os.path.join(tmp, "out"), branch,
                                    'confinement = "enclosed"' in text.replace("'", '"'))
                kind = "success" if not probs else "written state: " + ", ".join(probs)
            elif "panicked" in err or p.returncode == 101:
                kind = "panic"
            elif p.returncode < 0:
                kind = "abort"
            elif err.startswith("error: ") and len(err) < 4000:
                kind = "clean error"
            else:
                kind = "unclear error"
        except subprocess.TimeoutExpired:
            kind = "over time limit"
            err = ""
        counts[kind] += 1
        if kind not in ("success", "clean error") and len(examples[kind]) < 3:
            examples[kind].append((open(path).read(), cmd[3:], err[:300]))
        if (i + 1) % 1000 == 0:
            print(f"{i + 1} runs: {dict(counts)}", file=sys.stderr, flush=True)
print(f"{N} runs (rodloop solve --accuracy fast, {DIAGRAMS:.0%} of them rodloop diagram --accuracy fast instead, {LIMIT:.0f} s limit each, {VALID:.0%} with a valid branch and length):")
for k in ["success", "clean error", "unclear error", "panic", "abort", "over time limit"]:
    print(f"  {k}: {counts[k]}")
for k in sorted(c for c in counts if c.startswith("written state")):
    print(f"  {k}: {counts[k]}")
for k, ex in examples.items():
    for scene, args, err in ex:
        print(f"--- {k}: args {args}\n{scene}\n{err}")
