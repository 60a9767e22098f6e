#!/usr/bin/env python3
"""Sweep `rodloop solve` over scenes, branches and lengths and check every written state.

Scenes: every file in data/scenes, plus COUNT random two-segment scenes (fixed seed):
D1/D0 log-uniform in [0.01, 0.9], soft segment [s0, s1] of 0.1-0.9 of the loop, gamma
log-uniform in [5, 300], radius in [0.3, 3], d0 in [0.2, 5], surface or enclosed. For each
scene, branches 1-4 at 5 lengths evenly inside each branch's range (eta-1, eta+1) (branch 2:
(0, 2)), alternately at the scene's accuracy and --accuracy fast. Each written config.csv is
checked by scripts/state_check.py (closure, on the sphere, energy recomputed from the file,
branch). Prints the counts: runs, verified states, clean errors, open loops, states off the
sphere, energy mismatches, branch contradictions (each also counted separately for enclosed
scenes), other failures, and the first examples.

Usage: scripts/solve_sweep.py [COUNT=40] [BIN=target/release/rodloop] [SECONDS=30] [JOBS=1]
"""
import collections, concurrent.futures, glob, math, os, random, subprocess, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from state_check import check_state  # noqa: E402

COUNT = int(sys.argv[1]) if len(sys.argv) > 1 else 40
BIN = os.environ.get("BIN", sys.argv[2] if len(sys.argv) > 2 else "target/release/rodloop")
LIMIT = float(sys.argv[3]) if len(sys.argv) > 3 else 30.0
JOBS = int(sys.argv[4]) if len(sys.argv) > 4 else 1
rng = random.Random(20261127)
# The shipped scenes, found beside this script whatever the working directory.
SCENES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "scenes", "*.toml")


def random_scene(i):
    d0 = math.exp(rng.uniform(math.log(0.2), math.log(5.0)))
    d1 = d0 * math.exp(rng.uniform(math.log(0.01), math.log(0.9)))
    width = rng.uniform(0.1, 0.9)
    s0 = rng.uniform(0.0, 1.0 - width)
    gamma = math.exp(rng.uniform(math.log(5.0), math.log(300.0)))
    conf = "enclosed" if rng.random() < 0.15 else "surface"
    return (f'name = "random-{i}"\nradius = {rng.uniform(0.3, 3.0):.4f}\nconfinement = "{conf}"\n'
            f'lbar_min = 0.5\nlbar_max = 5.0\naccuracy = "default"\n[stiffness]\nkind = "tanh"\n'
            f'd0 = {d0:.5g}\nd1 = {d1:.5g}\ns0 = {s0:.4f}\ns1 = {s0 + width:.4f}\ngamma = {gamma:.4g}\n')


def jobs(tmp):
    scenes = [(os.path.basename(p), open(p).read()) for p in sorted(glob.glob(SCENES))]
    scenes += [(f"random-{i}", random_scene(i)) for i in range(COUNT)]
    out = []
    for name, text in scenes:
        path = os.path.join(tmp, name if name.endswith(".toml") else name + ".toml")
        with open(path, "w") as f:
            f.write(text)
        enclosed = 'confinement = "enclosed"' in text
        k = 0
        for branch in (1, 2, 3, 4):
            eta = {1: 2, 2: 1}.get(branch, branch)
            lo, hi = (0.0 if branch == 2 else eta - 1.0), eta + 1.0
            for j in range(1, 6):
                lbar = lo + (hi - lo) * j / 6
                acc = [] if k % 2 == 0 else ["--accuracy", "fast"]
                k += 1
                out.append((name, path, enclosed, branch, f"{lbar:.4f}", acc))
    return out


def run(job, tmp, idx):
    name, path, enclosed, branch, lbar, acc = job
    out = os.path.join(tmp, f"out-{idx}")
    cmd = [BIN, "solve", "--scene", path, "--lbar", lbar, "--branch", str(branch), "--out", out] + acc
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=LIMIT)
    except subprocess.TimeoutExpired:
        return job, ["over time limit"], ""
    if p.returncode == 0:
        probs = check_state(out, branch, enclosed)
        suffix = " (enclosed)" if enclosed else ""
        return job, [p + suffix for p in probs] or ["verified"], ""
    if "panicked" in p.stderr or p.returncode < 0 or p.returncode == 101:
        return job, ["panic or abort"], p.stderr[-300:]
    if p.stderr.startswith("error: ") and p.stderr.strip().count("\n") == 0:
        return job, ["clean error"], p.stderr.strip()[:200]
    return job, ["unclear error"], p.stderr[:300]


def main():
    t0 = time.time()
    counts = collections.Counter()
    examples = collections.defaultdict(list)
    with tempfile.TemporaryDirectory() as tmp:
        todo = jobs(tmp)
        with concurrent.futures.ThreadPoolExecutor(max_workers=JOBS) as pool:
            futs = [pool.submit(run, j, tmp, i) for i, j in enumerate(todo)]
            for f in concurrent.futures.as_completed(futs):
                job, kinds, err = f.result()
                counts["runs"] += 1
                for k in kinds:
                    counts[k] += 1
                    if k not in ("verified", "clean error") and len(examples[k]) < 4:
                        name, _, _, branch, lbar, acc = job
                        examples[k].append(f"{name} --lbar {lbar} --branch {branch} {' '.join(acc)} {err}")
    print(f"{counts['runs']} solve runs over {len(glob.glob(SCENES))} shipped + {COUNT} random scenes "
          f"({time.time() - t0:.0f} s, {LIMIT:.0f} s limit each):")
    for k in ["verified", "clean error", "open loop", "off the sphere", "energy mismatch",
              "branch contradiction", "unreadable", "unclear error", "panic or abort", "over time limit"]:
        print(f"  {k}: {counts[k]}")
        if counts[k + " (enclosed)"]:
            print(f"  {k} (enclosed): {counts[k + ' (enclosed)']}")
    for k, ex in examples.items():
        for e in ex:
            print(f"--- {k}: {e}")


if __name__ == "__main__":
    main()
