"""Tables as CSV text: "%.17g" for float64 (17 significant digits round-trip a double).

Python's "%.17g" costs ~0.4 us a number (CPython's dtoa takes its big-integer
path beyond 14 digits), so the CSV rows of a long run cost more than its
integration (issue 12); here float64 columns are formatted with numpy, to the
same text, and Python formats only the numbers where that could differ.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np


def collisions_csv(table: np.ndarray, format_value=None) -> str:
    """The table as CSV text: a header row, then :func:`csv_rows`."""
    return ",".join(table.dtype.names) + "\n" + csv_rows(table, format_value).decode("ascii")


def csv_rows(table: np.ndarray, format_value=None) -> bytes:
    """The rows of a structured table as CSV, one line per row.

    float64 columns are written as ``"%.17g"`` (17 significant digits
    round-trip a double), integer columns as integers, object columns (quad /
    MPFR runs) by ``format_value``.
    """
    kinds = {table.dtype[name].kind for name in table.dtype.names}
    if table.size == 0 or not kinds <= {"f", "i", "u"} or not _exact_in_double(table):
        return _rows_by_value(table, format_value)
    ncol = len(table.dtype.names)
    rows = max(1, _BLOCK // ncol)  # a block's arrays stay in the cache
    last = np.tile(np.arange(ncol) == ncol - 1, rows)
    block = np.empty((rows, ncol))
    parts = []
    for start in range(0, table.size, rows):
        part = table[start:start + rows]
        values = block[:part.size]
        for c, name in enumerate(table.dtype.names):
            values[:, c] = part[name]
        cells = _g17_cells(values.reshape(-1), last[:values.size])
        parts.append(cells.tobytes().translate(None, b"\0"))
    return b"".join(parts)


def _exact_in_double(table: np.ndarray) -> bool:
    """Integer columns go through the float64 writer: exact, and "%.17g" of them is str(), below 2**53."""
    return all(-(2**53) < table[name].min() and table[name].max() < 2**53
               for name in table.dtype.names if table.dtype[name].kind in "iu")


def _rows_by_value(table: np.ndarray, format_value) -> bytes:
    """One number at a time in Python (object columns; ~0.4 us a double)."""
    formatters = []
    for name in table.dtype.names:
        if table.dtype[name].kind in "iuU":  # integers, and text (the friction modes)
            formatters.append(str)
        elif table.dtype[name] == object:
            formatters.append(format_value)
        else:
            formatters.append(lambda x: "%.17g" % x)
    columns = [table[name].tolist() for name in table.dtype.names]
    return "".join(",".join(f(v) for f, v in zip(formatters, values)) + "\n" for values in zip(*columns)).encode()


# -- "%.17g" of float64 arrays with numpy ------------------------------------------------
# Python's "%.17g" costs ~0.4 us a number (CPython's dtoa takes its big-integer path beyond
# 14 digits): the CSV rows of a long run cost more than its integration (issue 12). Here each
# x with 1e-280 <= |x| < 1e280 is scaled to y = |x| 10^(16-k), k = floor(log10 |x|), in
# double-double arithmetic (Dekker's exact product; error < 1e-14 on y < 1e17), rounded to
# the 17-digit integer D = round(y), and D's digits are laid out by a byte template chosen by
# (sign, decimal point position, last digit kept, separator). Where that could differ from
# "%.17g" -- y within 1e-6 of a rounding tie, log10 misjudging k next to a power of ten, zero
# excepted every |x| outside the range, nan, inf -- Python formats the number.
_BLOCK = 8192  # numbers formatted together
_KMIN, _KMAX = -280, 279
_SPLIT = 134217729.0  # 2**27 + 1: Dekker's split of a double into two 26-bit halves
_POWERS = [Fraction(10) ** (16 - k) for k in range(_KMIN, _KMAX + 1)]
_P = np.array([float(p) for p in _POWERS])  # 10^(16-k) = _P + _P_LO to ~2**-106
_P_LO = np.array([float(p - Fraction(hi)) for p, hi in zip(_POWERS, _P.tolist())])
_P_H = _P * _SPLIT - (_P * _SPLIT - _P)
_P_L = _P - _P_H
del _POWERS
#: "0000" .. "9999" as 4-byte words, then an empty word (index 10000).
_WORDS = np.frombuffer(b"".join(b"%04d" % v for v in range(10000)) + bytes(4), dtype=np.uint32)
#: Trailing zeros of a 4-digit group ("0000": 4).
_TRAILING = np.array([4] + [len(str(v)) - len(str(v).rstrip("0")) for v in range(1, 10000)], dtype=np.int64)
#: The exponent of %g's exponential form ("e+17", "e-308"; empty where %g is positional), 8 bytes per k.
_EXPONENT = np.frombuffer(b"".join((b"" if -4 <= k < 17 else b"e%+03d" % k).ljust(8, b"\0")
                                   for k in range(_KMIN, _KMAX + 1)), dtype=np.uint64)
_CELL = 32  # bytes per number: sign, 22 mantissa bytes, one spare, exponent (5) and separator in the last word


def _template(negative: bool, separator: int, point: int, end: int) -> tuple[bytes, bytes, bytes]:
    """A cell's fixed bytes and the masks of its digits.

    The digits are E = "0000" followed by D's 17 digits. The mantissa (cell
    bytes 1..22) is E[min(point, 4)] .. E[point], the decimal point, then the
    rest of E up to mantissa byte ``end`` (trailing zeros dropped): mantissa
    byte j is E[j] before the point (mask ``before``), E[j - 1] after it
    (mask ``after``).
    """
    fixed, before, after = bytearray(_CELL), bytearray(_CELL), bytearray(_CELL)
    fixed[0] = ord("-") if negative else 0
    for j in range(min(point, 4), end + 1):
        if j <= point:
            before[1 + j] = 0xFF
        elif j == point + 1:
            fixed[1 + j] = ord(".")
        else:
            after[1 + j] = 0xFF
    fixed[29] = separator
    return bytes(fixed), bytes(before), bytes(after)


_TEMPLATES = [_template(neg, sep, point, end) for neg in (False, True) for sep in b",\n"
              for point in range(21) for end in range(22)]
_FIXED, _BEFORE, _AFTER = (np.frombuffer(b"".join(t[q] for t in _TEMPLATES), dtype=np.uint8).reshape(-1, _CELL)
                           for q in range(3))
del _TEMPLATES


def _g17_cells(x: np.ndarray, last: np.ndarray) -> np.ndarray:
    """(x.size, _CELL) bytes: "%.17g" % x[n] then "," ("\n" where ``last``), NUL-padded."""
    m = x.size
    a = np.abs(x)
    zero = a == 0
    fast = (a >= 1e-280) & (a < 1e280)
    a[~fast] = 1.0  # zero too: k = 0 then, and D = 0 below prints "0"
    row = np.floor(np.log10(a)).astype(np.intp) - _KMIN  # of the power tables (clipped: checked below)
    # y = a * 10^(16-k) = p + r: p = fl(a _P), r its exact error (Dekker) plus a _P_LO.
    p = a * _P.take(row, mode="clip")
    ah = a * _SPLIT
    ah = ah - (ah - a)
    al = a - ah
    ph, pl = _P_H.take(row, mode="clip"), _P_L.take(row, mode="clip")
    r = ah * ph - p
    r += ah * pl
    r += al * ph
    r += al * pl
    r += a * _P_LO.take(row, mode="clip")
    # y >= 1e16 - 0.04 rounds to 17 digits at exponent k (1e16 included); y < 1e17 - 0.6 to at most 17 nines.
    fast &= ((p - 1e16) + r >= -0.04) & ((p - 1e17) + r < -0.6)  # p - 1e16, p - 1e17 exact where it matters
    whole = np.floor(r)
    r -= whole
    fast &= np.abs(r - 0.5) > 1e-6
    fast |= zero
    d = p.astype(np.int64) + whole.astype(np.int64) + (r > 0.5)  # p > 2**53: an integer
    d[~fast | zero] = 0  # (numbers left to Python: any digits, overwritten below)
    # D's digits: "0000", the leading digit, four 4-digit groups (and 8 empty bytes: the cell's width).
    g = np.empty((m, 8), dtype=np.intp)
    g[:, 0] = 0
    g[:, 6:] = 10000
    high = d // 100000000
    low = d - high * 100000000
    g[:, 1] = high // 100000000
    high -= g[:, 1] * 100000000
    g[:, 2] = high // 10000
    g[:, 3] = high - g[:, 2] * 10000
    g[:, 4] = low // 10000
    g[:, 5] = low - g[:, 4] * 10000
    words = np.empty(m * 8 + 1, dtype=np.uint32)  # one more word: the shifted reads below stay inside
    _WORDS.take(g, out=words[:-1].reshape(m, 8), mode="clip")
    digits = words.view(np.uint8)
    zeros = _TRAILING[g[:, 5]]
    more = g[:, 5] == 0
    for col in (4, 3, 2):
        zeros += more * _TRAILING[g[:, col]]
        more &= g[:, col] == 0
    k = row + _KMIN
    point = np.where((k >= -4) & (k < 17), k + 4, 4)  # %g: positional for -4 <= k < 17
    kept = np.maximum(20 - zeros, point)  # the integer part is written in full
    end = kept + (kept > point)
    key = ((np.signbit(x) * 2 + last) * 21 + point) * 22 + end
    # Cell byte 1 + j holds E[j] = digits byte j + 3 before the point, E[j - 1] after it.
    n = m * _CELL
    out = _FIXED.take(key, axis=0, mode="clip").reshape(n)
    out |= digits[2:n + 2] & _BEFORE.take(key, axis=0, mode="clip").reshape(n)
    out |= digits[1:n + 1] & _AFTER.take(key, axis=0, mode="clip").reshape(n)
    cells = out.reshape(m, _CELL)
    cells.view(np.uint64)[:, 3] |= _EXPONENT.take(row, mode="clip")
    for q in np.flatnonzero(~fast).tolist():
        text = b"%.17g" % float(x[q])
        cells[q, :29] = 0
        cells[q, :len(text)] = np.frombuffer(text, dtype=np.uint8)
    return cells
