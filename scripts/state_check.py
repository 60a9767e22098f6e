"""Checks of a state written by `rodloop solve` (config.csv + summary.json), independent of
rodloop's own code: python3 standard library only. Shared by scripts/solve_sweep.py and
scripts/fuzz_cli.py.

check_state(out_dir, branch) returns a list of problems, each one of:
  "open loop"            the chord from the last point back to the first is longer than the
                         arclength between them (a closed curve's chord never is);
  "off the sphere"       a point with | |r| - R | > 1e-9 R (surface) or, enclosed, a node
                         with |r| > R (1 + 1e-9) or a Gauss point (node = 0) beyond the reach
                         of its cell's curve outside the ball, (h/R)^2 (1 + kappa_max R)/12
                         (f = |r|^2 has f'' = 2 (1 + r.kappa) <= 2 (1 + R kappa_max); between
                         nodes inside the ball f <= R^2 + u (h - u)(1 + R kappa_max), and
                         u (h - u) = h^2/6 at the Gauss points), in the file's units of R;
  "energy mismatch"      E R/(pi D0) = (1/pi) sum weight 1/2 D kappa^2 over the rows of an
                         enclosed file (its weight column: two-point Gauss weights h/2 at the
                         Gauss points and 0 at the nodes of a 3-D state, the trapezoid step at
                         the samples of a surface loop; the rule that computed the state's
                         energy) differs from the printed energy by more than the tolerance
                         summary.json states (verification.energy_tolerance) + 1e-9 max(1, |E|);
                         a surface file: (1/pi) sum 1/2 D kappa^2 ds by the periodic
                         trapezoidal rule on the file differs from the printed energy by more than
                         the tolerance summary.json states (verification.energy_tolerance:
                         the printed error estimate plus that of the recomputation, from the
                         companion solve) + |T_h - T_2h| + 1e-9 max(1, |E|); without that
                         field, 16 x the printed error estimate stands for the stated part:
                         the file's kappa = sqrt(kappa_g^2 + 1) with kappa_g = M.n/D at the cell
                         boundaries is a second O(h^4) discretisation of the state, whose error
                         is bounded by that of the half-resolution companion solve,
                         |E_N - E_N/2| = 15 x the estimate (measured on the shipped scenes:
                         at most about 12 x);
  "branch contradiction" summary.json names another branch than the one asked, or the
                         dominant Fourier harmonic of the file's kappa_g (enclosed: kappa_1 at
                         the nodes; its number of periods eta) is not the asked branch's eta;
  "unreadable"           the files are missing or malformed.
"""
import csv, json, math, os


def eta_of_branch(branch):
    """Paper numbering: branch 1 has eta = 2, branch 2 has eta = 1, branch B >= 3 has eta = B."""
    return {1: 2, 2: 1}.get(branch, branch)


def _rows(path):
    with open(path) as f:
        lines = [l for l in f if not l.startswith("#")]
    r = csv.DictReader(lines)
    return [{k.strip(): float(v) for k, v in row.items()} for row in r]


def dominant_harmonic(s, kg, length):
    """Number of periods of kappa_g: the k >= 1 with the largest |Fourier coefficient|."""
    n = len(s)
    w = []
    for j in range(n):
        nxt = s[j + 1] - s[j] if j + 1 < n else s[0] + length - s[j]
        prv = s[j] - s[j - 1] if j > 0 else s[0] + length - s[n - 1]
        w.append(0.5 * (nxt + prv))
    mean = sum(a * b for a, b in zip(kg, w)) / length
    best, amp_best = 0, -1.0
    for k in range(1, max(2, n // 4 + 1)):
        re = sum(wj * (v - mean) * math.cos(2 * math.pi * k * sj / length) for sj, v, wj in zip(s, kg, w))
        im = sum(wj * (v - mean) * math.sin(2 * math.pi * k * sj / length) for sj, v, wj in zip(s, kg, w))
        a = math.hypot(re, im)
        if a > amp_best:
            best, amp_best = k, a
    return best


def weighted_energy(rows):
    """E R/(pi D0) of an enclosed file by its quadrature weights, in the file's units."""
    return sum(r["weight"] * 0.5 * r["D"] * r["kappa"] ** 2 for r in rows) / math.pi


GAUSS = (0.5 - 0.5 / math.sqrt(3.0), 0.5 + 0.5 / math.sqrt(3.0))


def outside_ball(rows):
    """True when an enclosed file has a node outside the ball (beyond 1e-9 R) or a Gauss point
    beyond the reach of its cell's curve (see the module docs); units of R."""
    for k, r in enumerate(rows):
        rad = math.sqrt(r["x"] ** 2 + r["y"] ** 2 + r["z"] ** 2)
        if r.get("node", 1.0) == 1.0:
            if rad > 1 + 1e-9:
                return True
            continue
        # The cell's two Gauss rows: this one and its neighbour.
        a, b = (rows[k], rows[k + 1]) if rows[k - 1].get("node", 1.0) == 1.0 else (rows[k - 1], rows[k])
        kmax = 0.0
        for u in (0.0, 1.0):
            t = (u - GAUSS[0]) / (GAUSS[1] - GAUSS[0])
            k1 = a["kappa_1"] + t * (b["kappa_1"] - a["kappa_1"])
            k2 = a["kappa_2"] + t * (b["kappa_2"] - a["kappa_2"])
            kmax = max(kmax, math.hypot(k1, k2))
        h = 2 * r["weight"]
        if rad - 1 > 1e-9 + h * h * (1 + kmax) / 12:
            return True
    return False


def check_state(out_dir, branch, enclosed=False):
    try:
        with open(os.path.join(out_dir, "summary.json")) as f:
            summary = json.load(f)
        rows = _rows(os.path.join(out_dir, "config.csv"))
    except (OSError, ValueError, KeyError) as e:
        return ["unreadable"]
    problems = []
    if len(rows) < 8 or not all(c in rows[0] for c in ("x", "y", "z")):
        return ["unreadable"]
    if any(not math.isfinite(v) for r in rows for v in r.values()):
        return ["unreadable"]
    lbar = summary.get("lbar")
    length = 2 * math.pi * lbar if isinstance(lbar, (int, float)) else None
    pos = [(r["x"], r["y"], r["z"]) for r in rows]
    if "s" in rows[0] and length:
        chord = math.dist(pos[-1], pos[0])
        arc = length + rows[0]["s"] - rows[-1]["s"]
        if not (arc > 0 and chord <= arc * (1 + 1e-9) + 1e-9):
            problems.append("open loop")
    if enclosed:
        if outside_ball(rows):
            problems.append("off the sphere")
    else:
        for p in pos:
            if abs(math.sqrt(sum(c * c for c in p)) - 1) > 1e-9:
                problems.append("off the sphere")
                break
    energy = summary.get("energy")
    if enclosed and isinstance(energy, (int, float)):
        stated = (summary.get("verification") or {}).get("energy_tolerance")
        if not all(c in rows[0] for c in ("weight", "kappa", "D")) or not isinstance(stated, (int, float)):
            problems.append("energy mismatch")
        elif abs(weighted_energy(rows) - energy) > stated + 1e-9 * max(1.0, abs(energy)):
            problems.append("energy mismatch")
    elif all(c in rows[0] for c in ("s", "kappa", "D")) and length and isinstance(energy, (int, float)):
        dens = [0.5 * r["D"] * r["kappa"] ** 2 for r in rows]
        s = [r["s"] for r in rows]

        def trap(step):
            idx = list(range(0, len(rows), step))
            tot = 0.0
            for j, a in enumerate(idx):
                b = idx[(j + 1) % len(idx)]
                ds = s[b] - s[a] if j + 1 < len(idx) else length + s[b] - s[a]
                tot += 0.5 * (dens[a] + dens[b]) * ds
            return tot / math.pi

        fine, coarse = trap(1), trap(2)
        err = summary.get("error_estimate") or 0.0
        stated = (summary.get("verification") or {}).get("energy_tolerance")
        allowed = stated if isinstance(stated, (int, float)) else 16 * abs(err)
        tol = allowed + abs(fine - coarse) + 1e-9 * max(1.0, abs(energy))
        if abs(fine - energy) > tol:
            problems.append("energy mismatch")
    want = eta_of_branch(branch)
    contradiction = summary.get("branch") not in (None, branch)
    if summary.get("identified_eta") not in (None, want):
        contradiction = True
    if "kappa_g" in rows[0] and "s" in rows[0] and length:
        if dominant_harmonic([r["s"] for r in rows], [r["kappa_g"] for r in rows], length) != want:
            contradiction = True
    if enclosed and branch > 0 and "kappa_1" in rows[0] and length:
        nodes = [r for r in rows if r.get("node", 1.0) == 1.0]
        if dominant_harmonic([r["s"] for r in nodes], [r["kappa_1"] for r in nodes], length) != want:
            contradiction = True
    if contradiction:
        problems.append("branch contradiction")
    return problems


def trapezoid_energies(rows, length):
    """E R/(pi D0) of a loop table by the periodic trapezoidal rule on every point and on every
    other point (T_h, T_2h), in the file's units of R and D0."""
    s = [r["s"] for r in rows]
    dens = [0.5 * r["D"] * r["kappa"] ** 2 for r in rows]

    def trap(step):
        idx = list(range(0, len(rows), step))
        tot = 0.0
        for j, a in enumerate(idx):
            b = idx[(j + 1) % len(idx)]
            ds = s[b] - s[a] if j + 1 < len(idx) else length + s[b] - s[a]
            tot += 0.5 * (dens[a] + dens[b]) * ds
        return tot / math.pi

    return trap(1), trap(2)


# Multiple of a row's error estimate within which its state file's energy must lie, and the
# relative tolerance of a row without an estimate (rodloop_diagram::ESTIMATES and
# NO_ESTIMATE_TOLERANCE: the file samples one resolution, the row is extrapolated).
ESTIMATES = 5.0
NO_ESTIMATE_TOLERANCE = 1e-4


def check_diagram(out_dir, enclosed=False):
    """Every state file of a diagram (branches.csv + states/) against its row. Returns a list
    of (state_file or row description, problem) with problem one of "open loop", "off the
    sphere", "energy mismatch" (the trapezoidal energy of the file differs from the row's by
    more than ESTIMATES x its error estimate, or NO_ESTIMATE_TOLERANCE relative without one,
    plus |T_h - T_2h| + 1e-9 max(1, |E|); enclosed files: their weighted energy, see
    check_state), "unreadable"; and the number of rows checked.
    Rows without a file are not checked (the diagram counts them in summary.json)."""
    problems = []
    try:
        with open(os.path.join(out_dir, "branches.csv")) as f:
            table = list(csv.DictReader(l for l in f if not l.startswith("#")))
    except OSError:
        return [("branches.csv", "unreadable")], 0
    checked = 0
    for row in table:
        name = (row.get("state_file") or "").strip()
        if not name:
            continue
        checked += 1
        try:
            pts = _rows(os.path.join(out_dir, name))
            lbar, energy = float(row["lbar"]), float(row["energy"])
        except (OSError, ValueError, KeyError):
            problems.append((name, "unreadable"))
            continue
        if len(pts) < 8 or any(not math.isfinite(v) for p in pts for v in p.values()):
            problems.append((name, "unreadable"))
            continue
        length = 2 * math.pi * lbar
        pos = [(p["x"], p["y"], p["z"]) for p in pts]
        chord = math.dist(pos[-1], pos[0])
        arc = length + pts[0]["s"] - pts[-1]["s"]
        # The points between mesh nodes are interpolated: 1 % of the last step
        # (rodloop_solver::verify::CHORD_SLACK); an open loop misses by many steps.
        if not (arc > 0 and chord <= arc * 1.01 + 1e-9):
            problems.append((name, "open loop"))
        if enclosed:
            if outside_ball(pts):
                problems.append((name, "off the sphere"))
        else:
            for p in pos:
                if abs(math.sqrt(sum(c * c for c in p)) - 1) > 1e-9:
                    problems.append((name, "off the sphere"))
                    break
        if enclosed:
            # The file's own quadrature weights: the rule that computed the state's energy.
            fine = coarse = weighted_energy(pts) if "weight" in pts[0] else float("nan")
        else:
            fine, coarse = trapezoid_energies(pts, length)
        est = (row.get("energy_error") or "").strip()
        scale = max(1.0, abs(energy))
        allowed = ESTIMATES * float(est) if est else NO_ESTIMATE_TOLERANCE * scale
        if not abs(fine - energy) <= allowed + abs(fine - coarse) + 1e-9 * scale:
            problems.append((name, "energy mismatch"))
    return problems, checked


if __name__ == "__main__":
    import sys

    bad = 0
    for d in sys.argv[1:]:
        enclosed = os.path.exists(os.path.join(d, "branches.csv")) and any(
            n.startswith("enclosed-") for n in os.listdir(os.path.join(d, "states")) if os.path.isdir(os.path.join(d, "states")))
        probs, n = check_diagram(d, enclosed)
        print(f"{d}: {n} state files checked, {len(probs)} problems")
        for name, why in probs[:20]:
            print(f"  {name}: {why}")
        bad += len(probs)
    sys.exit(1 if bad else 0)
