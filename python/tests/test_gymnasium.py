"""With Gymnasium importable, pamdp's envs are registered: gymnasium.make("pamdp/hfo-1v0") gives a
gymnasium.Env that passes Gymnasium's own env checker. Gymnasium is not a Debian package, so
without it this test is skipped (exit 77); test_conventions.py checks the same properties there."""

import sys
import unittest

try:
    import gymnasium
    from gymnasium.utils.env_checker import check_env
except ImportError:
    print("python_gymnasium_test: skipped, gymnasium is not importable")
    sys.exit(77)

import numpy as np

import pamdp  # registers pamdp/<id>


class GymnasiumRegistration(unittest.TestCase):
    def test_make_and_check(self):
        for env_id in ("pamdp/hfo-1v0", "pamdp/hfo-1v1", "pamdp/reach_stop"):
            with self.subTest(env=env_id):
                env = gymnasium.make(env_id)
                check_env(env.unwrapped, skip_render_check=True)
                obs, info = env.reset(seed=3)
                self.assertIn(obs, env.observation_space)
                env.action_space.seed(1)
                for _ in range(50):
                    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
                    self.assertIn(obs, env.observation_space)
                    if terminated or truncated:
                        self.assertIn(info["outcome"], ("GOAL", "OUT_OF_BOUNDS", "CAPTURED_BY_DEFENSE", "OUT_OF_TIME",
                                                        "SUCCESS", "WRONG_STOP"))
                        env.reset()
        # Its render mode: the field as text.
        env = gymnasium.make("pamdp/hfo-1v1", render_mode="ansi")
        check_env(env.unwrapped)
        env.reset(seed=1)
        self.assertIn("A agent, G goalie", env.render())
        env = gymnasium.make("pamdp/hfo-1v0", noise=False)
        a, _ = env.reset(seed=1)
        b, _ = pamdp.make("hfo-1v0", noise=False).reset(seed=1)
        np.testing.assert_array_equal(a, b)
        with self.assertRaises(ValueError):
            gymnasium.make("pamdp/hfo-1v0", nosie=False)


if __name__ == "__main__":
    unittest.main()
