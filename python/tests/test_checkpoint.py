"""A committed checkpoint's table row from Python equals `pamdp eval`'s on the same seed (goal
rate, steps to goal, return, outcomes); the batch call equals the single one; exploration draws
with the checkpoint's ε.

Usage: test_checkpoint.py PAMDP_BINARY SOURCE_DIR"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

import pamdp

PAMDP = SOURCE = None
CASES = [  # (checkpoint, episodes, seed): few episodes, so that the test takes seconds
    # (path, episodes, seed, a goal rate it beats: the policy plays, it is not a random one)
    ("models/hfo-1v0-fast-eps005-seed2.ckpt", 100, 1, 0.5),  # README's bold row: 1.000 / 72.1
    ("models/hfo-1v0-mpdqn-seed1.ckpt", 100, 1, 0.5),  # MP-DQN's parameter and Q-networks
    # Against agent2d's goalie, which it was not trained against; plays its actor average.
    ("models/hfo-1v1-side-seed2.ckpt", 60, 3, 0.01),
]


class CheckpointFromPython(unittest.TestCase):
    def check_against_pamdp_eval(self, path, episodes, seed, floor):
        out = subprocess.run([PAMDP, "eval", "--checkpoint", path, "--episodes", str(episodes), "--seed", str(seed),
                              "--json"], check=True, capture_output=True, text=True)
        cpp = json.loads(out.stdout.strip().splitlines()[-1])
        py = pamdp.evaluate(pamdp.load_policy(path), episodes=episodes, seed=seed)
        self.assertEqual(py["episodes"], cpp["episodes"])
        self.assertEqual(py["goal_rate"], cpp["goal_rate"])
        self.assertEqual(py["avg_steps_to_goal"], cpp["avg_steps_to_goal"])
        self.assertEqual(py["avg_steps"], cpp["avg_steps"])
        self.assertEqual(py["avg_return"], cpp["avg_return"])
        self.assertEqual(py["outcomes"], cpp["outcomes"])
        self.assertGreater(py["goal_rate"], floor)

    def test_eval_row_equals_pamdp_eval(self):
        for path, episodes, seed, floor in CASES:
            with self.subTest(checkpoint=path):
                self.check_against_pamdp_eval(os.path.join(SOURCE, path), episodes, seed, floor)

    def test_toy_task_checkpoint(self):
        # A fresh reach_stop run (under a second) of each learner and its checkpoint, read back
        # from Python.
        for algorithm in ("ddpg", "mpdqn"):
            with self.subTest(algorithm=algorithm), tempfile.TemporaryDirectory() as run:
                subprocess.run([PAMDP, "train", "--config", os.path.join(SOURCE, "deploy/configs/reach_stop.toml"),
                                "--run-dir", run, "--seed", "3", "--set", "train.algorithm=" + algorithm],
                               check=True, capture_output=True)
                path = os.path.join(run, "checkpoint.ckpt")
                self.check_against_pamdp_eval(path, 200, 5, 0.5)
                policy = pamdp.load_policy(path)
                self.assertEqual(policy.env_id, "reach_stop")
                self.assertEqual(policy.algorithm, algorithm)
                ids, params = policy(np.zeros((3, 3), np.float32))
                self.assertEqual([p.shape for p in params], [(3, 1), (3, 0)])

    def test_batch_and_exploration(self):
        full = os.path.join(SOURCE, CASES[0][0])
        policy = pamdp.load_policy(full)
        env = policy.make_env()
        self.assertEqual(env.env_id, "hfo-1v0")
        vec = pamdp.make_vec("hfo-1v0", num_envs=16)
        obs, _ = vec.reset(seed=4)
        ids, params = policy(obs)
        self.assertEqual(ids.shape, (16,))
        self.assertEqual([p.shape for p in params], [(16, 2), (16, 1), (16, 1), (16, 2)])
        self.assertTrue(np.all(ids != 2))  # TACKLE is masked, as in training
        for i in range(16):
            one_id, one_params = policy(obs[i])
            self.assertEqual(one_id, ids[i])
            for a in range(4):
                np.testing.assert_array_equal(one_params[a], params[a][i])
        vec.step((ids, params))
        explorer = pamdp.load_policy(full, exploration=True, epsilon=1.0, seed=7)
        self.assertEqual(explorer.epsilon, 1.0)
        random_ids, _ = explorer(np.repeat(obs[:1], 400, axis=0))
        self.assertEqual(set(random_ids.tolist()), {0, 1, 3})  # uniform over the unmasked actions
        self.assertAlmostEqual(pamdp.load_policy(full, exploration=True).epsilon, 0.05)
        with self.assertRaises(ValueError) as ctx:
            policy(np.zeros(57, np.float32))
        self.assertIn("shape (58,)", str(ctx.exception))
        with self.assertRaises(ValueError):
            pamdp.load_policy(full, actor="average")  # this run kept no average
        with self.assertRaises(ValueError):
            pamdp.load_policy(full, epsilon=2.0, exploration=True)


if __name__ == "__main__":
    PAMDP, SOURCE = sys.argv.pop(1), sys.argv.pop(1)
    unittest.main()
