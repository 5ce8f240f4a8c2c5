"""Gymnasium-style spaces for pamdp's envs, with no dependency on Gymnasium.

They follow gymnasium.spaces (shape, dtype, seed(), sample(), contains()), so code written for
Gymnasium's Discrete, Box, MultiDiscrete and Tuple reads them as it reads those. The Gymnasium
adapter (pamdp.gymnasium_env) converts them with to_gymnasium().
"""

from __future__ import annotations

import numpy as np


class Space:
    """A set of values; sample() draws from it with its own generator (seed() sets it)."""

    def __init__(self, shape=None, dtype=None, seed=None):
        self.shape = shape
        self.dtype = None if dtype is None else np.dtype(dtype)
        self._np_random = None
        if seed is not None:
            self.seed(seed)

    @property
    def np_random(self) -> np.random.Generator:
        if self._np_random is None:
            self.seed()
        return self._np_random

    def seed(self, seed=None):
        """Seeds the sampler (None: from the OS's entropy), as Gymnasium's spaces do."""
        self._np_random = np.random.default_rng(seed)
        return [seed]

    def sample(self):
        raise NotImplementedError

    def contains(self, x) -> bool:
        raise NotImplementedError

    def __contains__(self, x) -> bool:
        return self.contains(x)


class Discrete(Space):
    """The integers 0 .. n-1."""

    def __init__(self, n: int, seed=None):
        super().__init__((), np.int64, seed)
        self.n = int(n)

    def sample(self) -> int:
        return int(self.np_random.integers(self.n))

    def contains(self, x) -> bool:
        try:
            v = int(x)
        except (TypeError, ValueError):
            return False
        return v == x and 0 <= v < self.n

    def __repr__(self):
        return f"Discrete({self.n})"


class MultiDiscrete(Space):
    """An array of integers, entry i in 0 .. nvec[i]-1 (a batch of Discrete ids)."""

    def __init__(self, nvec, seed=None):
        self.nvec = np.asarray(nvec, dtype=np.int64)
        super().__init__(self.nvec.shape, np.int64, seed)

        # One bound for every entry (a batch of one Discrete): a much faster draw.
        self._bound = int(self.nvec.flat[0]) if self.nvec.size and np.all(self.nvec == self.nvec.flat[0]) else None

    def sample(self) -> np.ndarray:
        if self._bound is not None:
            return self.np_random.integers(0, self._bound, self.shape)
        return self.np_random.integers(self.nvec)

    def contains(self, x) -> bool:
        x = np.asarray(x)
        return x.shape == self.shape and x.dtype.kind in "iu" and bool(np.all((x >= 0) & (x < self.nvec)))

    def __repr__(self):
        return f"MultiDiscrete({self.nvec.tolist()})"


def _bound_repr(bound: np.ndarray) -> str:
    if bound.size and np.all(bound == bound.flat[0]):
        return str(bound.flat[0])
    return np.array2string(bound, separator=", ")


class Box(Space):
    """Arrays of `shape` within [low, high] element-wise."""

    def __init__(self, low, high, shape=None, dtype=np.float32, seed=None):
        dtype = np.dtype(dtype)
        if shape is None:
            shape = np.broadcast(np.asarray(low), np.asarray(high)).shape
        shape = tuple(int(s) for s in shape)
        self.low = np.broadcast_to(np.asarray(low, dtype=dtype), shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=dtype), shape).copy()
        if not (np.all(np.isfinite(self.low)) and np.all(np.isfinite(self.high))):
            raise ValueError("Box: bounds must be finite")
        # Drawn in double and rounded once to the dtype, so a sample never leaves [low, high].
        self._low64 = self.low.astype(np.float64)
        self._range64 = self.high.astype(np.float64) - self._low64
        super().__init__(shape, dtype, seed)

    def sample(self) -> np.ndarray:
        u = self.np_random.random(self.shape)
        u *= self._range64
        u += self._low64
        return u.astype(self.dtype)

    def contains(self, x) -> bool:
        x = np.asarray(x)
        return (
            x.shape == self.shape
            and np.can_cast(x.dtype, self.dtype, "same_kind")
            and bool(np.all((x >= self.low) & (x <= self.high)))
        )

    def __repr__(self):
        # As gymnasium.spaces.Box: one number when every entry shares a bound, else every entry's.
        return f"Box({_bound_repr(self.low)}, {_bound_repr(self.high)}, {self.shape}, {self.dtype})"


class Tuple(Space):
    """A tuple of values, one from each of `spaces`."""

    def __init__(self, spaces, seed=None):
        self.spaces = tuple(spaces)
        super().__init__(None, None, None)
        if seed is not None:
            self.seed(seed)

    def seed(self, seed=None):
        """Seeds this space's and every subspace's sampler from one seed."""
        super().seed(seed)
        children = np.random.SeedSequence(seed).spawn(len(self.spaces))
        for space, child in zip(self.spaces, children):
            space.seed(int(child.generate_state(1)[0]))
        return [seed]

    def sample(self) -> tuple:
        if self._np_random is None:
            self.seed()
        return tuple(s.sample() for s in self.spaces)

    def contains(self, x) -> bool:
        if isinstance(x, list):
            x = tuple(x)
        return (
            isinstance(x, tuple)
            and len(x) == len(self.spaces)
            and all(s.contains(v) for s, v in zip(self.spaces, x))
        )

    def __getitem__(self, i):
        return self.spaces[i]

    def __len__(self):
        return len(self.spaces)

    def __repr__(self):
        return "Tuple(" + ", ".join(repr(s) for s in self.spaces) + ")"


class ParameterizedActionSpace(Tuple):
    """Tuple((ids, Tuple(Box per discrete action))): a Tuple whose sample() draws the id(s) and
    every parameter in two calls on its own generator (the per-action arrays are column views of
    one draw), so a batch for a vector env costs a few microseconds, not one draw per subspace."""

    def __init__(self, ids, boxes, seed=None):
        super().__init__((ids, Tuple(boxes)), seed)
        self._batch = () if isinstance(ids, Discrete) else ids.shape
        n = ids.n if isinstance(ids, Discrete) else int(ids.nvec.flat[0])
        self._n = n
        self._low64 = np.concatenate([b._low64.reshape(self._batch + (-1,)) for b in boxes], axis=-1)
        self._range64 = np.concatenate([b._range64.reshape(self._batch + (-1,)) for b in boxes], axis=-1)
        widths = [b.shape[-1] if b.shape else 0 for b in boxes]
        self._slices = [slice(s, s + w) for s, w in zip(np.cumsum([0] + widths[:-1]), widths)]

    def sample(self):
        rng = self.np_random
        ids = rng.integers(0, self._n, self._batch) if self._batch else int(rng.integers(self._n))
        u = rng.random(self._low64.shape)
        u *= self._range64
        u += self._low64
        u = u.astype(np.float32)
        return ids, tuple(u[..., s] for s in self._slices)


def action_space(actions, num_envs=None) -> Tuple:
    """The parameterized action space of an env (`actions`: per discrete action its name and its
    parameters as (name, lo, hi)): Tuple(Discrete(n), Tuple(Box per action)), MP-DQN's
    convention. With num_envs, the batch of num_envs such actions: Tuple(MultiDiscrete,
    Tuple(Box of shape (num_envs, k) per action)); num_envs may be a shape, (num_envs, agents)
    for a team vector env: ids of that shape, each Box (num_envs, agents, k)."""
    batch = None if num_envs is None else tuple(np.atleast_1d(num_envs).astype(int).tolist())
    boxes = []
    for _name, params in actions:
        low = np.array([lo for _p, lo, _hi in params], dtype=np.float32)
        high = np.array([hi for _p, _lo, hi in params], dtype=np.float32)
        if batch is None:
            boxes.append(Box(low, high, (len(params),)))
        else:
            shape = batch + (len(params),)
            boxes.append(Box(np.broadcast_to(low, shape), np.broadcast_to(high, shape), shape))
    ids = Discrete(len(actions)) if batch is None else MultiDiscrete(np.full(batch, len(actions)))
    return ParameterizedActionSpace(ids, boxes)


def to_gymnasium(space):
    """The same space as a gymnasium.spaces object (Gymnasium must be importable)."""
    from gymnasium import spaces as gs

    if isinstance(space, Discrete):
        return gs.Discrete(space.n)
    if isinstance(space, MultiDiscrete):
        return gs.MultiDiscrete(space.nvec)
    if isinstance(space, Box):
        return gs.Box(space.low, space.high, space.shape, space.dtype)
    if isinstance(space, Tuple):
        return gs.Tuple(tuple(to_gymnasium(s) for s in space.spaces))
    raise TypeError(f"to_gymnasium: no Gymnasium space for {space!r}")
