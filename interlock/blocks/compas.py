"""Deprecated: COMPAS assembly JSON moved to :mod:`interlock.formats.compas`; the old path is removed in interlock 0.3.
"""

from interlock import deprecation

__all__: list[str] = []

_NAMES = ["read_compas", "write_compas", "fingerprint", "UPSTREAM_SUPPORTS", "UPSTREAM_FINGERPRINTS",
          "FINGERPRINT_ROUNDING", "COMPAS_DTYPES", "BLOCK_DTYPE", "GRAPH_DTYPE", "INFO_ATTRIBUTE", "load_compas"]

__getattr__ = deprecation.moved(__name__, dict.fromkeys(_NAMES, "interlock.formats.compas"))
