"""Stand-in for gym.utils.seeding: core/rng.hpp's generator (xoshiro256++ seeded through
splitmix64), so that gym-goal draws the same uniforms as our env, in its own order."""
import numpy

MASK = (1 << 64) - 1
# Set by run_gym_goal.py with the noise off: a zero-width range takes no draw, as in our env.
NO_DRAW_WHEN_EMPTY = False


def _rotl(x, k):
    return ((x << k) | (x >> (64 - k))) & MASK


class Xoshiro:
    def __init__(self, seed):
        self.s = []
        for _ in range(4):
            seed = (seed + 0x9E3779B97F4A7C15) & MASK
            z = seed
            z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
            z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
            self.s.append(z ^ (z >> 31))

    def next_u64(self):
        s = self.s
        result = (_rotl((s[0] + s[3]) & MASK, 23) + s[0]) & MASK
        t = (s[1] << 17) & MASK
        s[2] ^= s[0]
        s[3] ^= s[1]
        s[1] ^= s[2]
        s[0] ^= s[3]
        s[2] ^= t
        s[3] = _rotl(s[3], 45)
        return result

    def u(self):
        return (self.next_u64() >> 11) * 2.0 ** -53

    def uniform(self, lo, hi, size=None):
        if size is not None:
            return numpy.ndarray([self.uniform(lo, hi) for _ in range(size)])
        if lo == hi and NO_DRAW_WHEN_EMPTY:
            return lo
        return lo + (hi - lo) * self.u()

    def random_sample(self):
        # Only Goalie.can_catch draws this, against CATCH_PROBABILITY = 1: our env takes no draw.
        return 0.5


def np_random(seed=None):
    return Xoshiro(0 if seed is None else seed), seed
