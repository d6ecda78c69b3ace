"""Track shapes y = f(x) written as text in a scene file.

A small whitelist parser: numbers, the variable ``x``, ``+ - * / **``,
parentheses and the functions ``sin cos exp sqrt``. Scene text is never
passed to ``eval``; it becomes a tree of frozen nodes that can be

* evaluated with any numeric library (numpy, mpmath, or heyoka's expression
  system: the caller passes the functions), and
* differentiated symbolically, so f', f'' and f''' are exact expressions too.

Numbers keep their decimal text, so an mpmath evaluation sees 0.1 as 1/10
to working precision and not as the nearest double.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from decimal import Decimal
from typing import Callable, Mapping, Union

from ..errors import SceneError

FUNCTIONS = ("sin", "cos", "exp", "sqrt")

_TOKEN = re.compile(
    r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)|(?P<name>[A-Za-z_]\w*)|(?P<op>\*\*|[-+*/()]))"
)


@dataclass(frozen=True)
class Num:
    text: str


@dataclass(frozen=True)
class Var:
    pass


@dataclass(frozen=True)
class Neg:
    arg: "Node"


@dataclass(frozen=True)
class Bin:
    op: str
    left: "Node"
    right: "Node"


@dataclass(frozen=True)
class Call:
    fn: str
    arg: "Node"


Node = Union[Num, Var, Neg, Bin, Call]
X = Var()
ZERO, ONE, TWO = Num("0"), Num("1"), Num("2")


class ExpressionError(SceneError):
    """A track expression breaks the grammar."""


#: Limits that keep a hostile expression from exhausting the parser or the recursion in
#: evaluation and differentiation (measured: 20,000 terms or 3,000 nested parentheses
#: ended in RecursionError): characters, and the depth of the expression tree.
MAX_EXPRESSION_LENGTH = 2000
MAX_EXPRESSION_DEPTH = 100


def parse(text: str, field: str = "track.y", variable: str = "x") -> Node:
    """Parse ``text`` into an expression tree; raises ExpressionError (a SceneError).

    ``variable``: the name of the one variable (x for y = f(x); u for a parametric curve).
    """
    if not isinstance(text, str):
        raise ExpressionError(field, f"must be a string expression in {variable}, got {text!r}")
    if len(text) > MAX_EXPRESSION_LENGTH:
        raise ExpressionError(field, f"is {len(text)} characters long; at most {MAX_EXPRESSION_LENGTH} are allowed")
    tokens = _tokenize(text, field, variable)
    depth = deepest = 0
    for kind, value in tokens:
        depth += value == "(" and 1 or value == ")" and -1 or 0
        deepest = max(deepest, depth)
    if deepest > MAX_EXPRESSION_DEPTH // 2:
        raise ExpressionError(field, f"nests parentheses {deepest} deep; at most {MAX_EXPRESSION_DEPTH // 2} are allowed")
    parser = _Parser(tokens, field, text, variable)
    node = parser.expression()
    if parser.pos != len(tokens):
        raise ExpressionError(field, f"unexpected {tokens[parser.pos][1]!r} in {text!r}")
    if _depth(node) > MAX_EXPRESSION_DEPTH:
        raise ExpressionError(field, f"is nested more than {MAX_EXPRESSION_DEPTH} operations deep (a chain of "
                              "that many terms or factors); write it shorter")
    return node


def denominators(node: Node):
    """The sub-expressions a formula divides by: right sides of '/', bases of negative powers. Where one
    changes sign on an interval the formula has a pole there (1/x on [-2, 2.2]), which samples may straddle."""
    stack = [node]
    while stack:
        n = stack.pop()
        if isinstance(n, Bin):
            if n.op == "/":
                yield n.right
            elif n.op == "**" and isinstance(n.right, Num) and Decimal(n.right.text) < 0:
                yield n.left
            elif n.op == "**" and isinstance(n.right, Neg) and isinstance(n.right.arg, Num):
                yield n.left
        for child in (getattr(n, "left", None), getattr(n, "right", None), getattr(n, "arg", None)):
            if child is not None:
                stack.append(child)


def _depth(node: Node) -> int:
    """Depth of an expression tree, without recursion."""
    deepest, stack = 0, [(node, 1)]
    while stack:
        n, d = stack.pop()
        deepest = max(deepest, d)
        for child in (getattr(n, "left", None), getattr(n, "right", None), getattr(n, "arg", None)):
            if child is not None:
                stack.append((child, d + 1))
    return deepest


def _tokenize(text: str, field: str, variable: str = "x") -> list[tuple[str, str]]:
    tokens, pos = [], 0
    text = text.rstrip()
    if not text:
        raise ExpressionError(field, f"empty expression: give a function of {variable}, e.g. \"0.5*{variable}**2\"")
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m or m.end() == pos:
            raise ExpressionError(field, f"character {text[pos]!r} at position {pos} is not allowed "
                                  f"(numbers, {variable}, + - * / **, parentheses, sin cos exp sqrt)")
        kind = m.lastgroup
        value = m.group(kind)
        if kind == "name" and value != variable and value not in FUNCTIONS:
            raise ExpressionError(field, f"unknown name {value!r}; allowed: {variable}, {', '.join(FUNCTIONS)}")
        tokens.append((kind, value))
        pos = m.end()
    return tokens


class _Parser:
    """Recursive descent: expr := term (+|- term)*; term := unary (*|/ unary)*;
    unary := (+|-) unary | power; power := atom (** unary)?  (right-assoc)."""

    def __init__(self, tokens, field, text, variable="x"):
        self.tokens, self.pos, self.field, self.text, self.variable = tokens, 0, field, text, variable

    def peek(self):
        return self.tokens[self.pos] if self.pos < len(self.tokens) else (None, None)

    def take(self, value=None):
        kind, tok = self.peek()
        if tok is None:
            raise ExpressionError(self.field, f"expression {self.text!r} ends too early")
        if value is not None and tok != value:
            raise ExpressionError(self.field, f"expected {value!r}, got {tok!r} in {self.text!r}")
        self.pos += 1
        return kind, tok

    def expression(self):
        node = self.term()
        while self.peek()[1] in ("+", "-"):
            _, op = self.take()
            node = Bin(op, node, self.term())
        return node

    def term(self):
        node = self.unary()
        while self.peek()[1] in ("*", "/"):
            _, op = self.take()
            node = Bin(op, node, self.unary())
        return node

    def unary(self):
        if self.peek()[1] in ("+", "-"):
            _, op = self.take()
            arg = self.unary()
            return Neg(arg) if op == "-" else arg
        return self.power()

    def power(self):
        base = self.atom()
        if self.peek()[1] == "**":
            self.take()
            return Bin("**", base, self.unary())
        return base

    def atom(self):
        kind, tok = self.take()
        if kind == "num":
            return Num(tok)
        if tok == self.variable:
            return X
        if kind == "name":
            self.take("(")
            arg = self.expression()
            self.take(")")
            return Call(tok, arg)
        if tok == "(":
            node = self.expression()
            self.take(")")
            return node
        raise ExpressionError(self.field, f"unexpected {tok!r} in {self.text!r}")


# ---------------------------------------------------------------- evaluation

@dataclass(frozen=True)
class Library:
    """How to evaluate a tree: a number constructor and the four functions."""

    number: Callable[[str], object]
    functions: Mapping[str, Callable]
    #: ``a ** n`` for a whole n, where ``a ** n`` itself will not do (None: ``a ** n``)
    whole_power: Callable | None = None


def evaluate(node: Node, x, lib: Library):
    """Value of ``node`` at ``x`` with the library's numbers and functions."""
    if isinstance(node, Num):
        return lib.number(node.text)
    if isinstance(node, Var):
        return x
    if isinstance(node, Neg):
        return -evaluate(node.arg, x, lib)
    if isinstance(node, Call):
        return lib.functions[node.fn](evaluate(node.arg, x, lib))
    a, b = evaluate(node.left, x, lib), evaluate(node.right, x, lib)
    if node.op == "+":
        return a + b
    if node.op == "-":
        return a - b
    if node.op == "*":
        return a * b
    if node.op == "/":
        return a / b
    if isinstance(node.right, Num) and _is_whole(node.right.text):
        n = int(Decimal(node.right.text))  # whole powers stay exact (x**2 == x*x)
        return a ** n if lib.whole_power is None else lib.whole_power(a, n)
    return a**b


def evaluation_error(exc: Exception) -> str:
    """Why evaluating (or folding) an expression failed, without an errno: math's OverflowError says
    "(34, 'Numerical result out of range')" (acceptance test)."""
    return str(exc.args[-1]) if len(exc.args) > 1 else str(exc)


def _is_whole(text: str) -> bool:
    d = Decimal(text)
    return d == d.to_integral_value() and abs(d) <= 64


def to_text(node: Node) -> str:
    """A fully parenthesized text form (round-trips through :func:`parse`)."""
    if isinstance(node, Num):
        return node.text
    if isinstance(node, Var):
        return "x"
    if isinstance(node, Neg):
        return f"(-{to_text(node.arg)})"
    if isinstance(node, Call):
        return f"{node.fn}({to_text(node.arg)})"
    return f"({to_text(node.left)} {node.op} {to_text(node.right)})"


# ------------------------------------------------------------ differentiation

def derivative(node: Node) -> Node:
    """d node / dx, simplified only where a factor is exactly 0 or 1."""
    if isinstance(node, Num):
        return ZERO
    if isinstance(node, Var):
        return ONE
    if isinstance(node, Neg):
        return _neg(derivative(node.arg))
    if isinstance(node, Call):
        u, du = node.arg, derivative(node.arg)
        outer = {
            "sin": lambda: Call("cos", u),
            "cos": lambda: _neg(Call("sin", u)),
            "exp": lambda: node,
            "sqrt": lambda: _div(ONE, _mul(TWO, node)),
        }[node.fn]()
        return _mul(outer, du)
    a, b = node.left, node.right
    da, db = derivative(a), derivative(b)
    if node.op == "+":
        return _add(da, db)
    if node.op == "-":
        return _sub(da, db)
    if node.op == "*":
        return _add(_mul(da, b), _mul(a, db))
    if node.op == "/":
        return _div(_sub(_mul(da, b), _mul(a, db)), _mul(b, b))
    # a ** b
    if _is_zero(db):
        if isinstance(b, Num):
            lowered = Num(str(Decimal(b.text) - 1))
            return _mul(_mul(b, _pow(a, lowered)), da)
        return _mul(_mul(b, _pow(a, _sub(b, ONE))), da)
    # general power: d(a^b) = a^b (b' ln a + b a'/a); ln is not in the grammar,
    # so only constant exponents are differentiable
    raise ExpressionError("track.y", "x may appear in an exponent only through exp(...)")


def _is_zero(n):
    return isinstance(n, Num) and Decimal(n.text) == 0


def _is_one(n):
    return isinstance(n, Num) and Decimal(n.text) == 1


def _neg(a):
    return ZERO if _is_zero(a) else Neg(a)


def _add(a, b):
    if _is_zero(a):
        return b
    if _is_zero(b):
        return a
    return Bin("+", a, b)


def _sub(a, b):
    if _is_zero(b):
        return a
    if _is_zero(a):
        return Neg(b)
    return Bin("-", a, b)


def _mul(a, b):
    if _is_zero(a) or _is_zero(b):
        return ZERO
    if _is_one(a):
        return b
    if _is_one(b):
        return a
    return Bin("*", a, b)


def _div(a, b):
    if _is_zero(a):
        return ZERO
    if _is_one(b):
        return a
    return Bin("/", a, b)


def _pow(a, b):
    if _is_one(b):
        return a
    if _is_zero(b):
        return ONE
    return Bin("**", a, b)


def contains_x(node: Node) -> bool:
    if isinstance(node, Var):
        return True
    if isinstance(node, Num):
        return False
    if isinstance(node, (Neg, Call)):
        return contains_x(node.arg)
    return contains_x(node.left) or contains_x(node.right)


def check_differentiable(node: Node, field: str) -> None:
    """Reject x in an exponent (the grammar has no log to differentiate it)."""
    if isinstance(node, Bin):
        if node.op == "**" and contains_x(node.right):
            raise ExpressionError(field, "x may not appear in an exponent (use exp(...))")
        check_differentiable(node.left, field)
        check_differentiable(node.right, field)
    elif isinstance(node, (Neg, Call)):
        check_differentiable(node.arg, field)


def power_by_products(a, n: int):
    """``a ** n`` for a whole n by squaring and multiplying (1/a^|n| for n < 0): heyoka's pow(x, n) takes its
    Taylor coefficients through a recurrence that divides by x, NaN at x = 0 (a double well y = x**4 - x**2
    failed from a body started on its hump at x = 0: acceptance test); products have none."""
    if n < 0:
        return 1.0 / power_by_products(a, -n)
    result, base = None, a
    while n:
        if n & 1:
            result = base if result is None else result * base
        n >>= 1
        if n:
            base = base * base
    return 1.0 + 0.0 * a if result is None else result
