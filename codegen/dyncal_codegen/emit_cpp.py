"""C++ printing of traced programs: straight-line code over a `Scalar` template parameter."""
import sympy as sp


class CppPrinter:
    """Prints SymPy expressions as C++ and counts the arithmetic it emits."""

    def __init__(self):
        self.muls = 0
        self.adds = 0

    def number(self, x):
        if x.is_Integer:
            return f"Scalar({int(x)})"
        return f"Scalar({repr(float(x))})"

    def expr(self, e):
        if e.is_Symbol:
            return str(e)
        if e.is_Number:
            if e < 0:
                return "-" + self.number(-e)
            return self.number(e)
        if e.is_Add:
            terms = e.as_ordered_terms()
            out = self.term(terms[0], first=True)
            for t in terms[1:]:
                self.adds += 1
                out += self.term(t, first=False)
            return out
        if e.is_Mul:
            return self.product(e)
        if e.is_Pow and e.exp.is_Integer and e.exp > 1:
            base = self.factor(e.base)
            self.muls += int(e.exp) - 1
            return "*".join([base] * int(e.exp))
        raise ValueError(f"cannot print {e!r}")

    def factor(self, e):
        s = self.expr(e)
        return f"({s})" if e.is_Add else s

    def product(self, e):
        coeff, rest = e.as_coeff_Mul()
        factors = sp.Mul.make_args(rest)
        body = [self.factor(f) for f in factors]
        self.muls += len(body) - 1
        if coeff == -1:
            return "-" + "*".join(body)
        if coeff == 1:
            return "*".join(body)
        self.muls += 1
        if coeff < 0:
            return "-" + self.number(-coeff) + "*" + "*".join(body)
        return self.number(coeff) + "*" + "*".join(body)

    def term(self, t, first):
        neg = t.could_extract_minus_sign()
        if first:
            return self.expr(t)
        if neg:
            return " - " + self.expr(-t)
        return " + " + self.expr(t)

    def program(self, defs, indent="  "):
        return "\n".join(f"{indent}const Scalar {s} = {self.expr(e)};" for s, e in defs)
