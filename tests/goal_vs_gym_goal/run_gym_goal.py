"""Plays gym-goal's own GoalEnv with a scripted random policy and prints every state.

Usage: run_gym_goal.py NOISE(0|1) EPISODES KICK_TO_PROBABILITY, with PYTHONPATH holding a
gym-goal checkout and stubs/ (numpy, gym and pygame stand-ins; numpy need not be installed).
run_goal_env.cpp plays the same policy on our GoalEnv; compare.py diffs the two.
"""
import struct
import sys

from gym.utils import seeding
from gym_goal.envs import config
from gym_goal.envs.goal_env import GoalEnv
import numpy as np


def f32(x):
    """The value as a float32 parameter, as our env receives it."""
    return struct.unpack('f', struct.pack('f', x))[0]


noise = sys.argv[1] == '1'
episodes = int(sys.argv[2])
kick = float(sys.argv[3])
if not noise:
    # Our env takes no draws with the noise off; gym-goal draws from zero-width ranges.
    seeding.NO_DRAW_WHEN_EMPTY = True
    config.PLAYER_CONFIG['RAND'] = 0.0
    config.BALL_CONFIG['RAND'] = 0.0
policy = seeding.Xoshiro(99)
env = GoalEnv()
env.seed(5)
for episode in range(episodes):
    if episode > 0:
        env.reset()
    print('R', ' '.join(repr(v) for v in env.get_state().v))
    while True:
        a = policy.u()
        if a < kick:
            act = 0
            p = [f32(-2 + 18 * policy.u()), f32(-20 + 40 * policy.u())]
        else:
            act = 1 if a < (1 + kick) / 2 else 2
            p = [f32(-10 + 20 * policy.u())]
        params = [np.array([0, 0]), np.array([0]), np.array([0])]
        params[act] = np.array(p)
        (state, steps), reward, terminal, _ = env.step((act, params))
        print('S', steps, repr(float(reward)), int(terminal), ' '.join(repr(v) for v in state.v))
        if terminal:
            break
