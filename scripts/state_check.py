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
                         periods of the file's bending moment D kappa_g (branch_of_file; an
                         enclosed file: of its central projection onto the sphere, or its
                         radial component where that projection is not regular, and a
                         one-fold loop shorter than the great circle is branch 0, one_fold)
                         do not name the asked branch's eta;
  "unreadable"           the files are missing or malformed.

check_diagram_branches(out_dir) names the branch of every state file of a diagram from the
file alone (branch_of_file: the periods of the bending moment D kappa_g, an enclosed 3-D
file's from the central projection of its positions onto the sphere, or the moment's
radial component where the projection is not regular; the count of
rodloop_solver::identify re-implemented) and lists the files that contradict their row.
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


def _periodic_weights(s, length):
    """Trapezoid weights of the samples s of a closed loop of the given length."""
    n = len(s)
    w = []
    for j in range(n):
        nxt = s[j + 1] - s[j] if j + 1 < n else s[0] + length - s[j]
        prv = s[j] - s[j - 1] if j > 0 else s[0] + length - s[n - 1]
        w.append(0.5 * (nxt + prv))
    return w


def _solve(a, b):
    """Gaussian elimination with partial pivoting (small dense systems)."""
    n = len(b)
    m = [row[:] + [bb] for row, bb in zip(a, b)]
    for i in range(n):
        p = max(range(i, n), key=lambda r: abs(m[r][i]))
        m[i], m[p] = m[p], m[i]
        for r in range(i + 1, n):
            f = m[r][i] / m[i][i]
            for c in range(i, n + 1):
                m[r][c] -= f * m[i][c]
    x = [0.0] * n
    for i in reversed(range(n)):
        x[i] = (m[i][n] - sum(m[i][c] * x[c] for c in range(i + 1, n))) / m[i][i]
    return x


def _local_frames(rows, length, half=3, deg=4):
    """Per row (r, t, k): the position, unit tangent and r'' of the least-squares polynomial
    of degree `deg` in s through the 2*half+1 nearest rows (the loop closed)."""
    n = len(rows)
    out = []
    for j in range(n):
        ds, pts = [], []
        for o in range(-half, half + 1):
            i = (j + o) % n
            d = rows[i]["s"] - rows[j]["s"]
            if j + o >= n:
                d += length
            if j + o < 0:
                d -= length
            ds.append(d)
            pts.append((rows[i]["x"], rows[i]["y"], rows[i]["z"]))
        ata = [[sum(d ** (a + b) for d in ds) for b in range(deg + 1)] for a in range(deg + 1)]
        t, k = [], []
        for c in range(3):
            co = _solve(ata, [sum(d ** a * p[c] for d, p in zip(ds, pts)) for a in range(deg + 1)])
            t.append(co[1])
            k.append(2 * co[2])
        r = pts[half]
        tn = math.sqrt(sum(v * v for v in t))
        out.append((r, [v / tn for v in t], k))
    return out


def _det(r, t, k):
    return (r[0] * (t[1] * k[2] - t[2] * k[1]) - r[1] * (t[0] * k[2] - t[2] * k[0])
            + r[2] * (t[0] * k[1] - t[1] * k[0]))


def projected_kappa_g(rows, length):
    """Geodesic curvature of the central projection r/|r| of an enclosed file's loop onto the
    unit sphere at each row, from the positions alone (_local_frames), det(r, t, r'') /
    (1 - (r.t/|r|)^2)^(3/2). On the sphere it is the loop's kappa_g. None where the projection
    is not regular (|r| < 1/4 or the tangent within asin(1/4) of radial;
    rodloop_solver::identify::PROJECTION_REGULARITY)."""
    out = []
    for r, t, k in _local_frames(rows, length):
        q = math.sqrt(sum(v * v for v in r))
        along = sum(a * b for a, b in zip(r, t)) / q if q > 0 else 1.0
        if q < 0.25 or 1 - along * along < 0.0625:
            return None
        out.append(_det(r, t, k) / (1 - along * along) ** 1.5)
    return out


def radial_moment(rows, length):
    """The signal of rodloop_solver::identify::enclosed_signal where the central projection is
    not regular, over D: det(r/|r|, t, r'') sin^2(t, r) at each row (_local_frames), the
    radial component of t x kappa weighted down where the loop runs radially; 0 at the
    centre."""
    out = []
    for r, t, k in _local_frames(rows, length):
        q = math.sqrt(sum(v * v for v in r))
        if q == 0:
            out.append(0.0)
            continue
        along = sum(a * b for a, b in zip(r, t)) / q
        out.append((1 - along * along) * _det(r, t, k) / q)
    return out


def _sign_changes(dev, h):
    start = next((i for i, v in enumerate(dev) if abs(v) > h), None)
    if start is None:
        return None
    positive, changes = dev[start] > 0, 0
    for i in range(1, len(dev) + 1):
        v = dev[(start + i) % len(dev)]
        if positive and v < -h:
            positive, changes = False, changes + 1
        elif not positive and v > h:
            positive, changes = True, changes + 1
    return changes


def _cubic_residual(s, v, length):
    """Largest |v_j - p_j(s_j)|, p_j the cubic through the rows j-2, j-1, j+1, j+2."""
    n, worst = len(v), 0.0
    for j in range(n):
        xs, ys = [], []
        for o in (-2, -1, 1, 2):
            i = (j + o) % n
            d = s[i] - s[j] + (length if j + o >= n else -length if j + o < 0 else 0.0)
            xs.append(d)
            ys.append(v[i])
        p = 0.0
        for a in range(4):
            term = ys[a]
            for b in range(4):
                if b != a:
                    term *= xs[b] / (xs[b] - xs[a])
            p += term
        worst = max(worst, abs(v[j] - p))
    return worst


def named_periods(s, signal, length):
    """The branch count of rodloop_solver::identify, re-implemented: half the sign changes of
    signal - mean (trapezoid-weighted), with hysteresis at 4 x the grid-scale noise (the
    cubic residual) and at a tenth of the amplitude; None unless both give the same count."""
    n = len(s)
    w = _periodic_weights(s, length)
    mean = sum(a * b for a, b in zip(signal, w)) / length
    dev = [v - mean for v in signal]
    amp = max(abs(v) for v in dev)
    scale = max(max(abs(v) for v in signal), 1.0 / length)
    if amp <= 1e-9 * scale:
        return None
    h = max(4.0 * _cubic_residual(s, dev, length), 1e-12 * scale)
    fine, coarse = _sign_changes(dev, h), _sign_changes(dev, max(h, 0.1 * amp))
    if fine is None or coarse is None or fine != coarse or coarse == 0:
        return None
    return coarse // 2


def _planar(kg, rows):
    """Whether the signal kg (over D) stays at its mean to 1e-6 of the largest D |kappa|: a
    loop in a plane through the centre (rodloop_solver::identify::PLANAR)."""
    mean = sum(kg) / len(kg)
    return max(abs(k - mean) * r["D"] for k, r in zip(kg, rows)) <= 1e-6 * max(
        r["D"] * abs(r["kappa"]) for r in rows
    )


def branch_of_file(rows, length):
    """The periods eta of a state file's bending moment D kappa_g (an enclosed 3-D file: of its
    central projection's, from the positions), or None where they name no branch."""
    if "kappa_g" in rows[0]:
        kg = [r["kappa_g"] for r in rows]
    else:
        kg = projected_kappa_g(rows, length)
        if kg is None:
            # The radial moment, unless it vanishes too: then the principal-axis curvature.
            kg = radial_moment(rows, length)
            if _planar(kg, rows):
                eta = principal_axis_periods(rows, length)
                if eta == 1 and length < 2 * math.pi and one_fold(rows):
                    return 0
                return eta
        elif _planar(kg, rows):
            # A loop in a plane through the centre projects onto a great circle: no periods.
            return None
    eta = named_periods([r["s"] for r in rows], [k * r["D"] for k, r in zip(kg, rows)], length)
    if eta == 1 and "kappa_g" not in rows[0] and length < 2 * math.pi and one_fold(rows):
        return 0
    return eta


def one_fold(rows):
    """Whether an enclosed file's loop (shorter than the great circle) is one-fold, the
    circle's family (branch 0) rather than a figure-eight: the polygon of its positions,
    projected onto the plane normal to its area vector A = 1/2 sum r_i x r_(i+1), turns once
    around (a figure-eight's projection turns 0 times). Undecided (False) where |A| is below
    a tenth of the circle's L^2/(4 pi) or an edge is nearly along A: the same rule as
    rodloop_solver::identify::identify_enclosed, on the file's polygon instead of the
    model's Gauss points."""
    pos = [(r["x"], r["y"], r["z"]) for r in rows]
    n = len(pos)
    ax = ay = az = 0.0
    length = 0.0
    for i in range(n):
        (x0, y0, z0), (x1, y1, z1) = pos[i], pos[(i + 1) % n]
        ax += 0.5 * (y0 * z1 - z0 * y1)
        ay += 0.5 * (z0 * x1 - x0 * z1)
        az += 0.5 * (x0 * y1 - y0 * x1)
        length += math.dist(pos[i], pos[(i + 1) % n])
    norm = math.sqrt(ax * ax + ay * ay + az * az)
    if norm < 0.1 * length * length / (4 * math.pi):
        return False
    nx, ny, nz = ax / norm, ay / norm, az / norm
    # An orthonormal pair in the plane normal to A.
    ux, uy, uz = (1.0, 0.0, 0.0) if abs(nx) < 0.9 else (0.0, 1.0, 0.0)
    d = ux * nx + uy * ny + uz * nz
    ux, uy, uz = ux - d * nx, uy - d * ny, uz - d * nz
    u = math.sqrt(ux * ux + uy * uy + uz * uz)
    ux, uy, uz = ux / u, uy / u, uz / u
    vx, vy, vz = ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux
    angles = []
    for i in range(n):
        (x0, y0, z0), (x1, y1, z1) = pos[i], pos[(i + 1) % n]
        ex, ey, ez = x1 - x0, y1 - y0, z1 - z0
        e = math.sqrt(ex * ex + ey * ey + ez * ez)
        if e == 0.0:
            continue
        a, b = (ex * ux + ey * uy + ez * uz) / e, (ex * vx + ey * vy + ez * vz) / e
        if math.hypot(a, b) < 0.1:
            return False
        angles.append(math.atan2(b, a))
    turn = 0.0
    for i in range(len(angles)):
        d = angles[(i + 1) % len(angles)] - angles[i]
        turn += (d + math.pi) % (2 * math.pi) - math.pi
    return abs(round(turn / (2 * math.pi))) == 1


def principal_axis_periods(rows, length):
    """The periods of an enclosed file whose central projection is not regular (a loop through
    the middle of the ball): rodloop_solver::identify::enclosed_signal's fallback, from the
    file's curvature components (kappa_1, kappa_2) in the rotation-minimising frame at the
    Gauss points (rows with node = 0), weighted by their quadrature weights, minus their mean
    and projected on their principal axis (the direction of largest variance), times D.
    None where the file has no such columns or the count names no branch."""
    if not all(c in rows[0] for c in ("kappa_1", "kappa_2", "weight", "node", "D")):
        return None
    g = [r for r in rows if r["node"] == 0]
    total = sum(r["weight"] for r in g)
    if len(g) < 8 or total <= 0:
        return None
    m1 = sum(r["weight"] * r["kappa_1"] for r in g) / total
    m2 = sum(r["weight"] * r["kappa_2"] for r in g) / total
    a = sum(r["weight"] * (r["kappa_1"] - m1) ** 2 for r in g)
    b = sum(r["weight"] * (r["kappa_1"] - m1) * (r["kappa_2"] - m2) for r in g)
    c = sum(r["weight"] * (r["kappa_2"] - m2) ** 2 for r in g)
    theta = 0.5 * math.atan2(2 * b, a - c)
    e1, e2 = math.cos(theta), math.sin(theta)
    signal = [r["D"] * ((r["kappa_1"] - m1) * e1 + (r["kappa_2"] - m2) * e2) for r in g]
    return named_periods([r["s"] for r in g], signal, length)


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
        # An enclosed file's last row is a Gauss point of the closing cell, interpolated
        # from the cell's curve: the same 1 % slack as check_diagram; an open loop misses
        # by many steps.
        slack = 1.01 if enclosed else 1 + 1e-9
        if not (arc > 0 and chord <= arc * slack + 1e-9):
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
    if branch > 0 and "s" in rows[0] and length:
        if branch_of_file(rows, length) != want:
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


def check_diagram_branches(out_dir):
    """Every state file of a diagram against its row's branch (branch_of_file). Returns
    (contradictions, unnamed, checked): the files whose periods name another eta than the
    row's, and those whose periods name none (their row's branch is the family's, from the
    state it was continued from)."""
    try:
        with open(os.path.join(out_dir, "branches.csv")) as f:
            table = list(csv.DictReader(l for l in f if not l.startswith("#")))
    except OSError:
        return [("branches.csv", "unreadable")], [], 0
    contradictions, unnamed, checked = [], [], 0
    for row in table:
        name = (row.get("state_file") or "").strip()
        if not name or not row.get("eta"):
            continue
        checked += 1
        eta = branch_of_file(_rows(os.path.join(out_dir, name)), 2 * math.pi * float(row["lbar"]))
        if eta is None:
            if int(row["eta"]) != 0:  # branch 0, the circle, has no periods
                unnamed.append(name)
        elif eta != int(row["eta"]):
            contradictions.append((name, f"branch contradiction: {eta} periods, row eta {row['eta']}"))
    return contradictions, unnamed, checked


if __name__ == "__main__":
    import sys

    bad = 0
    for d in sys.argv[1:]:
        enclosed = os.path.exists(os.path.join(d, "branches.csv")) and any(
            n.startswith("enclosed-") for n in os.listdir(os.path.join(d, "states")) if os.path.isdir(os.path.join(d, "states")))
        probs, n = check_diagram(d, enclosed)
        wrong, unnamed, _ = check_diagram_branches(d)
        probs += wrong
        print(f"{d}: {n} state files checked, {len(probs)} problems, {len(unnamed)} whose "
              "periods name no branch")
        for name, why in probs[:20]:
            print(f"  {name}: {why}")
        bad += len(probs)
    sys.exit(1 if bad else 0)
