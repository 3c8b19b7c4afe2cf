"""Uniform random plane partitions in a box by coupling from the past (Propp-Wilson).

The sampler behind :func:`interlock.blocks.lozenge.random_hexagon`: plane
partitions in an ``a x b x c`` box are the lozenge tilings of the ``a x b x c``
hexagon.
"""

from __future__ import annotations

import numpy as np

__all__ = ["uniform_plane_partition", "CFTP_FIRST_EPOCH"]

#: Sweeps of the last epoch of coupling from the past; each earlier epoch doubles the total.
CFTP_FIRST_EPOCH = 8
# Sweeps whose uniforms are drawn at once (fixed, so that a seed gives the same sample on every machine).
_CHUNK = 64


def uniform_plane_partition(a: int, b: int, c: int, rng: np.random.Generator, progress=None) -> np.ndarray:
    """A uniform plane partition in the ``a x b x c`` box (Propp-Wilson).

    See :func:`~interlock.blocks.lozenge.random_hexagon`.

    ``progress``, if given, is called as ``progress(sweeps)`` after every chunk of sweeps.

    >>> uniform_plane_partition(2, 2, 2, np.random.default_rng(0)).shape
    (2, 2)
    """
    if a * b * c == 0:
        return np.zeros((a, b), dtype=np.int64)
    parity = np.add.outer(np.arange(a), np.arange(b)) % 2
    masks = (parity == 0, parity == 1)
    seeds: list[int] = []  # seeds[k] drives epoch k; epoch 0 ends at time 0
    while True:
        seeds.append(int(rng.integers(2**63)))
        chains = np.zeros((2, a + 2, b + 2), dtype=np.int64)  # padded: c above and left, 0 below and right
        chains[:, 0, :] = chains[:, :, 0] = c
        chains[0, 1:-1, 1:-1] = c
        for epoch in reversed(range(len(seeds))):
            epoch_rng = np.random.default_rng(seeds[epoch])
            left = CFTP_FIRST_EPOCH * 2 ** max(epoch - 1, 0)
            while left:
                _sweeps(chains, epoch_rng.random((min(_CHUNK, left), a, b)), masks)
                if progress is not None:
                    progress(min(_CHUNK, left))
                left -= min(_CHUNK, left)
        if np.array_equal(chains[0], chains[1]):
            return chains[0, 1:-1, 1:-1].copy()


def _sweeps(chains: np.ndarray, uniforms: np.ndarray, masks) -> None:
    """Heat-bath sweeps (two checkerboard half-sweeps each) on the padded chains, in place."""
    inner = chains[:, 1:-1, 1:-1]
    below, right = chains[:, 2:, 1:-1], chains[:, 1:-1, 2:]
    above, left = chains[:, :-2, 1:-1], chains[:, 1:-1, :-2]
    low, span, value = np.empty_like(inner), np.empty_like(inner), np.empty(inner.shape)
    for u in uniforms:
        for mask in masks:
            np.maximum(below, right, out=low)
            np.minimum(above, left, out=span)
            span -= low
            span += 1  # the entry may take span values from low on
            np.multiply(u, span, out=value)
            value += low
            np.copyto(inner, value, where=mask, casting="unsafe")  # truncation is the floor: values are positive
