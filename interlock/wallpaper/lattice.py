"""Lattice parameters of the five plane crystal systems: defaults and validation."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from interlock.errors import LatticeError

__all__ = ["LatticeParameters", "lattice_parameters", "conventional_basis", "LENGTH_RANGE", "GAMMA_MARGIN"]

#: Relative tolerance for "b equals a" and "gamma equals 90/120 degrees".
PARAMETER_RTOL = 1e-9

_DEFAULT_OBLIQUE_GAMMA = 75.0

#: The cell lengths ``a`` and ``b`` allowed.  Blocks are built from cells of these lengths, their volumes are
#: cubes of lengths and their contacts products of them, so far beyond (1e100) areas, volumes and squared
#: distances overflow float64; 1e30 also keeps a patch of a few hundred cells within float32 (3.4e38, the STL,
#: GLB and 3MF coordinates) and far within ``interlock.blocks.assembly.MAX_COORDINATE``; 1e-30 keeps volumes of
#: such cells (1e-90) far above float64's smallest numbers.
LENGTH_RANGE = (1e-30, 1e30)
#: How far (degrees) gamma must stay from 0 and 180: a cell flatter than that (sin gamma < 2e-5) has tiles a
#: hundred thousand times longer than wide, whose blocks the mesh checks cannot tell from flat ones (gamma =
#: 1e-300 made an Escher block that is no closed surface).
GAMMA_MARGIN = 1e-3

_RULES = {
    # system: (b must equal a, required gamma or None, text for the message)
    "oblique": (False, None, "any a > 0, b > 0 and 0 < gamma < 180 degrees"),
    "rectangular": (False, 90.0, "a > 0, b > 0 and gamma = 90 degrees"),
    "centred rectangular": (False, 90.0, "a > 0, b > 0 (the centred conventional cell) and gamma = 90 degrees"),
    "square": (True, 90.0, "a > 0, b = a and gamma = 90 degrees"),
    "hexagonal": (True, 120.0, "a > 0, b = a and gamma = 120 degrees"),
}


@dataclass(frozen=True)
class LatticeParameters:
    """Conventional cell parameters: lengths ``a``, ``b`` and the angle ``gamma`` in degrees."""

    a: float
    b: float
    gamma: float


def lattice_parameters(group_name: str, system: str, a=1.0, b=None, gamma=None) -> LatticeParameters:
    """Fill in the crystal system's defaults and reject parameters it does not allow.

    Defaults: ``b = a``; ``gamma`` = 90 degrees (rectangular, square), 120
    degrees (hexagonal) and 75 degrees for the oblique groups p1 and p2, so
    that their default lattice has no extra symmetry of angle.
    """
    b_equals_a, required_gamma, allowed = _RULES[system]
    a = _length("a", a, group_name, allowed)
    b = a if b is None else _length("b", b, group_name, allowed)
    if gamma is None:
        gamma = required_gamma if required_gamma is not None else _DEFAULT_OBLIQUE_GAMMA
    gamma = _number("gamma", gamma, group_name, allowed)
    if not 0.0 < gamma < 180.0:
        raise LatticeError(f"{group_name}: gamma = {gamma} degrees gives a degenerate lattice; allowed: {allowed}")
    if not GAMMA_MARGIN <= gamma <= 180.0 - GAMMA_MARGIN:
        raise LatticeError(f"{group_name}: gamma = {gamma:g} degrees gives a cell too flat for its blocks; allowed: "
                           f"{GAMMA_MARGIN:g} <= gamma <= {180 - GAMMA_MARGIN:g} degrees")
    if b_equals_a and not math.isclose(a, b, rel_tol=PARAMETER_RTOL):
        raise LatticeError(f"{group_name} has a {system} lattice, so b must equal a (got a = {a}, b = {b}); allowed: {allowed}")
    if required_gamma is not None and not math.isclose(gamma, required_gamma, rel_tol=PARAMETER_RTOL):
        raise LatticeError(f"{group_name} has a {system} lattice, so gamma must be {required_gamma:g} degrees (got {gamma}); allowed: {allowed}")
    return LatticeParameters(a, a if b_equals_a else b, gamma)


def conventional_basis(params: LatticeParameters) -> np.ndarray:
    """Rows: ``a1 = (a, 0)`` and ``a2 = b (cos gamma, sin gamma)``, a right-handed basis."""
    g = math.radians(params.gamma)
    basis = np.array([[params.a, 0.0], [params.b * math.cos(g), params.b * math.sin(g)]])
    if params.gamma == 90.0:
        basis[1, 0] = 0.0
    return basis


def _number(name, value, group_name, allowed) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise LatticeError(f"{group_name}: {name} must be a real number, got {value!r}; allowed: {allowed}") from None
    if not math.isfinite(value):
        raise LatticeError(f"{group_name}: {name} = {value} is not finite; allowed: {allowed}")
    return value


def _length(name, value, group_name, allowed) -> float:
    value = _number(name, value, group_name, allowed)
    if value <= 0.0:
        raise LatticeError(f"{group_name}: the length {name} = {value} must be positive; allowed: {allowed}")
    low, high = LENGTH_RANGE
    if not low <= value <= high:
        raise LatticeError(f"{group_name}: the length {name} = {value:g} is outside {low:g}..{high:g}, where areas "
                           "and volumes of the blocks would overflow or underflow float64; give the lattice in "
                           "other units")
    return value
