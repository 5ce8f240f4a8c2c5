"""Teams in Python (issue 79): pamdp.make_team, PettingZoo's parallel API without PettingZoo.
Dicts keyed by agent name, one episode end for all, each player's own observation and reward,
determinism under a seed, one agent equal to the one-player env, and the errors a caller meets.
pamdp.make_team_vec: many games with an agent axis, each game equal to make_team's."""

import unittest

import numpy as np

import pamdp


def play(env, seed, steps):
    """Observations, rewards and infos of `steps` seeded random joint actions from reset(seed)."""
    for a in env.possible_agents:
        env.action_space(a).seed(seed + int(a.split("_")[1]))
    out = [env.reset(seed=seed)]
    for _ in range(steps):
        if not env.agents:
            out.append(env.reset())
            continue
        out.append(env.step({a: env.action_space(a).sample() for a in env.agents}))
    return out


class TeamApi(unittest.TestCase):
    def test_parallel_api(self):
        env = pamdp.make_team("hfo-1v1", agents=2)
        self.assertEqual(env.possible_agents, ["offense_0", "offense_1"])
        self.assertEqual(env.agents, [])
        observations, infos = env.reset(seed=3)
        self.assertEqual(env.agents, env.possible_agents)
        self.assertEqual(env.num_agents, 2)
        for a in env.agents:
            space = env.observation_space(a)
            self.assertEqual(space.shape, (58 + 8 + 8,))
            self.assertTrue(space.contains(observations[a]))
            self.assertEqual(infos[a]["outcome"], "IN_GAME")
        self.assertFalse(np.array_equal(observations["offense_0"], observations["offense_1"]),
                         "each player observes from its own place")
        steps = 0
        while env.agents:
            acting = list(env.agents)
            observations, rewards, terminations, truncations, infos = env.step(
                {a: env.action_space(a).sample() for a in acting})
            steps += 1
            for d in (observations, rewards, terminations, truncations, infos):
                self.assertEqual(sorted(d), acting)
            self.assertTrue(all(isinstance(r, float) for r in rewards.values()))
        self.assertIn(infos["offense_0"]["outcome"], ("GOAL", "CAPTURED_BY_DEFENSE", "OUT_OF_BOUNDS", "OUT_OF_TIME"))
        self.assertEqual(len({i["outcome"] for i in infos.values()}), 1, "one episode end for the team")
        self.assertNotEqual(terminations["offense_0"], truncations["offense_0"])
        with self.assertRaises(RuntimeError):
            env.step({})

    def test_same_seed_same_game(self):
        a = play(pamdp.make_team("hfo-1v1", agents=2), 5, 300)
        b = play(pamdp.make_team("hfo-1v1", agents=2), 5, 300)
        for x, y in zip(a, b):
            for dx, dy in zip(x, y):
                for key in dx:
                    np.testing.assert_array_equal(np.asarray(dx[key], dtype=object), np.asarray(dy[key], dtype=object))

    def test_one_agent_is_the_one_player_env(self):
        team = pamdp.make_team("hfo-1v1", agents=1)
        single = pamdp.make("hfo-1v1")
        obs_t, _ = team.reset(seed=9)
        obs_s, _ = single.reset(seed=9)
        np.testing.assert_array_equal(obs_t["offense_0"], obs_s)
        space = single.action_space
        space.seed(4)
        for _ in range(400):
            action = space.sample()
            obs_t, rew_t, term_t, trunc_t, info_t = team.step({"offense_0": action})
            obs_s, rew_s, term_s, trunc_s, info_s = single.step(action)
            np.testing.assert_array_equal(obs_t["offense_0"], obs_s)
            self.assertEqual(rew_t["offense_0"], rew_s)
            self.assertEqual((term_t["offense_0"], trunc_t["offense_0"]), (term_s, trunc_s))
            self.assertEqual(info_t["offense_0"]["outcome"], info_s["outcome"])
            if term_s or trunc_s:
                obs_t, _ = team.reset()
                obs_s, _ = single.reset()
                np.testing.assert_array_equal(obs_t["offense_0"], obs_s)

    def test_errors_name_the_fix(self):
        with self.assertRaisesRegex(ValueError, "hfo id"):
            pamdp.make_team("platform", agents=2)
        with self.assertRaisesRegex(ValueError, r"agents must be within \[1, 4\]"):
            pamdp.make_team("hfo-1v0", agents=5)
        with self.assertRaises(TypeError):
            pamdp.make_team("hfo-1v0", agents="2")
        env = pamdp.make_team("hfo-1v0", agents=2, noise=False)
        env.reset(seed=1)
        with self.assertRaisesRegex(KeyError, "missing"):
            env.step({"offense_0": env.action_space("offense_0").sample()})
        with self.assertRaisesRegex(KeyError, "offense_2"):
            env.observation_space("offense_2")


class TeamVectorEnvTest(unittest.TestCase):
    def test_each_game_is_make_teams_game(self):
        """Game i of make_team_vec(seed=s) against make_team reset with s + i, the same actions in,
        through episode ends (next-step autoreset: the step after an end starts the next game)."""
        n, agents = 3, 2
        vec = pamdp.make_team_vec("hfo-1v1", agents=agents, num_envs=n, num_threads=2)
        self.assertEqual(vec.observation_space.shape, (n, agents, 74))
        games = [pamdp.make_team("hfo-1v1", agents=agents) for _ in range(n)]
        obs, _ = vec.reset(seed=20)
        self.assertEqual(obs.shape, (n, agents, 74))
        names = games[0].possible_agents
        for i, game in enumerate(games):
            first, _ = game.reset(seed=20 + i)
            np.testing.assert_array_equal(obs[i], np.stack([first[a] for a in names]))
        vec.action_space.seed(3)
        pending = [False] * n
        ends = 0
        for _ in range(500):
            ids, params = vec.action_space.sample()
            obs, reward, terminated, truncated, info = vec.step((ids, params))
            self.assertEqual(reward.shape, (n, agents))
            self.assertEqual(terminated.shape, (n,))
            for i, game in enumerate(games):
                if pending[i]:
                    expected, _ = game.reset()
                    pending[i] = False
                    np.testing.assert_array_equal(reward[i], 0.0)
                    self.assertFalse(terminated[i] or truncated[i])
                else:
                    actions = {a: (int(ids[i, k]), tuple(p[i, k] for p in params)) for k, a in enumerate(names)}
                    expected, rewards, terms, truncs, infos = game.step(actions)
                    np.testing.assert_array_equal(reward[i], np.array([rewards[a] for a in names], np.float32))
                    self.assertEqual((bool(terminated[i]), bool(truncated[i])), (terms["offense_0"], truncs["offense_0"]))
                    self.assertEqual(int(info["status"][i]), infos["offense_0"]["status"])
                    pending[i] = terms["offense_0"] or truncs["offense_0"]
                    ends += pending[i]
                np.testing.assert_array_equal(obs[i], np.stack([expected[a] for a in names]))
        self.assertGreater(ends, 3, "games must end for the autoreset to be checked")

    def test_one_array_of_parameters_and_errors(self):
        vec = pamdp.make_team_vec("hfo-1v0", agents=2, num_envs=2, noise=False)
        vec.reset(seed=1)
        ids = np.zeros((2, 2), dtype=np.int64)
        obs, reward, *_ = vec.step((ids, np.zeros((2, 2, 6), dtype=np.float32)))
        self.assertEqual(obs.shape, (2, 2, 66))
        with self.assertRaisesRegex(ValueError, r"shape \(2, 2\)"):
            vec.step((np.zeros(4, dtype=np.int64), np.zeros((2, 2, 6), dtype=np.float32)))
        with self.assertRaisesRegex(ValueError, "games, agents, parameters"):
            vec.step((ids, np.zeros((4, 6), dtype=np.float32)))
        with self.assertRaisesRegex(ValueError, "hfo id"):
            pamdp.make_team_vec("platform", agents=2)
        with self.assertRaisesRegex(ValueError, r"agents must be within \[1, 4\]"):
            pamdp.make_team_vec("hfo-1v1", agents=5)
        with self.assertRaisesRegex(ValueError, r"agents must be within \[1, 4\]"):
            pamdp.make_team_vec("hfo-1v1", agents=0)
        with self.assertRaises(TypeError):
            pamdp.make_team_vec("hfo-1v1", agents=None)
        with self.assertRaisesRegex(ValueError, "make_team_vec"):
            pamdp.make_vec("hfo-1v1", num_envs=2, offense_agents=2)


if __name__ == "__main__":
    unittest.main()
