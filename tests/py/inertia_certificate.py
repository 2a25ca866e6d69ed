"""Matrix inertia of K - sigma*M in 40-digit arithmetic (mpmath), for cli/tests/models/modes_structured.rs
and tests/model/hidden_cable.rs.

Sylvester's law of inertia: for symmetric A = K - sigma*M with M positive definite, the
number of negative pivots of A = L D L^T equals the number of generalised eigenvalues of
(K, M) below sigma. The LDL^T is a sparse elimination without pivoting in the order given
(interior nodes cable by cable, the end-effector last: little fill). Every input number is
the exact binary value of an f64 (parsed with float(), then converted exactly), so the counts
are those of the assembled f64 matrices, free of any rounding of ours.

Input (JSON on stdin): {"n": N, "order": [...], "k": [[i, j, "v"], ...] (upper triangle),
"m": [[i, j, "v"], ...], "sigmas": [["lambda", "rel"], ...]} (f64 numbers as shortest
round-trip strings); sigma = lambda * (1 + rel), formed in 40 digits.
Output (JSON on stdout): {"negatives": [count per sigma]}.
"""
import json
import sys

from mpmath import mp, mpf

mp.dps = 40


def upper(entries, pos):
    out = {}
    for i, j, v in entries:
        p, q = pos[i], pos[j]
        if p > q:
            p, q = q, p
        out[(p, q)] = out.get((p, q), mpf(0)) + mpf(float(v))
    return out


def negatives(kk, mm, sigma, n):
    rows = [dict() for _ in range(n)]
    keys = set(kk) | set(mm)
    for (p, q) in keys:
        rows[p][q] = kk.get((p, q), mpf(0)) - sigma * mm.get((p, q), mpf(0))
    neg = 0
    for p in range(n):
        row = rows[p]
        d = row.get(p, mpf(0))
        if d == 0:
            raise SystemExit(f"zero pivot at {p}: sigma is an eigenvalue to 40 digits")
        if d < 0:
            neg += 1
        off = sorted((q, v) for q, v in row.items() if q > p)
        for a, (q1, v1) in enumerate(off):
            f = v1 / d
            r1 = rows[q1]
            for q2, v2 in off[a:]:
                r1[q2] = r1.get(q2, mpf(0)) - f * v2
        rows[p] = None
    return neg


def main():
    data = json.load(sys.stdin)
    n = data["n"]
    pos = {dof: p for p, dof in enumerate(data["order"])}
    kk = upper(data["k"], pos)
    mm = upper(data["m"], pos)
    sig = [mpf(float(lam)) * (1 + mpf(rel)) for lam, rel in data["sigmas"]]
    counts = [negatives(kk, mm, s, n) for s in sig]
    json.dump({"negatives": counts}, sys.stdout)


main()
