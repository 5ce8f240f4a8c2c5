"""Gymnasium's conventions, checked without Gymnasium (Debian does not package it, so
test_gymnasium.py skips here): what gymnasium.utils.env_checker.check_env checks (spaces and
their bounds, reset's seeding and its (obs, info), step's 5-tuple and its types, determinism
under one seed, np_random, render modes), plus what a new user meets first (issue 81): faithful
space reprs, env ids wherever an env is taken, errors that name the shape they got, one outcome
vocabulary, help(pamdp.make) listing every id, and the rule for out-of-range parameters."""

import io
import pydoc
import unittest
import warnings

import numpy as np

import pamdp
from pamdp import spaces

ENV_IDS = ("hfo-1v0", "hfo-1v1", "reach_stop", "platform", "goal")
CHECKPOINT = "../../models/hfo-1v0-fast-seed1.ckpt"


def random_steps(env, seed, steps):
    """(obs, reward, terminated, truncated, info) of `steps` seeded random actions from reset(seed)."""
    env.action_space.seed(seed)
    out = [env.reset(seed=seed)]
    for _ in range(steps):
        result = env.step(env.action_space.sample())
        out.append(result)
        if result[2] or result[3]:
            out.append(env.reset())
    return out


class CheckEnvProperties(unittest.TestCase):
    """gymnasium.utils.env_checker.check_env's checks, one env id at a time."""

    def test_spaces(self):
        for env_id in ENV_IDS:
            with self.subTest(env=env_id):
                env = pamdp.make(env_id)
                self.assertIsInstance(env.observation_space, spaces.Box)
                self.assertIsInstance(env.action_space, spaces.Tuple)
                box = env.observation_space
                self.assertEqual(box.dtype, np.float32)
                self.assertTrue(np.all(np.isfinite(box.low)) and np.all(np.isfinite(box.high)))
                self.assertTrue(np.all(box.low < box.high))
                ids, params = env.action_space
                self.assertIsInstance(ids, spaces.Discrete)
                self.assertEqual(len(params), ids.n)
                for p in params:
                    self.assertTrue(np.all(p.low <= p.high))
                env.action_space.seed(5)
                a = env.action_space.sample()
                self.assertIn(a, env.action_space)
                env.action_space.seed(5)
                b = env.action_space.sample()
                self.assertEqual(a[0], b[0])
                for x, y in zip(a[1], b[1]):
                    np.testing.assert_array_equal(x, y)

    def test_reset_seeding_and_return_types(self):
        for env_id in ENV_IDS:
            with self.subTest(env=env_id):
                env = pamdp.make(env_id)
                obs, info = env.reset(seed=123)
                self.assertIsInstance(info, dict)
                self.assertIn(obs, env.observation_space)
                self.assertEqual(obs.dtype, env.observation_space.dtype)
                self.assertIsInstance(env.np_random, np.random.Generator)
                self.assertEqual(env.np_random_seed, 123)
                state = env.np_random.bit_generator.state
                again, _ = env.reset(seed=123)
                np.testing.assert_array_equal(obs, again)
                self.assertEqual(env.np_random.bit_generator.state, state, "reset(seed) reseeds np_random")
                env.np_random.random()
                generator = env.np_random
                env.reset()
                self.assertIs(env.np_random, generator, "reset() without a seed keeps the generator")
                env.reset(seed=456)
                self.assertNotEqual(env.np_random.bit_generator.state, state)
                obs, info = env.reset(seed=1, options={})
                self.assertIn(obs, env.observation_space)

    def test_step_return_types(self):
        for env_id in ENV_IDS:
            with self.subTest(env=env_id):
                env = pamdp.make(env_id)
                env.reset(seed=2)
                env.action_space.seed(2)
                for _ in range(200):
                    result = env.step(env.action_space.sample())
                    self.assertEqual(len(result), 5)
                    obs, reward, terminated, truncated, info = result
                    self.assertIn(obs, env.observation_space)
                    self.assertIsInstance(reward, float)
                    self.assertTrue(np.isfinite(reward))
                    self.assertIsInstance(terminated, bool)
                    self.assertIsInstance(truncated, bool)
                    self.assertIsInstance(info, dict)
                    if terminated or truncated:
                        env.reset()

    def test_step_determinism(self):
        for env_id in ENV_IDS:
            with self.subTest(env=env_id):
                a = random_steps(pamdp.make(env_id), 9, 150)
                b = random_steps(pamdp.make(env_id), 9, 150)
                self.assertEqual(len(a), len(b))
                for x, y in zip(a, b):
                    np.testing.assert_array_equal(x[0], y[0])
                    self.assertEqual(x[1:], y[1:])

    def test_spec_metadata_and_render(self):
        for env_id in ENV_IDS:
            with self.subTest(env=env_id):
                env = pamdp.make(env_id, render_mode="ansi")
                self.assertEqual(env.spec.id, env_id)
                self.assertEqual(env.spec.max_episode_steps, env.max_episode_steps)
                self.assertEqual(env.spec.make().env_id, env_id)
                self.assertIsInstance(env.metadata["render_modes"], list)
                self.assertIn("ansi", env.metadata["render_modes"])
                self.assertEqual(env.render_mode, "ansi")
                self.assertIs(env.unwrapped, env)
                env.reset(seed=1)
                text = env.render()
                self.assertIsInstance(text, str)
                self.assertIn(env_id.split("-")[0], text)
                self.assertIn("IN_GAME", text)
                plain = pamdp.make(env_id)
                self.assertIsNone(plain.render_mode)
                self.assertIsNone(plain.render())
                plain.reset(seed=1)
                self.assertEqual(plain.render("ansi"), text, "render('ansi') and render_mode='ansi' agree")
                with self.assertRaises(ValueError):
                    plain.render("human")
                with self.assertRaises(ValueError):
                    pamdp.make(env_id, render_mode="rgb_array")
                env.close()
        spec = pamdp.make("hfo-1v0", noise=False).spec
        self.assertEqual(spec.kwargs, {"noise": False})
        self.assertEqual(spec.make().options["noise"], False)

    def test_render_shows_the_field(self):
        env = pamdp.make("hfo-1v1", render_mode="ansi")
        env.reset(seed=3)
        text = env.render()
        self.assertIn("A agent, G goalie, o ball", text)
        self.assertIn("agent  x", text)
        self.assertIn("goalie x", text)
        self.assertIn("ball   x", text)
        # The field moves with the state: a few dashes change the picture.
        for _ in range(5):
            env.step((0, (np.array([100, 0], np.float32), np.zeros(1, np.float32), np.zeros(1, np.float32),
                          np.zeros(2, np.float32))))
        self.assertNotEqual(env.render(), text)
        self.assertIn("step 5", env.render())
        reach = pamdp.make("reach_stop")
        reach.reset(seed=1)
        self.assertIn("position", reach.render("ansi"))


class FirstContact(unittest.TestCase):
    """What a new user meets in the first hour (issue 81)."""

    def test_space_reprs(self):
        # reach_stop's STOP has no parameters: an empty Box, whose repr once raised.
        self.assertEqual(repr(pamdp.make("reach_stop").action_space),
                         "Tuple(Discrete(2), Tuple(Box(-1.0, 1.0, (1,), float32), Box([], [], (0,), float32)))")
        # Per-dimension bounds: DASH's power [0, 100] and direction [-180, 180] both show.
        dash = repr(pamdp.make("hfo-1v0").action_space[1][0])
        self.assertIn("100.", dash)
        self.assertIn("-180.", dash)
        self.assertIn("0.", dash)
        self.assertEqual(repr(spaces.Box(-1.0, 1.0, (3,))), "Box(-1.0, 1.0, (3,), float32)")
        for env_id in ENV_IDS:
            repr(pamdp.make(env_id).action_space)
            repr(pamdp.make(env_id).observation_space)
            repr(pamdp.make_vec(env_id, num_envs=2).action_space)

    def test_one_outcome_vocabulary(self):
        for env_id in ENV_IDS:
            with self.subTest(env=env_id):
                env = pamdp.make(env_id)
                _, info = env.reset(seed=1)
                self.assertEqual(info["outcome"], "IN_GAME")
                self.assertEqual(dict(env.outcomes)[0], "IN_GAME")
                self.assertNotIn("IN_PROGRESS", dict(env.outcomes).values())

    def test_help_of_make_lists_every_id(self):
        text = pydoc.render_doc(pamdp.make, renderer=pydoc.plaintext)
        for env_id in pamdp.env_ids():
            self.assertIn(env_id, text)
        for env_id in ("platform", "goal", "hfo-1v1"):
            self.assertIn(env_id, text)

    def test_out_of_range_parameters_are_clamped_by_the_env_and_said_once(self):
        env = pamdp.make("hfo-1v0", noise=False)
        same = pamdp.make("hfo-1v0", noise=False)
        env.reset(seed=4)
        same.reset(seed=4)
        rest = (np.zeros(1, np.float32), np.zeros(1, np.float32), np.zeros(2, np.float32))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            a = env.step((0, (np.array([500, 0], np.float32),) + rest))
            env.step((0, (np.array([500, 0], np.float32),) + rest))
        messages = [str(w.message) for w in caught]
        self.assertEqual(len(messages), 1, messages)
        self.assertIn("dash_power = 500", messages[0])
        self.assertIn("[0, 100]", messages[0])
        self.assertIn("clamps", messages[0])
        # The rule: a power of 500 is the server's 100, as the real HFO does.
        b = same.step((0, (np.array([100, 0], np.float32),) + rest))
        np.testing.assert_array_equal(a[0], b[0])
        self.assertEqual(a[1:], b[1:])
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            quiet = pamdp.make("hfo-1v0")
            quiet.reset(seed=1)
            quiet.step((0, (np.array([100, 0], np.float32),) + rest))  # in range: no warning


class Evaluate(unittest.TestCase):
    def test_env_ids_are_taken_wherever_an_env_is(self):
        policy = pamdp.load_policy(CHECKPOINT)
        by_id = pamdp.evaluate(policy, env="hfo-1v0", episodes=3)
        by_env = pamdp.evaluate(policy, env=pamdp.make("hfo-1v0"), episodes=3)
        self.assertEqual(by_id, by_env)
        with self.assertRaisesRegex(ValueError, "58 floats.*'platform' gives 9"):
            pamdp.evaluate(policy, env="platform", episodes=1)
        with self.assertRaisesRegex(ValueError, "unknown env .no-such-env. \\(valid: hfo-1v0"):
            pamdp.evaluate(policy, env="no-such-env", episodes=1)
        with self.assertRaises(TypeError):
            pamdp.evaluate(policy, env=3, episodes=1)

    def test_a_wrong_observation_names_its_shape(self):
        policy = pamdp.load_policy(CHECKPOINT)
        obs, _ = pamdp.make("platform").reset(seed=1)
        with self.assertRaisesRegex(ValueError, r"shape \(58,\).*got shape \(9,\)"):
            policy(obs)
        with self.assertRaisesRegex(ValueError, r"got shape \(2, 3, 58\)"):
            policy(np.zeros((2, 3, 58), np.float32))


if __name__ == "__main__":
    unittest.main()
