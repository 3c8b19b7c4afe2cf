"""Random valid deformations for tests: points near the edges of F, one edge per pair."""

import numpy as np

from interlock.blocks import DeformationError, escher_block


def random_deformation(group, rng, max_points=2, offset=0.2, skip=0.0):
    """Points at sorted positions along each deformable edge, pushed off it by up to ``offset`` x its length."""
    corners = np.asarray(group.fundamental_domain().exterior.coords)
    deformation = {}
    for s in group.side_pairings():
        if s.partner < s.edge or s.self_paired or rng.random() < skip:
            continue
        p, q = corners[s.edge], corners[s.edge + 1]
        normal = np.array([q[1] - p[1], p[0] - q[0]])
        m = int(rng.integers(1, max_points + 1))
        along = (np.arange(1, m + 1) + rng.uniform(-0.3, 0.3, m)) / (m + 1)  # increasing, inside (0, 1)
        deformation[s.edge] = p + along[:, None] * (q - p) + rng.uniform(-offset, offset, (m, 1)) * normal
    return deformation


def random_block(group, rng, tries=100, **kwargs):
    """A block from the first random deformation that is valid (invalid ones are rejected by escher_block)."""
    for _ in range(tries):
        try:
            return escher_block(group, random_deformation(group, rng, **kwargs), height=float(rng.uniform(0.5, 2)))
        except DeformationError:
            continue
    raise AssertionError(f"no valid random deformation of {group.name} in {tries} tries")
