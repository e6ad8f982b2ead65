"""Batched inputs for the C core's property tests (tests/python/core_settings.py has the counts).

One hypothesis example checks a batch of input vectors: the first drawn by the property's own
hypothesis strategy (as before batching), the rest by numpy's Generator from a seed the example
draws, over the same ranges with the strategy's edge values mixed in at the rate the strategy
draws them:

- an ``I16`` element (``one_of(integers(-32768, 32767), sampled_from(I16_EDGES))``): one of
  :data:`I16_EDGES` with probability :data:`EDGE_SHARE` (hypothesis's ``one_of`` picks either
  branch alike), else uniform over the whole range;
- a plain ``integers(lo, hi)`` or ``floats(lo, hi)``: its bounds (and 0 where inside) with
  probability :data:`BOUND_SHARE`, else uniform over the range.

A failing batch is reproduced by its seed (hypothesis prints it); hypothesis shrinks the seed and
the first vector, not the numpy-drawn vectors.
"""
import numpy as np
from hypothesis import strategies as st

I16_EDGES = (-32768, -32767, -1, 0, 1, 32766, 32767)
#: the share of an I16 element drawn from I16_EDGES
EDGE_SHARE = 0.5
#: the share of a plain integers()/floats() element drawn at a bound of its range (or 0)
BOUND_SHARE = 0.125

seeds = st.integers(0, 2 ** 64 - 1)


def generator(seed: int) -> np.random.Generator:
    """numpy's Generator for a drawn seed."""
    return np.random.default_rng(seed)


def mix(rng, v, edges, share):
    """v with each element replaced, with probability ``share``, by one of ``edges``."""
    v = np.asarray(v)
    pick = rng.random(v.shape) < share
    e = np.asarray(edges, v.dtype)
    return np.where(pick, e[rng.integers(0, len(e), v.shape)], v)


def ints(rng, lo, hi, size=None, edges=None, share: float | None = None) -> np.ndarray:
    """int64 uniform on [lo, hi] (lo, hi scalars or arrays); ``edges`` mixed in at ``share``
    (default EDGE_SHARE), or without edges the bounds lo, hi and 0 (where inside) at BOUND_SHARE."""
    v = rng.integers(lo, hi, size=size, endpoint=True, dtype=np.int64)
    if edges is not None:
        return mix(rng, v, [e for e in edges if lo <= e <= hi], EDGE_SHARE if share is None else share)
    lo, hi = np.broadcast_to(lo, v.shape), np.broadcast_to(hi, v.shape)
    bounds = np.choose(rng.integers(0, 3, v.shape), [lo, hi, np.where((lo <= 0) & (hi >= 0), 0, lo)])
    return np.where(rng.random(v.shape) < (BOUND_SHARE if share is None else share), bounds, v)


def i16(rng, size=None, lo: int = -32768) -> np.ndarray:
    """int64 values as the I16 strategy draws them (``lo`` > -32768: I16 filtered to >= lo, the
    edges below lo left out)."""
    return ints(rng, lo, 32767, size, I16_EDGES)


def floats(rng, lo: float, hi: float, size=None) -> np.ndarray:
    """float64 uniform on [lo, hi] with lo, hi (and 0 where inside) at BOUND_SHARE."""
    v = rng.uniform(lo, hi, size)
    edges = [lo, hi] + ([0.0] if lo <= 0.0 <= hi else [])
    return mix(rng, v, edges, BOUND_SHARE)


def rows_hold(holds, **columns):
    """Assert every row of a batch holds; else name the first failing row's inputs."""
    bad = np.flatnonzero(~np.asarray(holds, bool))
    if bad.size:
        first = ", ".join(f"{k}={np.asarray(v)[bad[0]].tolist()!r}" for k, v in columns.items())
        raise AssertionError(f"{bad.size} of {np.size(holds)} vectors fail; the first (row {bad[0]}): {first}")


def stack(first, rest):
    """Row 0 the hypothesis-drawn value ``first``, then the numpy-drawn rows ``rest`` (k, ...)."""
    first = np.asarray(first, rest.dtype)
    return np.concatenate([first.reshape((1,) + rest.shape[1:]), rest], axis=0)
