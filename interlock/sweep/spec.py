"""What a design-space sweep explores: a TOML spec, read into a :class:`SweepSpec`.

A spec names the family of blocks (a wallpaper group and the intermediate
points of its deformed edges, or RhomBlocks on random lozenge tilings), the
parameters that vary (grids of values, or random samples with a seed) and
the verdicts to compute at every point.  Every number of the family may be a
parameter's name instead::

    group = "p4"
    verdicts = ["periodic", "criterion_4_3"]

    [parameters]
    t = {range = [0.2, 0.8], steps = 7}     # 7 values, ends included
    s = {range = [-0.2, 0.2], steps = 9}
    # h = {values = [0.5, 1.0, 2.0]}         # explicit values

    [[points]]                 # one intermediate point of edge 0 (Escher trick)
    edge = 0
    along = "t"                # fraction of the edge, from vertex `edge` to `edge + 1`
    offset = "s"               # distance off the edge's line, in edge lengths, to its left

The points are the full grid (in the order of ``[parameters]``, last fastest)
unless ``samples = N`` asks for N points drawn uniformly from the ranges
(``values`` draw from their list) with ``seed``.  RhomBlocks::

    verdicts = ["patch"]
    [tiling]
    kind = "hexagon"           # random_hexagon(a, b, c, seed)
    a = 2
    b = 2
    c = "c"
    seed = "k"                 # the tiling's random seed, a parameter here
    variant = 0

Top-level options: ``height`` (1.0), ``patch_radius`` (1.5 cells, for the
"patch" and "stability" verdicts of Escher blocks), ``mu`` (0.5, for
"stability"), ``chunk`` (points per task, 8).

Every value is checked when the spec is read, before any point is
computed: an edge the group's fundamental domain does not have, a height or
a friction coefficient out of range, a tiling size that is not a whole
number >= 0 (also among a parameter's values) is a :class:`SweepError`.
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from interlock.errors import InterlockError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["SweepError", "SweepSpec", "Parameter", "load_spec", "VERDICTS", "MAX_STEPS", "SAMPLE_BLOCK", "Steps"]

#: The verdicts a sweep can compute, and what they call.
VERDICTS = {
    "periodic": "periodic_check of the block's periodic cell (the infinite assembly)",
    "criterion_4_3": "Criterion 4.3 of the main paper, exactly",
    "patch": "check of a finite patch with its outer ring fixed",
    "stability": "rbe under gravity of that patch at friction mu",
}
ESCHER_VERDICTS = tuple(VERDICTS)
TILING_VERDICTS = ("patch", "stability")
TILING_KINDS = ("hexagon",)
TILING_KEYS = {"kind", "a", "b", "c", "seed", "variant"}
POINT_KEYS = {"edge", "along", "offset"}
TOP_KEYS = {"group", "tiling", "verdicts", "parameters", "points", "samples", "seed", "height", "patch_radius",
            "mu", "chunk", "name"}
#: The most values one parameter's range may be cut into (``steps``): ten million floats are 80 MB; the
#: number of points of the whole sweep is bounded when it runs (``interlock.sweep.run.MAX_POINTS``).
MAX_STEPS = 10_000_000
#: Sampled points are drawn this many at a time (:meth:`SweepSpec.iter_points`): 8 MB per parameter, and up to
#: this many samples (the default limit of a run, ``MAX_POINTS``) the very points interlock 0.1 drew.
SAMPLE_BLOCK = 1_000_000


class SweepError(InterlockError):
    """Bad sweep input: a spec, a parameter or records that cannot be used."""


class Steps(Sequence):
    """``steps`` values from ``low`` to ``high``, ends included, each rounded to 12 significant digits (0.3,
    not 0.29999999999999993): the values of ``numpy.linspace(low, high, steps)``, made when asked for, so a
    range of ten million steps costs nothing to read, check, copy to a worker or run through.

    >>> Steps(0.0, 1.0, 11)[3], len(Steps(0.0, 1.0, 10**7)), Steps(0.0, 1.0, 3)[:]
    (0.3, 10000000, (0.0, 0.5, 1.0))
    """

    def __init__(self, low: float, high: float, steps: int):
        self.low, self.high, self.steps = float(low), float(high), int(steps)
        self._step = (self.high - self.low) / (self.steps - 1) if self.steps > 1 else 0.0

    def __len__(self) -> int:
        return self.steps

    def __getitem__(self, index):
        if isinstance(index, slice):
            return tuple(self[i] for i in range(*index.indices(self.steps)))
        i = range(self.steps)[index]  # negative indices; IndexError past the end
        value = self.high if i == self.steps - 1 else i * self._step + self.low  # as numpy.linspace computes it
        return float(f"{value:.12g}")

    def __eq__(self, other) -> bool:
        if isinstance(other, Steps):
            return (self.low, self.high, self.steps) == (other.low, other.high, other.steps)
        return isinstance(other, Sequence) and len(other) == len(self) and tuple(other) == tuple(self)

    def __hash__(self) -> int:
        return hash((self.low, self.high, self.steps))

    def __repr__(self) -> str:
        return f"Steps({self.low!r}, {self.high!r}, {self.steps!r})"


@dataclass(frozen=True)
class Parameter:
    """One varying number: ``values`` on a grid, or ``low .. high`` (or ``values``) when sampled."""

    name: str
    values: Sequence[float]  # a tuple, or the Steps of a range
    low: float | None = None
    high: float | None = None

    def sample(self, rng: np.random.Generator, count: int) -> np.ndarray:
        if self.low is None:
            return rng.choice(np.asarray(self.values), size=count)
        return rng.uniform(self.low, self.high, size=count)


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep spec (see the module docstring for the TOML form).

    ``family`` is ``{"group": name, "height": ..., "points": [{"edge", "along", "offset"}]}`` or
    ``{"tiling": {"kind", "a", "b", "c", "seed", "variant"}}``, where any number may be a parameter's name.
    """

    family: dict
    parameters: tuple[Parameter, ...]
    verdicts: tuple[str, ...]
    samples: int = 0
    seed: int = 0
    patch_radius: float = 1.5
    mu: float = 0.5
    chunk: int = 8
    name: str = "sweep"
    source: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def size(self) -> int:
        """The number of points, computed without making them.

        >>> load_spec({"group": "p1", "parameters": {"s": {"range": [0, 1], "steps": 100000},
        ...            "t": {"range": [0, 1], "steps": 100000}}}).size
        10000000000
        """
        return self.samples or math.prod(len(p.values) for p in self.parameters)

    @property
    def fingerprint(self) -> str:
        """What a record of this spec means: the family, the verdicts and the options that change them.

        A hash (SHA-256, 16 hex digits) of the family, the parameters' names, the
        verdicts, ``patch_radius`` and ``mu``; not of the points themselves
        (a grid may be extended and resumed), which :func:`~interlock.sweep.run`
        compares record by record, nor of ``chunk`` and ``name``.
        """
        meaning = {"family": self.family, "parameters": [p.name for p in self.parameters],
                   "verdicts": list(self.verdicts), "patch_radius": self.patch_radius, "mu": self.mu}
        return hashlib.sha256(json.dumps(meaning, sort_keys=True).encode()).hexdigest()[:16]

    def points(self) -> list[dict]:
        """Every point of the sweep, in order: ``{name: value}`` per point (deterministic for a seed).

        A list of :attr:`size` dicts; :meth:`iter_points` makes the same points one at a time.
        """
        return list(self.iter_points())

    def iter_points(self):
        """The points of :meth:`points`, made as they are needed: memory does not grow with the sweep.

        A grid runs through the parameters' values (last fastest).  Samples
        are drawn in blocks of :data:`SAMPLE_BLOCK` points: up to one block,
        column after column from one generator seeded with ``seed`` (as
        interlock 0.1 drew them); beyond, block ``b`` from a generator
        seeded with ``[seed, b]``, so no column of the whole sweep is ever
        held.

        >>> spec = load_spec({"group": "p1", "parameters": {"s": {"range": [0, 1], "steps": 10**7},
        ...                   "t": {"range": [0, 1], "steps": 10**7}}})
        >>> points = spec.iter_points()
        >>> spec.size, next(points), next(points)["t"]
        (100000000000000, {'s': 0.0, 't': 0.0}, 1.0000001e-07)
        """
        names = [p.name for p in self.parameters]
        if not self.samples:  # an odometer over the values' indices (itertools.product would copy every range)
            values = [p.values for p in self.parameters]
            sizes = [len(v) for v in values]
            if 0 in sizes:
                return
            digits = [0] * len(values)
            current = [float(v[0]) for v in values]
            for _ in range(self.size):
                yield dict(zip(names, current))
                k = len(digits) - 1
                while k >= 0:
                    digits[k] += 1
                    if digits[k] < sizes[k]:
                        current[k] = float(values[k][digits[k]])
                        break
                    digits[k], current[k] = 0, float(values[k][0])
                    k -= 1
            return
        single = self.samples <= SAMPLE_BLOCK
        for block, start in enumerate(range(0, self.samples, SAMPLE_BLOCK)):
            count = min(SAMPLE_BLOCK, self.samples - start)
            rng = np.random.default_rng(self.seed if single else [self.seed, block])
            columns = [p.sample(rng, count) for p in self.parameters]
            for i in range(count):
                yield {n: float(c[i]) for n, c in zip(names, columns)}

    def theory(self, x: str, y: str) -> list[dict]:
        """Overlay lines for a map over parameters ``x`` and ``y``: where a swept ``offset`` is 0 the
        intermediate point lies on its edge (collinear), so that edge is not deformed there and
        Criterion 4.3 may change."""
        lines = []
        for point in self.family.get("points", ()):
            for axis, name in (("x", x), ("y", y)):
                if point["offset"] == name:
                    lines.append({"axis": axis, "value": 0.0,
                                  "label": f"point on edge {point['edge']} (collinear, edge undeformed)"})
        return lines


def load_spec(source) -> SweepSpec:
    """Read a spec from a TOML file path or a dict (as :func:`tomllib.loads` gives).

    >>> spec = load_spec({"group": "p4", "verdicts": ["criterion_4_3"],
    ...                   "parameters": {"s": {"range": [-0.1, 0.1], "steps": 3}},
    ...                   "points": [{"edge": 0, "along": 0.5, "offset": "s"}]})
    >>> [p["s"] for p in spec.points()]
    [-0.1, 0.0, 0.1]
    """
    if isinstance(source, (str, Path)):
        path = Path(source)
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise SweepError(f"no sweep spec at {path}") from None
        except IsADirectoryError:
            raise SweepError(f"{path} is a folder; give the sweep spec, a TOML file") from None
        except UnicodeDecodeError:
            raise SweepError(f"{path} is not a text file; give the sweep spec, a TOML file") from None
        except OSError as error:
            raise SweepError(f"cannot read the sweep spec {path}: {error.strerror or error}") from None
        except tomllib.TOMLDecodeError as error:
            raise SweepError(f"{path} is not valid TOML: {error}") from None
    elif isinstance(source, dict):
        data = source
    else:
        raise SweepError(f"a sweep spec is a TOML file path or a dict, got {type(source).__name__}")
    unknown = set(data) - TOP_KEYS
    if unknown:
        raise SweepError(f"unknown spec keys {sorted(unknown)}; known: {sorted(TOP_KEYS)}")
    parameters = tuple(_parameter(name, value) for name, value in _table(data, "parameters").items())
    names = {p.name for p in parameters}
    family = _family(data, names)
    verdicts = data.get("verdicts", ["periodic"] if "group" in data else ["patch"])
    allowed = ESCHER_VERDICTS if "group" in family else TILING_VERDICTS
    if not isinstance(verdicts, list) or not verdicts or any(v not in allowed for v in verdicts):
        raise SweepError(f"verdicts must be a non-empty list from {list(allowed)}, got {verdicts!r}")
    samples = _integer(data.get("samples", 0), "samples", 0)
    if not samples and any(p.low is not None and len(p.values) == 0 for p in parameters):
        raise SweepError("a range without steps can only be sampled: give steps, or samples = N")
    mu = _number(data.get("mu", 0.5), "mu")
    if mu < 0:
        raise SweepError(f"mu, the friction coefficient, must be >= 0, got {mu}")
    _check_values(family, {p.name: p for p in parameters}, samples)
    return SweepSpec(family, parameters, tuple(verdicts), samples, _integer(data.get("seed", 0), "seed", 0),
                     _number(data.get("patch_radius", 1.5), "patch_radius", positive=True),
                     mu, _integer(data.get("chunk", 8), "chunk", 1),
                     str(data.get("name", Path(source).stem if isinstance(source, (str, Path)) else "sweep")), data)


def _check_values(family: dict, parameters: dict, samples: int) -> None:
    """Every value a point can take is allowed where it is used: a bad spec fails before any point is computed.

    Heights are > 0; tiling sizes and seeds whole numbers >= 0 and the variant 0 or 1, also every value
    of a parameter used there (a sampled range gives no whole numbers: use ``values``).
    """
    if "group" in family:
        from interlock.wallpaper.lattice import LENGTH_RANGE  # a block's volumes are products of its lengths

        _check_place(family["height"], "height", parameters, samples, lambda v: 0 < v <= LENGTH_RANGE[1],
                     "a number > 0" + (f" and at most {LENGTH_RANGE[1]:g}" if _largest(family["height"], parameters)
                                       > LENGTH_RANGE[1] else ""))
        return
    for key in ("a", "b", "c", "seed", "variant"):
        allowed = (lambda v: v in (0, 1)) if key == "variant" else (lambda v: v >= 0 and float(v).is_integer())
        meaning = "0 or 1" if key == "variant" else "a whole number >= 0"
        _check_place(family["tiling"][key], f"tiling.{key}", parameters, samples, allowed, meaning,
                     whole=True)


def _largest(value, parameters: dict) -> float:
    """The largest value a fixed number or a parameter's values (or range) takes."""
    if not isinstance(value, str):
        return value
    parameter = parameters[value]
    return parameter.high if parameter.low is not None else max(parameter.values)


def _check_place(value, what: str, parameters: dict, samples: int, allowed, meaning: str, whole=False) -> None:
    """Check a fixed value, or every value of the parameter named ``value``, against ``allowed``."""
    if not isinstance(value, str):
        if not allowed(value):
            raise SweepError(f"{what} must be {meaning}, got {value:g}")
        return
    parameter = parameters[value]
    if samples and parameter.low is not None:
        if whole:
            raise SweepError(f"{what} takes whole numbers, but parameter {value!r} is sampled from a range; "
                             "give it values = [...]")
        values = (parameter.low, parameter.high)
    else:
        values = parameter.values
    bad = [v for v in values if not allowed(v)]
    if bad:
        raise SweepError(f"{what} must be {meaning}, but parameter {value!r} takes {bad[0]:g}")


def _family(data: dict, names: set) -> dict:
    if ("group" in data) == ("tiling" in data):
        raise SweepError("a spec names exactly one family: group = \"p4\" (Escher blocks) or [tiling] (RhomBlocks)")
    if "tiling" in data:
        tiling = _table(data, "tiling")
        if set(tiling) - TILING_KEYS or tiling.get("kind", "hexagon") not in TILING_KINDS:
            raise SweepError(f"[tiling] takes kind = {TILING_KINDS} and {sorted(TILING_KEYS - {'kind'})}, "
                             f"got {tiling}")
        values = {key: _value(tiling.get(key, default), f"tiling.{key}", names)
                  for key, default in (("a", 2), ("b", 2), ("c", 2), ("seed", 0), ("variant", 0))}
        return {"tiling": {"kind": tiling.get("kind", "hexagon"), **values}}
    from interlock import wallpaper

    group = data["group"]
    try:
        wallpaper.group(group)
    except InterlockError as error:
        raise SweepError(f"group: {error}") from None
    points = data.get("points", [])
    if not isinstance(points, list):
        raise SweepError("points must be an array of tables [[points]] with edge, along, offset")
    parsed = []
    for k, point in enumerate(points):
        if not isinstance(point, dict) or set(point) != POINT_KEYS:
            raise SweepError(f"points[{k}] needs exactly the keys {sorted(POINT_KEYS)}, got {point!r}")
        edges = len(wallpaper.group(group).side_pairings())
        edge = point["edge"]
        if isinstance(edge, float) and edge.is_integer() and 0 <= edge < edges:
            raise SweepError(f"points[{k}].edge is an edge's index, a whole number written without a decimal point: "
                             f"edge = {int(edge)}, not {edge!r} ({group}'s fundamental domain has edges "
                             f"0..{edges - 1})")
        if isinstance(edge, bool) or not (isinstance(edge, int) and 0 <= edge < edges):
            raise SweepError(f"points[{k}].edge must be an edge of {group}'s fundamental domain, 0..{edges - 1}, "
                             f"got {edge!r}")
        parsed.append({"edge": _integer(point["edge"], f"points[{k}].edge", 0),
                       "along": _value(point["along"], f"points[{k}].along", names),
                       "offset": _value(point["offset"], f"points[{k}].offset", names)})
    return {"group": group, "height": _value(data.get("height", 1.0), "height", names), "points": parsed}


def _parameter(name: str, value) -> Parameter:
    if not isinstance(value, dict):
        raise SweepError(f"parameter {name!r} must be a table: {{range = [low, high], steps = n}} or "
                         f"{{values = [...]}}, got {value!r}")
    if "values" in value and set(value) == {"values"}:
        values = value["values"]
        if not isinstance(values, list) or not values:
            raise SweepError(f"parameter {name!r}: values must be a non-empty list of numbers")
        return Parameter(name, tuple(_number(v, f"parameter {name!r}") for v in values))
    if "range" in value and set(value) <= {"range", "steps"}:
        low_high = value["range"]
        if not (isinstance(low_high, list) and len(low_high) == 2):
            raise SweepError(f"parameter {name!r}: range must be [low, high], got {low_high!r}")
        low, high = (_number(v, f"parameter {name!r}") for v in low_high)
        if not low < high:
            raise SweepError(f"parameter {name!r}: range needs low < high, got [{low}, {high}]")
        steps = _integer(value.get("steps", 0), f"parameter {name!r} steps", 0)
        if steps == 1 or steps > MAX_STEPS:
            raise SweepError(f"parameter {name!r}: steps must be 0 (sampled only) or 2..{MAX_STEPS:,}, "
                             f"got {steps:,}")
        return Parameter(name, Steps(low, high, steps), low, high)
    raise SweepError(f"parameter {name!r} must be {{range = [low, high], steps = n}} or {{values = [...]}}, "
                     f"got {value!r}")


def _table(data: dict, key: str) -> dict:
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise SweepError(f"[{key}] must be a table, got {value!r}")
    return value


def _value(value, what: str, names: set):
    if isinstance(value, str):
        if value not in names:
            raise SweepError(f"{what} names the parameter {value!r}, which [parameters] does not define "
                             f"(defined: {sorted(names)})")
        return value
    return _number(value, what)


def _number(value, what: str, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SweepError(f"{what} must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise SweepError(f"{what} must be positive, got {value!r}")
    return float(value)


def _integer(value, what: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < least:
        hint = (f" (TOML: write {int(value)}, without a decimal point)"
                if isinstance(value, float) and value.is_integer() and value >= least else "")
        raise SweepError(f"{what} must be an integer >= {least}, got {value!r}{hint}")
    return value
