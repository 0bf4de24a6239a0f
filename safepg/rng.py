"""Seeding helpers: every stochastic function accepts a seed or a Generator."""

from __future__ import annotations

import numpy as np

RNGLike = np.random.Generator | int | np.random.SeedSequence | None


def as_generator(rng: RNGLike) -> np.random.Generator:
    """Return a :class:`numpy.random.Generator` for ``rng``.

    An existing Generator is returned unchanged (so a caller can share one stream);
    an int or SeedSequence seeds a fresh PCG64; ``None`` draws fresh OS entropy.
    """
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, (int, np.integer, np.random.SeedSequence)):
        return np.random.default_rng(rng)
    raise TypeError(f"rng must be a numpy Generator, an int seed or None, got {type(rng).__name__}")


__all__ = ["RNGLike", "as_generator"]
