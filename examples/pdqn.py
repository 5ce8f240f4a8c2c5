#!/usr/bin/env python3
"""P-DQN (Xiong et al. 2018, "Parametrized Deep Q-Networks Learning") on a pamdp vector env, in
PyTorch: a parameter network x(s) proposes every discrete action's parameters, a Q network
Q(s, x) scores the discrete actions, the agent plays argmax_a Q(s, x(s))_a with x(s)'s
parameters. A starting point for one's own research: it learns the toy task (reach_stop) in
seconds; on HFO it runs as is (--env hfo-1v0) but needs far more steps and tuning.

    PYTHONPATH=build/python /usr/bin/python3 examples/pdqn.py [--env reach_stop] [--iterations 3000]

Exits 0 when the greedy agent's success rate on fresh episodes reaches --target, 1 when not,
77 (skipped) without PyTorch (Debian: apt-get install python3-torch).
"""

import argparse
import copy
import sys
import time

import numpy as np

try:
    import torch
    import torch.nn.functional as F
    from torch import nn
except ImportError:
    print("examples/pdqn.py: skipped, PyTorch is not installed (apt-get install python3-torch)")
    sys.exit(77)

import pamdp


def mlp(inputs: int, outputs: int, hidden: int = 64) -> nn.Module:
    return nn.Sequential(nn.Linear(inputs, hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU(),
                         nn.Linear(hidden, outputs))


class Agent:
    """The two networks, their targets and the updates."""

    def __init__(self, obs_dim: int, boxes, gamma: float, lr_q: float, lr_x: float, tau: float):
        self.low = torch.tensor(np.concatenate([b.low for b in boxes]))
        self.high = torch.tensor(np.concatenate([b.high for b in boxes]))
        self.num_actions, self.num_params = len(boxes), len(self.low)
        self.x_net = mlp(obs_dim, self.num_params)  # every parameter, in the env's flat order
        self.q_net = mlp(obs_dim + self.num_params, self.num_actions)
        self.x_target, self.q_target = copy.deepcopy(self.x_net), copy.deepcopy(self.q_net)
        self.x_opt = torch.optim.Adam(self.x_net.parameters(), lr=lr_x)
        self.q_opt = torch.optim.Adam(self.q_net.parameters(), lr=lr_q)
        self.gamma, self.tau = gamma, tau

    def params(self, net, obs):
        """Parameters within the action space's bounds (tanh squashing)."""
        return self.low + (torch.tanh(net(obs)) + 1) * 0.5 * (self.high - self.low)

    def q(self, net, obs, params):
        return net(torch.cat([obs, params / self.high.abs().clamp(min=1)], dim=1))

    @torch.no_grad()
    def act(self, obs: np.ndarray):
        o = torch.as_tensor(obs)
        x = self.params(self.x_net, o)
        return self.q(self.q_net, o, x).argmax(1).numpy(), x.numpy()

    def update(self, s, a, x, r, s2, term):
        with torch.no_grad():
            q2 = self.q(self.q_target, s2, self.params(self.x_target, s2)).max(1).values
            y = r + self.gamma * (1 - term) * q2
        q = self.q(self.q_net, s, x).gather(1, a[:, None]).squeeze(1)
        q_loss = F.smooth_l1_loss(q, y)
        self.q_opt.zero_grad()
        q_loss.backward()
        self.q_opt.step()
        # P-DQN's parameter step: raise the Q of every action through its proposed parameters.
        x_loss = -self.q(self.q_net, s, self.params(self.x_net, s)).sum(1).mean()
        self.x_opt.zero_grad()
        x_loss.backward()
        self.x_opt.step()
        with torch.no_grad():
            for net, target in ((self.q_net, self.q_target), (self.x_net, self.x_target)):
                for p, tp in zip(net.parameters(), target.parameters()):
                    tp.mul_(1 - self.tau).add_(self.tau * p)
        return q_loss.item()


def success_rate(agent: Agent, env_id: str, episodes: int, seed: int) -> float:
    """Greedy play: the first episode of each of `episodes` envs, on starts training never saw."""
    vec = pamdp.make_vec(env_id, num_envs=episodes, autoreset_mode="same_step", copy=False)
    obs, _ = vec.reset(seed=seed)
    outcome = np.full(episodes, -1)
    while np.any(outcome < 0):
        ids, params = agent.act(obs)
        obs, _, terminated, truncated, info = vec.step((ids, params))
        done = (terminated | truncated) & (outcome < 0)
        outcome[done] = info["status"][done]
    return float(np.mean(outcome == vec.success_status))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="reach_stop", help="a pamdp env id (pamdp.env_ids())")
    parser.add_argument("--num-envs", type=int, default=16)
    parser.add_argument("--iterations", type=int, default=3000, help="vector steps, one update each")
    parser.add_argument("--batch", type=int, default=128)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--target", type=float, default=0.9, help="greedy success rate to reach")
    args = parser.parse_args()

    torch.manual_seed(args.seed)
    torch.set_num_threads(1)
    rng = np.random.default_rng(args.seed)
    vec = pamdp.make_vec(args.env, num_envs=args.num_envs, autoreset_mode="same_step")
    boxes = vec.single_action_space[1]
    obs_dim = vec.single_observation_space.shape[0]
    agent = Agent(obs_dim, boxes, gamma=0.95, lr_q=1e-3, lr_x=1e-4, tau=0.01)

    capacity = 200_000
    S = np.zeros((capacity, obs_dim), np.float32)
    S2 = np.zeros_like(S)
    A = np.zeros(capacity, np.int64)
    X = np.zeros((capacity, agent.num_params), np.float32)
    R = np.zeros(capacity, np.float32)
    T = np.zeros(capacity, np.float32)
    size = 0

    start = time.time()
    obs, _ = vec.reset(seed=args.seed)
    returns, episode_return, finished, loss = [], np.zeros(args.num_envs), 0, float("nan")
    for it in range(args.iterations):
        epsilon = max(0.05, 1.0 - it / (0.3 * args.iterations))
        ids, params = agent.act(obs)
        explore = rng.random(args.num_envs) < epsilon
        ids[explore] = rng.integers(agent.num_actions, size=int(explore.sum()))
        params[explore] = rng.uniform(agent.low.numpy(), agent.high.numpy(), (int(explore.sum()), agent.num_params))
        next_obs, reward, terminated, truncated, info = vec.step((ids, params))  # one flat parameter array
        done = terminated | truncated
        # same_step autoreset: next_obs already starts the next episode where done; the episode's
        # last observation is in final_obs. Time-outs (truncated) still bootstrap.
        last_obs = np.where(done[:, None], info["final_obs"], next_obs)
        k = np.arange(size, size + args.num_envs) % capacity
        S[k], A[k], X[k], R[k], S2[k], T[k] = obs, ids, params, reward, last_obs, terminated
        size = min(size + args.num_envs, capacity)
        obs = next_obs
        episode_return += reward
        returns.extend(episode_return[done].tolist())
        episode_return[done] = 0
        finished += int(done.sum())
        if size >= 1000:
            b = rng.integers(size, size=args.batch)
            loss = agent.update(*(torch.as_tensor(v[b]) for v in (S, A, X, R, S2, T)))
        if (it + 1) % 500 == 0:
            print(f"iteration {it + 1:5d}  episodes {finished:6d}  mean return (last 100) "
                  f"{np.mean(returns[-100:]):6.3f}  epsilon {epsilon:.2f}  q loss {loss:.4f}  "
                  f"{time.time() - start:5.1f} s", flush=True)

    rate = success_rate(agent, args.env, episodes=500, seed=10_000 + args.seed)
    print(f"greedy success rate on 500 fresh episodes: {rate:.3f} (target {args.target}), "
          f"{time.time() - start:.1f} s, {size} transitions")
    return 0 if rate >= args.target else 1


if __name__ == "__main__":
    sys.exit(main())
