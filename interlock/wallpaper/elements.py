"""Exact elements of plane crystallographic groups, in lattice coordinates.

An element acts on lattice (fractional) coordinates ``u`` as ``u -> R u + t``
with ``R`` an integer 2x2 matrix and ``t`` a rational 2-vector.  Keeping them
exact makes elements hashable and comparable, so group tables, closures and
orbits never depend on floating-point tolerances.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from interlock.errors import GroupError

__all__ = ["GroupElement", "parse_symop"]

Vector = tuple[Fraction, Fraction]


@dataclass(frozen=True)
class GroupElement:
    """An isometry of the plane written in lattice coordinates, ``u -> R u + t``.

    Parameters
    ----------
    linear : ((int, int), (int, int))
        The matrix ``R`` (rows), integral with determinant +1 or -1.
    translation : (Fraction, Fraction)
        The vector ``t``.

    Examples
    --------
    >>> g = parse_symop("-y,x-y")          # the 3-fold rotation of p3
    >>> (g @ g @ g).is_identity
    True
    >>> str(g.inverse())
    '-x+y,-x'
    """

    linear: tuple[tuple[int, int], tuple[int, int]]
    translation: Vector

    def __post_init__(self):
        (a, b), (c, d) = self.linear
        if a * d - b * c not in (1, -1):
            raise GroupError(
                f"linear part {self.linear} has determinant {a * d - b * c}; "
                "an element of a plane crystallographic group needs determinant +1 or -1"
            )

    # --- algebra -----------------------------------------------------------
    def __matmul__(self, other: GroupElement) -> GroupElement:
        """Composition ``(self @ other)(u) = self(other(u))``."""
        if not isinstance(other, GroupElement):
            return NotImplemented
        R, S = self.linear, other.linear
        linear = tuple(
            tuple(R[i][0] * S[0][j] + R[i][1] * S[1][j] for j in range(2)) for i in range(2)
        )
        return GroupElement(linear, self.apply_exact(other.translation))

    def inverse(self) -> GroupElement:
        """The inverse ``u -> R^-1 (u - t)``."""
        (a, b), (c, d) = self.linear
        det = a * d - b * c
        inv = ((d * det, -b * det), (-c * det, a * det))  # det = +-1, so 1/det = det
        t = self.translation
        return GroupElement(inv, tuple(-(inv[i][0] * t[0] + inv[i][1] * t[1]) for i in range(2)))

    def apply_exact(self, point: Vector) -> Vector:
        """Image of one point given exactly (Fractions or ints)."""
        (a, b), (c, d) = self.linear
        x, y = point
        return (a * x + b * y + self.translation[0], c * x + d * y + self.translation[1])

    # --- properties --------------------------------------------------------
    @property
    def det(self) -> int:
        (a, b), (c, d) = self.linear
        return a * d - b * c

    @property
    def is_identity(self) -> bool:
        return self.linear == ((1, 0), (0, 1)) and self.translation == (0, 0)

    @property
    def is_translation(self) -> bool:
        return self.linear == ((1, 0), (0, 1))

    @property
    def order_of_linear_part(self) -> int:
        """Smallest ``n >= 1`` with ``R^n = I`` (1, 2, 3, 4 or 6)."""
        power, n = self, 1
        while not power.is_translation:
            power, n = power @ self, n + 1
        return n

    @property
    def kind(self) -> str:
        """One of 'identity', 'translation', 'rotation', 'reflection', 'glide reflection'."""
        if self.is_translation:
            return "identity" if self.is_identity else "translation"
        if self.det == 1:
            return "rotation"
        return "reflection" if (self @ self).is_identity else "glide reflection"

    def rotation_centre(self) -> Vector | None:
        """The fixed point of a rotation (exact, lattice coordinates), else ``None``."""
        if self.kind != "rotation":
            return None
        (a, b), (c, d) = self.linear
        # solve (R - I) u = -t by Cramer's rule; R - I is invertible for a rotation
        m00, m01, m10, m11 = a - 1, b, c, d - 1
        det = Fraction(m00 * m11 - m01 * m10)
        tx, ty = (-self.translation[0], -self.translation[1])
        return ((tx * m11 - m01 * ty) / det, (m00 * ty - m10 * tx) / det)

    def affine(self) -> np.ndarray:
        """The 3x3 affine matrix in lattice coordinates, as floats."""
        (a, b), (c, d) = self.linear
        tx, ty = self.translation
        return np.array([[a, b, float(tx)], [c, d, float(ty)], [0.0, 0.0, 1.0]])

    def shifted(self, shift) -> GroupElement:
        """``t_shift @ self``: the same element followed by a lattice translation."""
        return GroupElement(
            self.linear, (self.translation[0] + int(shift[0]), self.translation[1] + int(shift[1]))
        )

    def __str__(self) -> str:
        return ",".join(_coordinate(row, t) for row, t in zip(self.linear, self.translation))

    def __repr__(self) -> str:
        return f"GroupElement('{self}')"


def parse_symop(text: str) -> GroupElement:
    """Parse a coordinate triplet in the notation of the International Tables.

    >>> str(parse_symop("-x+1/2, y+1/2"))
    '-x+1/2,y+1/2'
    """
    parts = [p.strip() for p in text.replace(" ", "").split(",")]
    if len(parts) != 2:
        raise GroupError(f"symmetry operation {text!r} must have two comma-separated coordinates, e.g. '-y,x-y'")
    rows, trans = [], []
    for part in parts:
        coeff = {"x": Fraction(0), "y": Fraction(0), "": Fraction(0)}
        terms = re.findall(r"([+-]?)(\d+(?:/\d+)?)?([xy]?)", part)
        if "".join(s + n + v for s, n, v in terms) != part or not part:
            raise GroupError(f"cannot read coordinate {part!r} in {text!r}; expected terms like -x, y, 1/2")
        for sign, number, var in terms:
            if not (number or var):
                continue
            value = Fraction(number) if number else Fraction(1)
            coeff[var] += -value if sign == "-" else value
        if coeff["x"].denominator != 1 or coeff["y"].denominator != 1:
            raise GroupError(f"linear coefficients of {text!r} must be integers")
        rows.append((int(coeff["x"]), int(coeff["y"])))
        trans.append(coeff[""])
    return GroupElement(tuple(rows), tuple(trans))


def _coordinate(row, t) -> str:
    text = ""
    for coefficient, var in zip(row, "xy"):
        if coefficient:
            sign = "-" if coefficient < 0 else ("+" if text else "")
            magnitude = "" if abs(coefficient) == 1 else str(abs(coefficient))
            text += f"{sign}{magnitude}{var}"
    if t:
        text += f"{'-' if t < 0 else ('+' if text else '')}{abs(t)}"
    return text or "0"
