"""The Python envs: Gymnasium conformance (spaces, bounds, determinism per seed, outcomes), the
vector env against single envs, and caller errors raising TypeError / ValueError."""

import unittest

import numpy as np

import pamdp

ENV_IDS = ["hfo-1v0", "hfo-1v1", "hfo", "reach_stop"]
OUTCOMES_HFO = {"IN_GAME", "GOAL", "CAPTURED_BY_DEFENSE", "OUT_OF_BOUNDS", "OUT_OF_TIME"}


def rollout(env, seed, action_seed, episodes):
    """Every observation, reward and outcome of `episodes` random episodes."""
    env.action_space.seed(action_seed)
    out = []
    for ep in range(episodes):
        obs, info = env.reset(seed=seed) if ep == 0 else env.reset()
        out.append(obs)
        done = False
        while not done:
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            out.extend([obs, np.float32(reward), info["status"]])
            done = terminated or truncated
    return out


class EnvConformance(unittest.TestCase):
    def test_ids_and_spaces(self):
        self.assertTrue({"hfo-1v0", "hfo-1v1", "reach_stop", "hfo"} <= set(pamdp.env_ids()))
        cases = {"hfo-1v0": (58, 4, [2, 1, 1, 2]), "hfo-1v1": (66, 4, [2, 1, 1, 2]), "reach_stop": (3, 2, [1, 0])}
        for env_id, (obs_size, n, widths) in cases.items():
            env = pamdp.make(env_id)
            self.assertEqual(env.observation_space.shape, (obs_size,))
            self.assertEqual(env.observation_space.dtype, np.float32)
            self.assertEqual(env.action_space[0].n, n)
            self.assertEqual([b.shape[0] for b in env.action_space[1]], widths)
            for _ in range(50):
                self.assertIn(env.action_space.sample(), env.action_space)
        hfo = pamdp.make("hfo-1v0").action_space[1]
        np.testing.assert_array_equal(hfo[0].low, [0, -180])
        np.testing.assert_array_equal(hfo[0].high, [100, 180])
        np.testing.assert_array_equal(hfo[3].high, [100, 180])
        self.assertTrue(pamdp.make("hfo", goalie=True).observation_space.shape == (66,))

    def test_api_and_bounds(self):
        for env_id in ENV_IDS:
            env = pamdp.make(env_id)
            obs, info = env.reset(seed=3)
            self.assertIsInstance(info, dict)
            self.assertEqual(obs.dtype, np.float32)
            env.action_space.seed(5)
            steps, episodes = 0, 0
            while episodes < 20:
                result = env.step(env.action_space.sample())
                self.assertEqual(len(result), 5)
                obs, reward, terminated, truncated, info = result
                self.assertIn(obs, env.observation_space)
                self.assertIsInstance(reward, float)
                self.assertIsInstance(terminated, bool)
                self.assertIsInstance(truncated, bool)
                self.assertFalse(terminated and truncated)
                self.assertIn(info["outcome"], dict(env.outcomes).values())
                self.assertEqual(truncated, info["outcome"] == "OUT_OF_TIME")
                self.assertEqual(terminated or truncated, info["status"] != 0)
                steps += 1
                self.assertLessEqual(steps, env.max_episode_steps)
                if terminated or truncated:
                    env.reset()
                    episodes, steps = episodes + 1, 0

    def test_determinism_per_seed(self):
        for env_id in ENV_IDS:
            a = rollout(pamdp.make(env_id), 11, 2, 3)
            b = rollout(pamdp.make(env_id), 11, 2, 3)
            self.assertEqual(len(a), len(b))
            for x, y in zip(a, b):
                np.testing.assert_array_equal(x, y)
            c = rollout(pamdp.make(env_id), 12, 2, 3)
            self.assertFalse(len(a) == len(c) and all(np.array_equal(x, y) for x, y in zip(a, c)))
        # A seeded reset decides the episode whatever was played before (HFO carries the body
        # angle between episodes; a seed starts as a fresh env does), in the vector env too.
        for env_id in ("hfo-1v0", "hfo-1v1"):
            used = pamdp.make(env_id)
            rollout(used, 3, 1, 4)
            for x, y in zip(rollout(used, 11, 2, 3), rollout(pamdp.make(env_id), 11, 2, 3)):
                np.testing.assert_array_equal(x, y)
        vec = pamdp.make_vec("hfo-1v0", num_envs=3)
        first, _ = vec.reset(seed=5)
        for _ in range(300):
            vec.step(vec.action_space.sample())
        np.testing.assert_array_equal(vec.reset(seed=5)[0], first)
        # A fresh env that was never seeded plays seed 0's episodes.
        fresh, seeded = pamdp.make("hfo-1v0"), pamdp.make("hfo-1v0")
        np.testing.assert_array_equal(fresh.reset()[0], seeded.reset(seed=0)[0])

    def test_outcomes(self):
        env = pamdp.make("hfo-1v0")
        self.assertEqual(set(dict(env.outcomes).values()), OUTCOMES_HFO)
        # The time limit is truncation, not termination.
        env = pamdp.make("hfo-1v0", max_steps=3, untouched_limit=1000)
        env.reset(seed=1)
        turn = (1, (np.zeros(2, np.float32), np.array([10.0], np.float32), np.zeros(1, np.float32),
                    np.zeros(2, np.float32)))
        results = [env.step(turn) for _ in range(4)]
        obs, reward, terminated, truncated, info = results[-1]
        self.assertTrue(truncated)
        self.assertFalse(terminated)
        self.assertEqual(info["outcome"], "OUT_OF_TIME")
        self.assertFalse(any(r[2] or r[3] for r in results[:-1]))
        # A ball kicked over the line from where the agent stands scores (GOAL is terminated).
        env = pamdp.make("reach_stop")
        obs, _ = env.reset(seed=4)
        while True:  # walk to the target, then STOP: SUCCESS
            gap = obs[2]
            if abs(gap) <= 0.05:
                obs, reward, terminated, truncated, info = env.step((1, (np.zeros(1, np.float32), np.zeros(0))))
                break
            v = np.float32(np.clip(gap / 0.25, -1, 1))
            obs, reward, terminated, truncated, info = env.step((0, (np.array([v]), np.zeros(0))))
        self.assertTrue(terminated)
        self.assertEqual(info["outcome"], "SUCCESS")

    def test_flat_params_equal_per_action_params(self):
        a, b = pamdp.make("hfo-1v1"), pamdp.make("hfo-1v1")
        a.reset(seed=8)
        b.reset(seed=8)
        a.action_space.seed(1)
        for _ in range(200):
            action_id, params = a.action_space.sample()
            flat = np.zeros(6, np.float32)
            layout = [[0, 1], [2], [3], [4, 5]]
            flat[layout[action_id]] = params[action_id]
            ra, rb = a.step((action_id, params)), b.step((action_id, flat))
            np.testing.assert_array_equal(ra[0], rb[0])
            self.assertEqual(ra[1:4], rb[1:4])
            if ra[2] or ra[3]:
                a.reset()
                b.reset()


class VectorEnvTest(unittest.TestCase):
    def check_against_single(self, env_id, num_envs, num_threads, autoreset_mode, copy):
        vec = pamdp.make_vec(env_id, num_envs=num_envs, num_threads=num_threads, autoreset_mode=autoreset_mode,
                             copy=copy)
        singles = [pamdp.make(env_id) for _ in range(num_envs)]
        obs, _ = vec.reset(seed=100)
        for i, env in enumerate(singles):
            np.testing.assert_array_equal(obs[i], env.reset(seed=100 + i)[0])
        vec.action_space.seed(9)
        pending = [False] * num_envs  # next_step: this env resets at the next step
        finished = 0
        for _ in range(400):
            ids, params = vec.action_space.sample()
            obs, reward, terminated, truncated, info = vec.step((ids, params))
            for i, env in enumerate(singles):
                if pending[i]:
                    o = env.reset()[0]
                    np.testing.assert_array_equal(obs[i], o)
                    self.assertEqual((reward[i], terminated[i], truncated[i]), (0, False, False))
                    pending[i] = False
                    continue
                o, r, te, tr, inf = env.step((int(ids[i]), tuple(p[i] for p in params)))
                self.assertEqual((np.float32(r), te, tr, inf["status"]),
                                 (reward[i], terminated[i], truncated[i], info["status"][i]))
                if te or tr:
                    finished += 1
                    if autoreset_mode == "same_step":
                        self.assertTrue(info["_final_obs"][i])
                        np.testing.assert_array_equal(info["final_obs"][i], o)
                        o = env.reset()[0]
                    else:
                        pending[i] = True
                np.testing.assert_array_equal(obs[i], o)
        self.assertGreater(finished, 0)

    def test_matches_single_envs(self):
        self.check_against_single("hfo-1v0", 5, 1, "next_step", True)
        self.check_against_single("hfo-1v1", 6, 3, "next_step", False)
        self.check_against_single("hfo-1v0", 4, 2, "same_step", True)
        self.check_against_single("reach_stop", 7, 2, "same_step", False)

    def test_spaces_and_buffers(self):
        vec = pamdp.make_vec("hfo-1v0", num_envs=8, copy=False)
        self.assertEqual(vec.observation_space.shape, (8, 58))
        self.assertEqual(vec.single_observation_space.shape, (58,))
        ids, params = vec.action_space.sample()
        self.assertEqual(ids.shape, (8,))
        self.assertEqual([p.shape for p in params], [(8, 2), (8, 1), (8, 1), (8, 2)])
        obs, _ = vec.reset()
        out = vec.step((ids, params))
        out2 = vec.step(vec.action_space.sample())
        self.assertIs(out[0], out2[0])  # copy=False: the same preallocated buffer every step
        self.assertIs(out[0], obs)
        flat = np.zeros((8, 6), np.float32)
        vec.step((ids, flat))  # one flat (N, num_params) array works too
        self.assertEqual(set(out[4]), {"status"})  # next_step: no final_obs
        # Large batches in both modes, made and dropped (a buffer overrun would show here).
        for mode in ("next_step", "same_step", "next_step"):
            big = pamdp.make_vec("hfo-1v1", num_envs=300, num_threads=3, autoreset_mode=mode)
            big.reset(seed=2)
            for _ in range(120):
                big.step(big.action_space.sample())
            del big
        # The first reset without a seed seeds env i with i.
        fresh = pamdp.make_vec("reach_stop", num_envs=3)
        obs, _ = fresh.reset()
        np.testing.assert_array_equal(obs[2], pamdp.make("reach_stop").reset(seed=2)[0])


class CallerErrors(unittest.TestCase):
    def assertRaisesWith(self, exc, fragment, fn, *args, **kwargs):
        with self.assertRaises(exc) as ctx:
            fn(*args, **kwargs)
        self.assertIn(fragment, str(ctx.exception))

    def test_make(self):
        self.assertRaisesWith(ValueError, "valid: hfo-1v0, hfo-1v1, hfo, reach_stop", pamdp.make, "hfo-2v2")
        self.assertRaisesWith(TypeError, "env id must be a str", pamdp.make, 3)
        self.assertRaisesWith(ValueError, "unknown option 'nosie' (valid: body_at_reset, max_steps, noise",
                              pamdp.make, "hfo-1v0", nosie=False)
        self.assertRaisesWith(ValueError, "'goalie' is fixed", pamdp.make, "hfo-1v0", goalie=True)
        self.assertRaisesWith(ValueError, "'defense_npcs' is fixed by the id ('defense_npcs=0'); make('hfo', "
                              "defense_npcs=...) chooses it", pamdp.make, "hfo-1v1", defense_npcs=2)
        self.assertRaisesWith(ValueError, "unknown option 'noise' (valid: none)", pamdp.make, "reach_stop",
                              noise=False)
        self.assertRaisesWith(ValueError, "'env.start' must be one of: paper, dec2015, hfo", pamdp.make, "hfo-1v0",
                              start="E4")
        self.assertRaisesWith(ValueError, "'env.max_steps' must be within [1, 1000000], got 0", pamdp.make,
                              "hfo-1v0", max_steps=0)
        self.assertRaisesWith(TypeError, "option 'noise' must be a bool, got str", pamdp.make, "hfo-1v0",
                              noise="no")
        self.assertRaisesWith(TypeError, "option 'max_steps' must be an int, got float", pamdp.make, "hfo-1v0",
                              max_steps=2.5)
        self.assertRaisesWith(ValueError, "num_envs must be >= 1", pamdp.make_vec, "hfo-1v0", num_envs=0)
        self.assertRaisesWith(TypeError, "num_threads must be an int", pamdp.make_vec, "hfo-1v0", num_threads="2")
        self.assertRaisesWith(ValueError, "autoreset_mode must be one of", pamdp.make_vec, "hfo-1v0",
                              autoreset_mode="never")
        self.assertRaisesWith(FileNotFoundError, "no checkpoint", pamdp.load_policy, "models/none.ckpt")

    def test_single_env(self):
        env = pamdp.make("hfo-1v0")
        good = env.action_space.sample()
        self.assertRaisesWith(RuntimeError, "call reset() first", env.step, good)
        env.reset(seed=1)
        self.assertRaisesWith(ValueError, "seed must be >= 0", env.reset, seed=-1)
        self.assertRaisesWith(TypeError, "seed must be an int, got str", env.reset, seed="1")
        self.assertRaisesWith(TypeError, "seed must be an int, got float", env.reset, seed=1.5)
        self.assertRaisesWith(ValueError, "reset options", env.reset, options={"x": 1})
        self.assertRaisesWith(TypeError, "action must be a tuple (id, params)", env.step, 3)
        self.assertRaisesWith(ValueError, "must be a pair", env.step, (1,))
        self.assertRaisesWith(ValueError, "7 is not an action id (valid: 0 DASH, 1 TURN, 2 TACKLE, 3 KICK)",
                              env.step, (7, good[1]))
        self.assertRaisesWith(ValueError, "is not an action id", env.step, (-1, good[1]))
        self.assertRaisesWith(TypeError, "discrete action id, must be an int, got float", env.step, (1.0, good[1]))
        self.assertRaisesWith(TypeError, "action[1] must be a tuple of 4 parameter arrays", env.step, (0, None))
        self.assertRaisesWith(TypeError, "of length 2", env.step, (0, good[1][:2]))
        bad = list(good[1])
        bad[0] = np.zeros(3, np.float32)
        self.assertRaisesWith(ValueError, "parameters of DASH, must be a float array of shape (2,)", env.step,
                              (0, bad))
        bad[0] = np.array([np.nan, 0.0], np.float32)
        self.assertRaisesWith(ValueError, "parameter dash_power of DASH is nan", env.step, (0, bad))
        bad[0] = ["a", "b"]
        self.assertRaisesWith(ValueError, "must be a float array", env.step, (0, bad))
        self.assertRaisesWith(ValueError, "must hold all 6 parameters", env.step, (0, np.zeros(5, np.float32)))
        env.step(good)  # the env is still usable after every refused call

    def test_garbage_never_crashes(self):
        env = pamdp.make("hfo-1v1")
        vec = pamdp.make_vec("hfo-1v1", num_envs=3)
        env.reset(seed=1)
        vec.reset(seed=1)
        junk = [None, "kick", b"x", 1.5, {}, {"id": 1}, [], [[]], (None, None), ("0", "1"), (0, "abc"),
                (0, np.array(["a", "b"])), (0, np.zeros((2, 3), np.float32)), (0, [None] * 4), (2**70, ()),
                (np.uint64(2**63), ()), (0, np.zeros(10**6, np.float32)), (0, [np.zeros(2)] * 3),
                (0, np.array([object()] * 6)), (np.array([0]), np.zeros((1, 6))), (0, (1, 2, 3, 4)),
                (np.zeros(3, np.int64), [np.zeros((3, 2)), None, None, None]), (np.zeros((3, 1), np.int64), ()),
                (np.zeros(3, np.int64), np.zeros((3, 6), np.complex64)), (True, ())]
        for action in junk:
            for target in (env, vec):
                with self.assertRaises((TypeError, ValueError, OverflowError), msg=repr(action)):
                    target.step(action)
        env.step(env.action_space.sample())
        vec.step(vec.action_space.sample())

    def test_vector_env(self):
        vec = pamdp.make_vec("hfo-1v0", num_envs=4)
        ids, params = vec.action_space.sample()
        self.assertRaisesWith(RuntimeError, "call reset() first", vec.step, (ids, params))
        vec.reset(seed=1)
        self.assertRaisesWith(ValueError, "one seed per env (4), got 2", vec.reset, seed=[1, 2])
        self.assertRaisesWith(TypeError, "must be an int array, got dtype float64", vec.step,
                              (ids.astype(np.float64), params))
        self.assertRaisesWith(ValueError, "must have shape (4,)", vec.step, (ids[:3], params))
        self.assertRaisesWith(ValueError, "actions[0][2] = 9 is not an action id", vec.step,
                              (np.array([0, 1, 9, 0]), params))
        self.assertRaisesWith(ValueError, "must be a float array of shape (4, 2)", vec.step,
                              (ids, (params[0][:2],) + params[1:]))
        self.assertRaisesWith(ValueError, "shape (4, 6)", vec.step, (ids, np.zeros((4, 5), np.float32)))
        self.assertRaisesWith(TypeError, "actions must be a tuple (ids, params)", vec.step, ids)
        nan = np.full((4, 6), np.nan, np.float32)
        self.assertRaisesWith(ValueError, "is nan", vec.step, (ids, nan))
        vec.step((ids, params))


if __name__ == "__main__":
    unittest.main()
