"""Python against C++ on the same seed, step for step: the module's envs give the observations,
rewards and statuses, bit for bit, that the env `pamdp` builds from the same settings gives.

Usage: test_reference.py REFERENCE_TRACE_BINARY"""

import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

import pamdp

REFERENCE = None
CASES = [  # (env id, options, the same env as config settings)
    ("hfo-1v0", {}, ['env.name="hfo"']),
    ("hfo-1v1", {}, ['env.name="hfo"', "env.goalie=true"]),
    ("hfo-1v0", {"noise": False, "start": "hfo", "max_steps": 60}, ['env.name="hfo"', "env.noise=false",
                                                                    'env.start="hfo"', "env.max_steps=60"]),
    ("reach_stop", {}, ['env.name="reach_stop"']),
]


class PythonAgainstCpp(unittest.TestCase):
    def test_step_for_step(self):
        for env_id, options, sets in CASES:
            with self.subTest(env=env_id, options=options):
                env = pamdp.make(env_id, **options)
                num_params = sum(b.shape[0] for b in env.action_space[1])
                rng = np.random.default_rng(42)
                steps = 3000
                ids = rng.integers(env.action_space[0].n, size=steps)
                lows = np.concatenate([b.low for b in env.action_space[1]])
                highs = np.concatenate([b.high for b in env.action_space[1]])
                params = rng.uniform(lows - 10, highs + 10, (steps, num_params)).astype(np.float32)
                with tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False) as f:
                    for i in range(steps):
                        f.write(",".join([str(ids[i])] + ["%.9g" % p for p in params[i]]) + "\n")
                    path = f.name
                try:
                    out = subprocess.run([REFERENCE, "5", path] + sets, check=True, capture_output=True, text=True)
                finally:
                    os.unlink(path)
                lines = out.stdout.splitlines()
                obs, _ = env.reset(seed=5)
                k, episodes = 0, 0
                self.assertEqual(lines[k].split(",")[0], "R")
                np.testing.assert_array_equal(obs, np.array(lines[k].split(",")[1:], np.float32))
                for i in range(steps):
                    obs, reward, terminated, truncated, info = env.step((int(ids[i]), params[i]))
                    k += 1
                    row = lines[k].split(",")
                    self.assertEqual(row[0], "S")
                    self.assertEqual(np.float32(reward), np.float32(row[1]), f"step {i}")
                    self.assertEqual(info["status"], int(row[2]), f"step {i}")
                    np.testing.assert_array_equal(obs, np.array(row[3:], np.float32), f"step {i}")
                    if terminated or truncated:
                        episodes += 1
                        obs, _ = env.reset()
                        k += 1
                        np.testing.assert_array_equal(obs, np.array(lines[k].split(",")[1:], np.float32))
                self.assertEqual(k + 1, len(lines))
                self.assertGreater(episodes, 2)


if __name__ == "__main__":
    REFERENCE = sys.argv.pop(1)
    unittest.main()
