"""Straight-line code builder with constant folding and common-subexpression elimination.

Every non-trivial SymPy expression handed to `let` becomes a named temporary; identical
expressions (and their negations) are hash-consed to the same temporary, so the program that
results has each common subexpression computed once. SymPy's own evaluation folds the zeros and
ones that the structured kinematics produce.
"""
import sympy as sp


def _is_atom(e):
    if e.is_Number or e.is_Symbol:
        return True
    return e.is_Mul and len(e.args) == 2 and e.args[0] == -1 and e.args[1].is_Symbol


class Tracer:
    def __init__(self, prefix="x"):
        self.prefix = prefix
        self.defs = []  # list of (Symbol, expr), in evaluation order
        self.cache = {}

    def let(self, e):
        e = sp.sympify(e)
        if _is_atom(e):
            return e
        hit = self.cache.get(e)
        if hit is not None:
            return hit
        hit = self.cache.get(-e)
        if hit is not None:
            return -hit
        s = sp.Symbol(f"{self.prefix}{len(self.defs)}")
        self.defs.append((s, e))
        self.cache[e] = s
        return s

    def vec(self, v):
        return [self.let(x) for x in v]

    # 3-vector helpers on lists of expressions
    def cross(self, a, b):
        return self.vec([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])

    def add(self, a, b):
        return self.vec([x + y for x, y in zip(a, b)])

    def matvec(self, R, v):
        return self.vec([sum(R[i][k] * v[k] for k in range(3)) for i in range(3)])

    def matTvec(self, R, v):
        return self.vec([sum(R[k][i] * v[k] for k in range(3)) for i in range(3)])

    def dot(self, a, b):
        return self.let(sum(x * y for x, y in zip(a, b)))


def live_program(defs, outputs):
    """The definitions needed by `outputs` (list of expressions), in order (dead-code elimination)."""
    needed = set()
    for e in outputs:
        needed |= sp.sympify(e).free_symbols
    by_sym = {s: e for s, e in defs}
    stack = [s for s in needed if s in by_sym]
    live = set()
    while stack:
        s = stack.pop()
        if s in live:
            continue
        live.add(s)
        for t in by_sym[s].free_symbols:
            if t in by_sym and t not in live:
                stack.append(t)
    return [(s, e) for s, e in defs if s in live]
