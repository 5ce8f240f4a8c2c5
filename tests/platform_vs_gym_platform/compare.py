"""Differential check of envs/platform against gym-platform's own Python code, noise off.

Loads gym_platform/envs/platform_env.py with gym and pygame replaced by stand-ins (numpy is
the real one) and its random source replaced by zeros, plays episodes on it, and plays the
same actions on ours (the driver run_platform_env). Two kinds of episodes: random actions, and
a search that at each step tries random actions on a copy of the gym env and keeps one that
does not end in failure (it reaches the goal now and then). Parameters are multiples of 1/64,
which a float holds exactly. Every step must agree on ticks, terminal, reward (to 1e-6, ours is
a float), observation (1e-6) and positions (1e-9 relative).

Usage: compare.py GYM_PLATFORM_DIR DRIVER EPISODES SEED
"""
import copy
import importlib.util
import json
import random
import subprocess
import sys
import types

import numpy as np


def load_gym_platform(root):
    gym = types.ModuleType("gym")
    gym.Env = object
    spaces = types.ModuleType("gym.spaces")
    spaces.Box = lambda *a, **k: None
    spaces.Discrete = lambda n: None
    spaces.Tuple = lambda t: types.SimpleNamespace(spaces=t)
    gym.spaces = spaces
    utils = types.ModuleType("gym.utils")
    seeding = types.ModuleType("gym.utils.seeding")
    seeding.np_random = lambda seed=None: (np.random.RandomState(seed), seed)
    utils.seeding = seeding
    gym.utils = utils
    sys.modules.update({"gym": gym, "gym.spaces": spaces, "gym.error": types.ModuleType("gym.error"),
                        "gym.utils": utils, "gym.utils.seeding": seeding, "pygame": types.ModuleType("pygame"),
                        "numba": None})
    spec = importlib.util.spec_from_file_location("platform_env", f"{root}/gym_platform/envs/platform_env.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class Zero:
    """The env's np_random with every draw 0: gym-platform with the noise off."""

    def normal(self, loc=0.0, scale=1.0, size=None):
        return np.zeros(size) if size is not None else 0.0


MAX_PARAM = [30, 720, 430]


def gym_step(env, a, p):
    params = [np.array([0.0]), np.array([0.0]), np.array([0.0])]
    params[a][0] = p
    (state, ticks), reward, terminal, _ = env.step((a, params))
    return {"ticks": ticks, "terminal": bool(terminal), "reward": float(reward), "px": float(env.player.position[0]),
            "py": float(env.player.position[1]), "e0": float(env.enemy1.position[0]),
            "e1": float(env.enemy2.position[0]), "obs": [float(v) for v in 2 * state - 1]}


def play(env, rng, search):
    env.reset()
    actions, steps = [], []
    for _ in range(200):
        a = rng.choice([0, 0, 1, 2])
        p = round(rng.uniform(-5, MAX_PARAM[a] * 1.1) * 64) / 64
        if search:
            for _ in range(30):
                trial = copy.deepcopy(env)
                r = gym_step(trial, a, p)
                if not r["terminal"] or trial.player.position[0] >= 1035:
                    break
                a = rng.choice([0, 0, 1, 2])
                p = round(rng.uniform(0, MAX_PARAM[a]) * 64) / 64
        actions.append((a, p))
        steps.append(gym_step(env, a, p))
        if steps[-1]["terminal"]:
            break
    return actions, steps


def agree(x, y):
    close = lambda u, v, tol: abs(u - v) <= tol * max(1.0, abs(u))
    return (x["ticks"] == y["ticks"] and x["terminal"] == y["terminal"] and abs(x["reward"] - y["reward"]) < 1e-6
            and all(close(x[k], y[k], 1e-9) for k in ("px", "py", "e0", "e1"))
            and all(abs(u - v) < 1e-6 for u, v in zip(x["obs"], y["obs"])))


def main():
    root, driver, episodes, seed = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    module = load_gym_platform(root)
    env = module.PlatformEnv()
    env.np_random = Zero()
    env._update_seeds()
    rng = random.Random(seed)
    mismatched, decisions, goals = 0, 0, 0
    for ep in range(episodes):
        actions, theirs = play(env, rng, search=ep % 2 == 1)
        out = subprocess.run([driver], input=" ".join(f"{a} {p!r}" for a, p in actions), capture_output=True,
                             text=True, check=True).stdout
        ours = [json.loads(line) for line in out.splitlines()]
        decisions += len(theirs)
        goals += int(theirs[-1]["terminal"] and theirs[-1]["px"] >= 1035)
        if len(ours) != len(theirs) or not all(agree(x, y) for x, y in zip(theirs, ours)):
            mismatched += 1
            if mismatched <= 3:
                print(f"episode {ep} differs:\n gym  {theirs}\n ours {ours}")
    print(f"{episodes} episodes, {decisions} decision steps, {goals} reaching the goal: {mismatched} differ")
    return 1 if mismatched else 0


if __name__ == "__main__":
    sys.exit(main())
