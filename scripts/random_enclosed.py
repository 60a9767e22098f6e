#!/usr/bin/env python3
"""Enclosed diagrams of random two-segment rods, the scenes of tests/random_enclosed.rs.

For each seed, the scene is drawn as `scene()` in tests/random_enclosed.rs draws it (the same
linear congruential generator, tests/common/mod.rs `Lcg`): D1/D0 in 0.2-0.8, a soft segment
of 0.2-0.6 of the loop at a random place, gamma in 20-100, R = 1, D0 = 1, on
LO <= lbar <= HI. `rodloop diagram` runs on it and one line per seed gives: the profile, the
wall time, the exchanges and collapses (lbar +- estimate), the warnings, the lowest states
of index > 0, the rows without a state file and the completeness certificate (lengths where
`solve` finds a state below the diagram's lowest, or misses it for its branch, and the
exchanges where `solve` finds a state below the exchange's energy or misses it). Python standard library only.

Usage: scripts/random_enclosed.py SEED [SEED ...] [--bin target/release/rodloop]
       [--lo 1.0] [--hi 2.6] [--out DIR]
"""
import argparse, csv, json, os, subprocess, sys, tempfile, time

MASK = (1 << 64) - 1


class Lcg:
    """tests/common/mod.rs `Lcg`: x <- 6364136223846793005 x + 1442695040888963407 (mod
    2^64), uniform in [0, 1) from its top 53 bits."""

    def __init__(self, seed):
        self.x = seed

    def next(self):
        self.x = (self.x * 6364136223846793005 + 1442695040888963407) & MASK
        return (self.x >> 11) / (1 << 53)

    def range(self, a, b):
        return a + (b - a) * self.next()


def scene(seed, lo, hi):
    g = Lcg(seed)
    d1 = g.range(0.2, 0.8)
    length = g.range(0.2, 0.6)
    s0 = g.range(0.0, 1.0 - length)
    gamma = g.range(20.0, 100.0)
    text = (
        f'name = "random-enclosed"\nradius = 1.0\nconfinement = "enclosed"\n'
        f"lbar_min = {lo!r}\nlbar_max = {hi!r}\naccuracy = \"default\"\n\n[stiffness]\n"
        f'kind = "tanh"\nd0 = 1.0\nd1 = {d1!r}\ns0 = {s0!r}\ns1 = {s0 + length!r}\n'
        f"gamma = {gamma!r}\n"
    )
    return text, (d1, s0, s0 + length, gamma)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("seeds", nargs="+", type=int)
    ap.add_argument("--bin", default="target/release/rodloop")
    ap.add_argument("--lo", type=float, default=1.0)
    ap.add_argument("--hi", type=float, default=2.6)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    root = a.out or tempfile.mkdtemp(prefix="random-enclosed-")
    for seed in a.seeds:
        text, (d1, s0, s1, gamma) = scene(seed, a.lo, a.hi)
        d = os.path.join(root, f"seed-{seed}")
        os.makedirs(d, exist_ok=True)
        sc = os.path.join(d, "scene.toml")
        with open(sc, "w") as f:
            f.write(text)
        t0 = time.monotonic()
        p = subprocess.run(
            [a.bin, "diagram", "--scene", sc, "--quiet", "--out", os.path.join(d, "out")],
            capture_output=True,
            text=True,
        )
        wall = time.monotonic() - t0
        head = f"seed {seed}: D1/D0 {d1:.3f} on {s0:.3f}-{s1:.3f}, gamma {gamma:.1f}, {wall:.1f} s"
        if p.returncode != 0:
            print(f"{head}: failed: {p.stderr.strip().splitlines()[-1:]}")
            continue
        out = os.path.join(d, "out")
        with open(os.path.join(out, "branches.csv")) as f:
            rows = list(csv.DictReader(f))
        with open(os.path.join(out, "critical.csv")) as f:
            crit = list(csv.DictReader(f))
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
        ex = "; ".join(
            f"{c['kind']} {c['from_branch']}->{c['to_branch']} "
            f"{float(c['lbar_cr']):.10f} +- {float(c['error_estimate']):.1e}"
            for c in crit
        )
        saddles = sum(1 for r in rows if r["lowest"] == "1" and r["index"] != "0")
        missing = sum(1 for r in rows if not r["state_file"])
        # The completeness certificate as the diagram judges it: lengths where `solve` found a
        # state below the lowest one (`below`), and where `solve` for the lowest state's
        # branch stayed above it by more than the two estimates or found nothing (`misses`).
        cert = summary.get("certificate", [])
        below = [c["lbar"] for c in cert if c.get("below")]
        misses = [c["lbar"] for c in cert if c.get("misses")]
        # At each located exchange, `solve`'s states of the two branches against the
        # exchange's energy: below it (the diagram missed a state) or above it / none.
        at_ex = summary.get("exchange_certificate", [])
        ex_below = [f"{c['lbar']:.6f}" for c in at_ex if c.get("below")]
        ex_misses = [f"{c['lbar']:.6f}" for c in at_ex if c.get("misses")]
        print(
            f"{head}; {len(rows)} rows; {ex}; {len(summary['warnings'])} warnings; "
            f"{saddles} lowest of index > 0; {missing} rows without a file; "
            f"certificate: {len(cert)} lengths, solve below the lowest at {below or 'none'}, "
            f"solve misses it at {misses or 'none'}; "
            f"{len(at_ex)} exchanges re-solved, solve below at {ex_below or 'none'}, "
            f"misses at {ex_misses or 'none'}"
        )
    print(f"outputs in {root}", file=sys.stderr)


if __name__ == "__main__":
    main()
