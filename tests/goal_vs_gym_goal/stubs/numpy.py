"""Stand-in for the numpy calls gym-goal makes: small float vectors that broadcast scalars,
clip, concatenate and scalar math. Enough to run its GoalEnv without numpy. In-place operators
rebind rather than mutate, which is the same here: gym-goal shares no vector between bodies."""
import math

pi = math.pi
float64 = float
float32 = float


class ndarray:
    def __init__(self, values):
        self.v = [float(x) for x in values]

    def _other(self, o):
        return o.v if isinstance(o, ndarray) else [o] * len(self.v)

    def __add__(self, o):
        return ndarray([a + b for a, b in zip(self.v, self._other(o))])

    __radd__ = __add__
    __iadd__ = __add__

    def __sub__(self, o):
        return ndarray([a - b for a, b in zip(self.v, self._other(o))])

    def __rsub__(self, o):
        return ndarray([b - a for a, b in zip(self.v, self._other(o))])

    def __mul__(self, o):
        return ndarray([a * b for a, b in zip(self.v, self._other(o))])

    def __rmul__(self, o):
        return ndarray([b * a for a, b in zip(self.v, self._other(o))])

    __imul__ = __mul__

    def __truediv__(self, o):
        return ndarray([a / b for a, b in zip(self.v, self._other(o))])

    def __neg__(self):
        return ndarray([-a for a in self.v])

    def __getitem__(self, i):
        return self.v[i]

    def __setitem__(self, i, x):
        self.v[i] = float(x)

    def __len__(self):
        return len(self.v)

    def __iter__(self):
        return iter(self.v)

    def copy(self):
        return ndarray(self.v)

    @property
    def shape(self):
        return (len(self.v),)


def array(values, dtype=None):
    return ndarray(list(values))


def clip(a, lo, hi):
    return ndarray([min(max(x, low), high) for x, low, high in zip(a, lo, hi)])


def sqrt(x):
    return math.sqrt(x)


def arctan2(y, x):
    return math.atan2(y, x)


def cos(x):
    return math.cos(x)


def sin(x):
    return math.sin(x)


def concatenate(parts):
    out = []
    for part in parts:
        out.extend(list(part))
    return ndarray(out)
