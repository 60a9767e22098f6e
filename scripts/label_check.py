#!/usr/bin/env python3
"""Check the stability labels of a diagram's branches.csv against its own energies.

    scripts/label_check.py DIAGRAM_DIR [DIAGRAM_DIR ...]

Works from the written files only (branches.csv, summary.json), independent of the code
that assigns the labels. A sheet is one traced curve: the rows of one branch, family and
sheet (`arc // 10**6` in surface diagrams, the `sheet` column in enclosed ones), by L̄. At
the L̄ of a row another sheet's energy is interpolated (quadratic through its three nearest
rows; the interpolation's uncertainty is its distance from the linear one) and counts as a
local minimum there when its rows on both sides have index 0; a row that is a located
index change of its family (`index_changes` in the diagram's `branches/` files: the row
carries one side's index only) counts with the change's index on the stretch's side
(`above` after it, `below` before it), and a fold or branch point with none (the stretch
takes the other row's index). Two energies are *tied*
when they differ by no more than the sum of their error estimates (`energy_error`; a row
without one takes the largest of its sheet) and the interpolation uncertainty.

Checks (each failure is one line; the exit status is 1 if there is any):

* label and index: "unstable" exactly when the index is > 0;
* a "stable" row has no local minimum of another sheet below it beyond a tie;
* a "metastable" row has a local minimum of another sheet below it or tied with it
  (or lies within 2e-3 of an integer L̄, where the untraced great circle is lowest);
* rows that are the same state (same branch, same L̄, same index, energies tied) carry
  the same label;
* every length of the range (a grid of step 0.005 and every row's L̄) has a state
  labelled "stable" (a sheet covering it with a stable row on at least one side; at a
  row's own L̄, the row or a neighbour on its sheet), unless
  a warning of summary.json names a stretch containing it, it lies within 2e-3 of an
  integer (a great-circle length, where the lowest state is the untraced great circle), or
  no state is traced there at all below L̄ = 1 (the untraced circle).
"""

import csv
import glob
import json
import math
import re
import sys
from collections import defaultdict


def index_changes(d):
    """(branch, family, lbar) -> (below, above) of the located index changes in d/branches/,
    and the set of (branch, family, lbar) of its folds and branch points."""
    out = {}
    singular = set()

    def walk(o):
        if isinstance(o, dict):
            if "index_changes" in o and "branch" in o:
                key = (o["branch"], o.get("family", 0))
                for c in o["index_changes"] or []:
                    out[key + (c["lbar"],)] = (c["below"], c["above"])
                for p in o.get("points") or []:
                    if p.get("source") in ("fold", "branch_point"):
                        singular.add(key + (p["lbar"],))
            for v in o.values():
                walk(v)
        elif isinstance(o, list):
            for v in o:
                walk(v)

    for f in sorted(glob.glob(f"{d}/branches/*.json")):
        with open(f) as fh:
            walk(json.load(fh))
    return out, singular


def read_rows(d):
    with open(f"{d}/branches.csv") as f:
        rows = list(csv.DictReader(f))
    changes, singular = index_changes(d)
    out = []
    for r in rows:
        label = r.get("stability") or r.get("label")
        if "arc" in r:
            sheet = int(r["arc"]) // 1_000_000
        else:
            sheet = int(r.get("sheet") or 0)
        err = r.get("energy_error", "")
        out.append(
            dict(
                branch=int(r["branch"]),
                family=int(r.get("family") or 0),
                sheet=sheet,
                lbar=float(r["lbar"]),
                energy=float(r["energy"]),
                error=float(err) if err not in ("", None) else None,
                label=label,
                index=int(r["index"]),
                source=r.get("source", ""),
                change=changes.get(
                    (int(r["branch"]), int(r.get("family") or 0), float(r["lbar"]))
                ),
                singular=(int(r["branch"]), int(r.get("family") or 0), float(r["lbar"]))
                in singular,
            )
        )
    return out


def stretch_index0(a, b):
    """Whether the stretch between consecutive rows a and b of a sheet has index 0: a located
    index change counts with its index on the stretch's side, a fold or branch point (an
    eigenvalue passes through zero there) with none."""

    def side(r, after):
        if r["change"]:
            return r["change"][1] if after else r["change"][0]
        return None if r["singular"] else r["index"]

    x, y = side(a, True), side(b, False)
    if x is None and y is None:
        return a["index"] == 0 and b["index"] == 0
    return all(v == 0 for v in (x, y) if v is not None)


def sheets_of(rows):
    groups = defaultdict(list)
    for r in rows:
        groups[(r["branch"], r["family"], r["sheet"])].append(r)
    out = []
    for key, s in sorted(groups.items()):
        s.sort(key=lambda r: r["lbar"])
        known = [r["error"] for r in s if r["error"] is not None]
        worst = max(known) if known else 0.0
        for r in s:
            r["err"] = r["error"] if r["error"] is not None else worst
        out.append(s)
    return out


def at(s, l):
    """(energy, uncertainty, index 0 on both sides, stable on a side) of sheet s at l, or None."""
    if not s or l < s[0]["lbar"] or l > s[-1]["lbar"]:
        return None
    exact = [i for i, r in enumerate(s) if r["lbar"] == l]
    if exact:
        i = min(exact, key=lambda i: s[i]["energy"])
        r = s[i]
        # Stable on a side: the row itself or a neighbour on its sheet.
        near = s[max(i - 1, 0) : i + 2]
        return r["energy"], r["err"], r["index"] == 0, any(x["label"] == "stable" for x in near)
    k = next(i for i, r in enumerate(s) if r["lbar"] > l)
    a, b = s[k - 1], s[k]
    t = (l - a["lbar"]) / (b["lbar"] - a["lbar"])
    lin = a["energy"] + t * (b["energy"] - a["energy"])
    e = lin
    # Quadratic through the three nearest rows (distinct L̄).
    j = k - 2 if k + 1 >= len(s) else k - 1
    if j >= 0 and j + 2 < len(s):
        p, q, r = s[j], s[j + 1], s[j + 2]
        if q["lbar"] - p["lbar"] > 1e-12 and r["lbar"] - q["lbar"] > 1e-12:
            lag = lambda x, y, z: (l - y) * (l - z) / ((x - y) * (x - z))
            e = (
                p["energy"] * lag(p["lbar"], q["lbar"], r["lbar"])
                + q["energy"] * lag(q["lbar"], p["lbar"], r["lbar"])
                + r["energy"] * lag(r["lbar"], p["lbar"], q["lbar"])
            )
    unc = max(a["err"], b["err"]) + abs(e - lin)
    return (
        e,
        unc,
        stretch_index0(a, b),
        a["label"] == "stable" or b["label"] == "stable",
    )


def warned_stretches(d):
    try:
        with open(f"{d}/summary.json") as f:
            warnings = json.load(f).get("warnings", [])
    except (OSError, ValueError):
        return []
    out = []
    for w in warnings:
        for a, b in re.findall(r"([0-9.]+) ≤ L̄ ≤ ([0-9.]+)", w):
            out.append((float(a), float(b)))
    return out


def check(d):
    rows = read_rows(d)
    sheets = sheets_of(rows)
    bad = []
    for r in rows:
        if (r["label"] == "unstable") != (r["index"] > 0) or r["label"] not in (
            "stable",
            "metastable",
            "unstable",
        ):
            bad.append(f"index: branch {r['branch']} at {r['lbar']:.6f} index {r['index']} labelled {r['label']}")
    # Stable / metastable against the other sheets' local minima.
    for i, s in enumerate(sheets):
        for r in s:
            if r["index"] > 0 or r["source"] == "circle":
                continue
            lower, tied = None, False
            for j, o in enumerate(sheets):
                if j == i:
                    continue
                v = at(o, r["lbar"])
                if v is None or not v[2]:
                    continue
                e, unc, _, _ = v
                tol = r["err"] + unc + 1e-12 * max(abs(r["energy"]), 1.0)
                if e < r["energy"] - tol:
                    if lower is None or e < lower[0]:
                        lower = (e, o[0]["branch"], o[0]["family"], o[0]["sheet"])
                elif e <= r["energy"] + tol:
                    tied = True
            where = f"branch {r['branch']} family {r['family']} sheet {r['sheet']} at {r['lbar']:.6f} (E {r['energy']:.10f})"
            if r["label"] == "stable" and lower is not None:
                bad.append(
                    f"stable-above: {where} is stable; branch {lower[1]} family {lower[2]} sheet {lower[3]} has index 0 at {lower[0]:.10f}"
                )
            # At a great-circle length (within 2e-3 of an integer) the lowest state is the
            # untraced great circle.
            at_great_circle = abs(r["lbar"] - round(r["lbar"])) < 2e-3
            if r["label"] == "metastable" and lower is None and not tied and not at_great_circle:
                bad.append(f"metastable-lowest: {where} is metastable and the lowest local minimum")
    # The same state twice carries one label.
    by_len = defaultdict(list)
    for r in rows:
        by_len[(r["branch"], r["lbar"], r["index"])].append(r)
    for group in by_len.values():
        for a_i, a in enumerate(group):
            for b in group[a_i + 1 :]:
                tol = a["err"] + b["err"] + 1e-12 * max(abs(a["energy"]), 1.0)
                if abs(a["energy"] - b["energy"]) <= tol and a["label"] != b["label"]:
                    bad.append(
                        f"same-state: branch {a['branch']} at {a['lbar']:.6f}: E {a['energy']:.10f} ({a['label']}, family {a['family']} sheet {a['sheet']}) and {b['energy']:.10f} ({b['label']}, family {b['family']} sheet {b['sheet']})"
                    )
    # Every length has a stable state unless warned.
    lo = min(r["lbar"] for r in rows)
    hi = max(r["lbar"] for r in rows)
    try:
        with open(f"{d}/summary.json") as f:
            sj = json.load(f)
        lo, hi = float(sj.get("lbar_min", lo)), float(sj.get("lbar_max", hi))
    except (OSError, ValueError):
        pass
    n = max(1, math.ceil((hi - lo) / 0.005))
    grid = sorted(set([lo + (hi - lo) * k / n for k in range(n + 1)] + [r["lbar"] for r in rows]))
    warned = warned_stretches(d)
    missing = []
    for l in grid:
        if abs(l - round(l)) < 2e-3:
            continue
        if any(a - 0.005 <= l <= b + 0.005 for a, b in warned):
            continue
        covering = [v for v in (at(s, l) for s in sheets) if v is not None]
        if not covering and l < 1.0:
            continue
        if not any(v[3] for v in covering):
            missing.append(l)
    # One line per stretch of missing lengths.
    run = None
    for l in missing + [None]:
        if run and l is not None and l - run[1] <= 0.0051:
            run[1] = l
            continue
        if run:
            bad.append(f"no-stable: no state labelled stable on {run[0]:.4f} ≤ L̄ ≤ {run[1]:.4f} and no warning")
        run = [l, l] if l is not None else None
    return bad


def main():
    total = 0
    for d in sys.argv[1:]:
        bad = check(d)
        kinds = defaultdict(int)
        for b in bad:
            kinds[b.split(":")[0]] += 1
        print(f"{d}: {len(bad)} failure(s) {dict(kinds)}")
        for b in bad:
            print("  " + b)
        total += len(bad)
    sys.exit(1 if total else 0)


if __name__ == "__main__":
    main()
