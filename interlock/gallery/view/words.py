"""Verdicts in plain words: one sentence a designer reads first, then the precise statement and its tolerances."""

from __future__ import annotations

import numpy as np

__all__ = ["plain_sentence", "details", "block_ranges", "blocks_words", "direction_words", "VERTICAL_COS",
           "LEVEL_COS", "TURN_SHARE"]

#: A translation within about 14 degrees of the vertical is "straight up" (or down).
VERTICAL_COS = 0.97
#: ... and within about 15 degrees of the horizontal, "sideways".
LEVEL_COS = 0.26
#: A motion whose rotation moves the block's box by less than this share of its translation is "a slide".
TURN_SHARE = 0.05
#: Blocks named one by one in a sentence; more are counted.
NAMED = 6


def block_ranges(indices) -> str:
    """Block indices as ranges, the form ``--fixed`` reads.

    >>> block_ranges([0, 1, 2, 3, 5, 6, 7, 8, 11])
    '0-3,5-8,11'
    """
    values = sorted({int(v) for v in indices})
    parts, k = [], 0
    while k < len(values):
        end = k
        while end + 1 < len(values) and values[end + 1] == values[end] + 1:
            end += 1
        parts.append(str(values[k]) if end == k else f"{values[k]}-{values[end]}")
        k = end + 1
    return ",".join(parts)


def blocks_words(indices) -> str:
    """'block 4', 'blocks 3 and 5', 'blocks 0-3 and 5-8' or '12 blocks'.

    >>> blocks_words([4]), blocks_words([3, 5]), blocks_words(range(40))
    ('block 4', 'blocks 3 and 5', 'blocks 0-39')
    """
    values = sorted({int(v) for v in indices})
    if len(values) == 1:
        return f"block {values[0]}"
    parts = block_ranges(values).split(",")
    if len(parts) > NAMED:
        return f"{len(values)} blocks"
    return "blocks " + (parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1])


def direction_words(twists, centres, size: float) -> str:
    """How blocks move along twists ``(omega, t)`` about ``centres``: 'straight up', 'sideways', 'by turning', ...

    >>> direction_words([[0, 0, 0, 0, 0, 2.0]], [[0, 0, 0]], 1.0)
    'straight up'
    >>> direction_words([[0, 0, 1.0, 0, 0, 0]], [[0, 0, 0]], 1.0)
    'by turning about a vertical axis'
    """
    twists = np.asarray(twists, dtype=float).reshape(-1, 6)
    omega, t = twists[:, :3], twists[:, 3:]
    turn = float(np.linalg.norm(omega, axis=1).max()) * size
    slide = float(np.linalg.norm(t, axis=1).max())
    if turn > slide / TURN_SHARE or slide == 0:
        axis = omega[np.argmax(np.linalg.norm(omega, axis=1))]
        upright = abs(axis[2]) / max(np.linalg.norm(axis), 1e-300) > VERTICAL_COS
        return "by turning about a vertical axis" if upright else "by turning"
    if turn > TURN_SHARE * slide:
        return "by turning and sliding"
    mean = t.mean(axis=0)
    together = np.linalg.norm(mean) > 0.9 * slide
    direction = mean if together else t[np.argmax(np.linalg.norm(t, axis=1))]
    cosine = direction[2] / max(np.linalg.norm(direction), 1e-300)
    if cosine > VERTICAL_COS:
        words = "straight up"
    elif cosine < -VERTICAL_COS:
        words = "straight down"
    elif abs(cosine) < LEVEL_COS:
        words = "sideways"
    else:
        words = "upwards at an angle" if cosine > 0 else "downwards at an angle"
    return words if together else f"in different directions ({words} the most)"


def plain_sentence(assembly, verdict=None, stability=None, frame_words: str | None = None) -> str:
    """One plain sentence (two with a stability result) saying what the verdicts mean for the blocks.

    "Not interlocked" is said as the verifier proved it: a first-order motion
    "can start to move" (no contact stops it at first order); only a finite
    motion shown (``order=2``) "can be taken out".

    >>> from interlock.blocks import presets
    >>> from interlock.verify import check
    >>> plain_sentence(presets.interlocking_cubes(), check(presets.interlocking_cubes()))
    'With the outer ring (8 blocks) fixed, the other block cannot move.'
    """
    parts = []
    if verdict is not None:
        parts.append(_kinematic(assembly, verdict, frame_words))
    if stability is not None:
        parts.append(_statics(stability))
    if not parts:
        return f"{len(assembly)} blocks, {len(assembly.frame)} of them fixed; no verdict was computed for this view."
    return " ".join(parts)


def _frame_words(assembly, frame, frame_words) -> str:
    if not frame_words and len(frame) > 2 and set(frame) == set(assembly.boundary()):
        frame_words = "the outer ring"
    if frame_words:
        return f"{frame_words} ({len(frame)} blocks)" if len(frame) > 1 else frame_words
    if len(frame) <= 8:
        return blocks_words(frame)
    return f"the {len(frame)} frame blocks"


def _kinematic(assembly, verdict, frame_words) -> str:
    frame = tuple(verdict.frame)
    if not frame:
        return ("With no block fixed, the whole assembly can move as one: give a frame (the blocks held fixed) "
                "to ask whether the others interlock.")
    held = f"With {_frame_words(assembly, frame, frame_words)} fixed"
    others = len(assembly) - len(frame)
    second = verdict.second_order is not None and getattr(verdict.second_order, "blocked", False)
    if verdict.interlocked is True:
        if second:
            return f"{held}, no block can move: the one first-order motion is blocked at second order."
        return f"{held}, no block can move." if others != 1 else f"{held}, the other block cannot move."
    moving = tuple(verdict.moving)
    finite = verdict.finite_motion
    shown = finite is not None and getattr(finite, "shown", False)
    twists = getattr(finite, "twists", None) if shown else None
    twists = verdict.motion if twists is None else twists
    how = ""
    if twists is not None and moving:
        chosen = np.asarray(twists, dtype=float)[list(moving)]
        how = " " + direction_words(chosen, assembly.centroids[list(moving)], assembly.block_size)
    who = blocks_words(moving) if moving else "some blocks"
    if verdict.interlocked is False and shown:
        out = " and out" if getattr(finite, "separated", False) or finite.ending == "separated" else ""
        verb = "be lifted" if how.strip() == "straight up" else "be moved"
        together = " together" if len(moving) > 1 and "different directions" not in how else ""
        return f"{held}, {who} can {verb}{how}{together}{out}: a finite motion was shown without collision."
    if verdict.interlocked is False and verdict.motion_kind == "within tolerance":
        return (f"{held}, {who} can move{how} within the contacts' tolerance: as built to that tolerance, "
                "the assembly is not interlocked.")
    if verdict.interlocked is False:
        them = "them" if len(moving) > 1 else "it"
        return f"{held}, {who} can start to move{how}: no contact stops {them} at first order."
    if verdict.order == 2 and moving:
        return (f"{held}, it is undecided whether {who} can move: a first-order motion{how} exists, but it was "
                "neither blocked at second order nor shown to be a finite motion.")
    return (f"{held}, the verifier could not decide whether any block can move "
            "(see the precise statement below).")


def _statics(stability) -> str:
    p = stability.parameters
    mu = p.get("mu")
    if stability.stable is True:
        return (f"It stands under its own weight with friction coefficient {mu:g}: the arrows show contact forces "
                "that carry every block.")
    if stability.stable is False:
        return (f"It does not stand under its own weight with friction coefficient {mu:g}: no contact forces can "
                "carry it, and the animation shows how it starts to come down.")
    return f"Whether it stands under its own weight with friction coefficient {mu:g} is undecided."


def details(verdict=None, stability=None) -> list[str]:
    """The precise statements (``str`` of each result) and their tolerances, one line each."""
    lines = []
    if verdict is not None:
        lines.append(str(verdict))
        if verdict.second_order is not None:
            lines.append(f"second order: {verdict.second_order}")
        if verdict.finite_motion is not None:
            lines.append(f"finite motion: {verdict.finite_motion.message}")
        if verdict.tolerances:
            lines.append("tolerances: " + ", ".join(f"{k} {_number(v)}" for k, v in verdict.tolerances.items()))
    if stability is not None:
        lines.append(str(stability))
        shown = {k: v for k, v in stability.parameters.items() if k in ("mu", "cone", "sides", "density", "eps",
                                                                        "eta", "gravity")}
        if shown:
            lines.append("parameters: " + ", ".join(f"{k} {_number(v)}" for k, v in shown.items()))
    return lines


def _number(value) -> str:
    if isinstance(value, float):
        return f"{value:.3g}"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} {_number(v)}" for k, v in value.items()) + "}"
    return str(value)
