#!/usr/bin/env python3
"""Generate data/reference/special_values.csv, the independent reference table
for the `rodloop-special` crate.

Every value is computed with mpmath at DPS significant digits (and re-checked
at CHECK_DPS digits; a row is rejected if the two disagree beyond 1e-25
relative), from inputs that are exactly representable IEEE doubles: each input
is written with Python's shortest round-trip `repr`, so the Rust test parses
exactly the same double that mpmath used.

Conventions (all in the *modulus* k unless the name ends in `_m`, which takes
the parameter m = k^2 directly, possibly negative):

    sn, cn, dn, am      u, k          Jacobi functions, mpmath.ellipfun(kind, u, m=k^2)
                                      am is the unwrapped amplitude (see below)
    K, E                k             complete integrals, mpmath.ellipk/ellipe(k^2)
    K_m, E_m            m
    Pi                  n, k          complete third kind, mpmath.ellippi(n, k^2)
    Pi_m                n, m
    F, Einc             phi, k        incomplete, mpmath.ellipf/ellipe(phi, k^2)
    F_m, Einc_m         phi, m
    Piinc               n, phi, k     mpmath.ellippi(n, phi, k^2)
    Piinc_m             n, phi, m
    dKdk, dEdk          k             d/dk of K(k), E(k)           (mpmath.diff)
    dPidn, dPidk        n, k          partial derivatives of Pi(n|k^2) (mpmath.diff)

am(u, k): for k < 1 it is the continuous amplitude, am = j*pi + atan2((-1)^j sn,
(-1)^j cn) with j = nint(u / 2K) (checked against mpmath.ellipf(am, m) = u);
for k = 1 it is gd(u) = atan(sinh u); for k > 1 it is asin(sn(u, k)) (cn > 0).

Usage: python3 scripts/gen_special_table.py  (writes the CSV, ~1 min)
"""

import math
import os
import sys

import mpmath
from mpmath import mp, mpf

DPS = 40
CHECK_DPS = 60
OUT = os.path.join(
    os.path.dirname(os.path.abspath(__file__)),
    "..",
    "data",
    "reference",
    "special_values.csv",
)


def real(z):
    """Strip a negligible imaginary part (mpmath returns complex for m > 1)."""
    if isinstance(z, mpmath.mpc):
        if abs(z.imag) > mpf(10) ** (-(mp.dps - 8)) * max(1, abs(z.real)):
            raise ValueError("unexpected complex value %s" % z)
        return z.real
    return z


def jacobi_value(kind, u, k):
    u = mpf(u)
    k = mpf(k)
    m = k * k
    if kind in ("sn", "cn", "dn"):
        if k == 1:
            return {"sn": mpmath.tanh(u), "cn": mpmath.sech(u), "dn": mpmath.sech(u)}[kind]
        return real(mpmath.ellipfun(kind, u, m=m))
    # amplitude
    if k == 1:
        return mpmath.atan(mpmath.sinh(u))
    sn = real(mpmath.ellipfun("sn", u, m=m))
    cn = real(mpmath.ellipfun("cn", u, m=m))
    if k > 1:
        return mpmath.atan2(sn, cn)
    if k == 0:
        return u
    kk = mpmath.ellipk(m)
    j = int(mpmath.nint(u / (2 * kk)))
    sgn = -1 if j % 2 else 1
    am = j * mp.pi + mpmath.atan2(sgn * sn, sgn * cn)
    # independent consistency check: F(am | m) must give back u
    back = mpmath.ellipf(am, m)
    assert abs(back - u) <= mpf(10) ** (-(mp.dps - 10)) * max(1, abs(u)), (u, k, back)
    return am


def value(func, args):
    a = [mpf(x) for x in args]
    if func in ("sn", "cn", "dn", "am"):
        return jacobi_value(func, args[0], args[1])
    if func == "K":
        return mpmath.ellipk(a[0] ** 2)
    if func == "E":
        return mpmath.ellipe(a[0] ** 2)
    if func == "K_m":
        return mpmath.ellipk(a[0])
    if func == "E_m":
        return mpmath.ellipe(a[0])
    if func == "Pi":
        return mpmath.ellippi(a[0], a[1] ** 2)
    if func == "Pi_m":
        return mpmath.ellippi(a[0], a[1])
    if func == "F":
        return mpmath.ellipf(a[0], a[1] ** 2)
    if func == "Einc":
        return mpmath.ellipe(a[0], a[1] ** 2)
    if func == "F_m":
        return mpmath.ellipf(a[0], a[1])
    if func == "Einc_m":
        return mpmath.ellipe(a[0], a[1])
    if func == "Piinc":
        return mpmath.ellippi(a[0], a[1], a[2] ** 2)
    if func == "Piinc_m":
        return mpmath.ellippi(a[0], a[1], a[2])
    if func == "dKdk":
        return mpmath.diff(lambda kk: mpmath.ellipk(kk ** 2), a[0])
    if func == "dEdk":
        return mpmath.diff(lambda kk: mpmath.ellipe(kk ** 2), a[0])
    if func == "dPidn":
        return mpmath.diff(lambda nn: mpmath.ellippi(nn, a[1] ** 2), a[0])
    if func == "dPidk":
        return mpmath.diff(lambda kk: mpmath.ellippi(a[0], kk ** 2), a[1])
    raise KeyError(func)


def checked_value(func, args):
    mp.dps = CHECK_DPS
    hi = real(value(func, args))
    mp.dps = DPS
    lo = real(value(func, args))
    scale = max(abs(hi), mpf(10) ** -12)
    if abs(hi - lo) > mpf(10) ** -25 * scale:
        raise ValueError("precision check failed for %s%s: %s vs %s" % (func, args, lo, hi))
    return lo


# ----------------------------------------------------------------------------
# grids (all inputs are Python floats, i.e. exact doubles)

K_BELOW = [
    0.0, 1e-8, 1e-3, 0.1, 0.3, 0.5, 2 ** -0.5, 0.8, 0.9, 0.99, 0.999,
    0.9999, 0.999999, 1 - 1e-9, 1 - 1e-12,
]
K_ABOVE = [1 + 1e-12, 1 + 1e-6, 1.001, 1.1, 1.5, 2.0, 3.7, 5.0, 10.0, 20.0, 50.0]
U_GRID = [
    0.0, 1e-8, -1e-8, 0.1, 0.5, -0.7, 1.0, 2.0, 3.3, -4.7, 7.5, 10.0, -13.0,
    20.0, 27.1, 33.3, -41.9, 50.0, -50.0,
]


def jacobi_rows():
    rows = []
    for k in K_BELOW + [1.0] + K_ABOVE:
        us = list(U_GRID)
        # points at (rounded) multiples of the quarter period: zeros of sn / cn
        mp.dps = DPS
        if k < 1:
            kq = mpmath.ellipk(mpf(k) ** 2)
        elif k > 1:
            kq = mpmath.ellipk(1 / mpf(k) ** 2) / k
        else:
            kq = None
        if kq is not None:
            for j in (1, 2, 3, 4, 7, -5, -6):
                x = float(j * kq)
                if abs(x) <= 50:
                    us.append(x)
                    us.append(math.nextafter(x, math.inf))
            x = float(2.5 * kq)
            if x <= 50:
                us.append(x)
        for u in us:
            for f in ("sn", "cn", "dn", "am"):
                rows.append((f, (u, k)))
    return rows


PHI_GRID = [
    0.0, 1e-9, 0.1, 0.5, 1.0, -1.2, math.pi / 2, 1.5707963, 1.6, 2.0, 3.0,
    math.pi, 4.0, -5.0, 7.5, 10.0, -13.7, 20.0, -20.0,
]
N_GRID = [-1e8, -1e5, -100.0, -10.0, -1.0, -0.1, -1e-6, 0.0, 1e-6, 0.1, 0.25, 0.5, 0.81, 0.9]
M_NEG = [-1e4, -100.0, -10.0, -2.0, -1.0, -0.5, -1e-6, 0.0, 0.3, 0.9, 1 - 1e-9]
K_INT = [0.0, 1e-8, 1e-3, 0.1, 0.3, 0.5, 2 ** -0.5, 0.9, 0.99, 0.999, 0.999999, 1 - 1e-9, 1 - 1e-12]


def integral_rows():
    rows = []
    for k in K_INT + [0.2, 0.6, 0.95, 0.9999]:
        for f in ("K", "E", "dKdk", "dEdk"):
            rows.append((f, (k,)))
    for m in M_NEG + [-1e8, -0.25]:
        rows.append(("K_m", (m,)))
        rows.append(("E_m", (m,)))
    for k in K_INT:
        for n in N_GRID:
            rows.append(("Pi", (n, k)))
            rows.append(("dPidn", (n, k)))
            rows.append(("dPidk", (n, k)))
    # n close to k^2: removable singularity of the closed-form derivatives
    for k in (0.1, 0.5, 0.9, 0.99, 0.999, 0.999999, 1 - 1e-9):
        k2 = k * k
        for n in (k2, math.nextafter(k2, -math.inf), k2 * (1 - 1e-3), k2 * (1 + 1e-3),
                  k2 - 1e-8, k2 + 1e-8, k2 * (1 - 1e-5)):
            if n < 1:
                rows.append(("Pi", (n, k)))
                rows.append(("dPidn", (n, k)))
                rows.append(("dPidk", (n, k)))
    for m in M_NEG:
        for n in (-1e8, -1e4, -10.0, -1.0, -0.1, 0.0, 0.5, 0.9):
            rows.append(("Pi_m", (n, m)))
    for k in K_INT:
        for phi in PHI_GRID:
            rows.append(("F", (phi, k)))
            rows.append(("Einc", (phi, k)))
    for m in M_NEG:
        for phi in (0.3, 1.0, math.pi / 2, 2.5, -7.0, 20.0):
            rows.append(("F_m", (phi, m)))
            rows.append(("Einc_m", (phi, m)))
    for k in (0.0, 1e-3, 0.5, 0.9, 0.999999, 1 - 1e-12):
        for n in (-1e8, -1e4, -10.0, -1.0, -0.1, 0.0, 0.1, 0.25, 0.81, 0.9):
            for phi in (1e-9, 0.3, 1.0, math.pi / 2, 2.0, 4.0, -7.5, 13.0, -20.0):
                rows.append(("Piinc", (n, phi, k)))
    for m in (-100.0, -1.0, -0.2):
        for n in (-1e8, -1e4, -10.0, -1.0, -0.1, 0.0, 0.5, 0.9):
            for phi in (0.3, 1.0, 2.0, -7.5, 20.0):
                rows.append(("Piinc_m", (n, phi, m)))
    return rows


def fmt_arg(x):
    r = repr(float(x))
    assert float(r) == x
    return r


def main():
    rows = jacobi_rows() + integral_rows()
    out_lines = [
        "# generated by scripts/gen_special_table.py with mpmath %s at %d significant digits "
        "(cross-checked at %d); do not edit by hand" % (mpmath.__version__, DPS, CHECK_DPS),
        "func,x1,x2,x3,value",
    ]
    for i, (func, args) in enumerate(rows):
        v = checked_value(func, args)
        cols = [fmt_arg(a) for a in args] + [""] * (3 - len(args))
        out_lines.append("%s,%s,%s" % (func, ",".join(cols), mpmath.nstr(v, 30, strip_zeros=False)))
        if i % 500 == 0:
            print("%d/%d" % (i, len(rows)), file=sys.stderr)
    with open(OUT, "w") as fh:
        fh.write("\n".join(out_lines) + "\n")
    print("wrote %d rows to %s" % (len(rows), os.path.normpath(OUT)), file=sys.stderr)


if __name__ == "__main__":
    main()
