"""pamdp from Python: the embedded HFO simulator and the toy tasks as Gymnasium-style envs, a
vector env stepped in C++, and trained agents.

    import pamdp
    env = pamdp.make("hfo-1v0")                  # or "hfo-1v1" (the goalie), "reach_stop", ...
    obs, info = env.reset(seed=1)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    info["outcome"]                              # "IN_GAME", "GOAL", "OUT_OF_BOUNDS", ...
    print(env.render("ansi"))                    # the field as text

Actions (MP-DQN's convention for parameterized action spaces): a pair (id, params) where id is
the discrete action (HFO: 0 DASH, 1 TURN, 2 TACKLE, 3 KICK) and params is a tuple with one
float32 array per discrete action holding that action's parameters (HFO: DASH (power, dir),
TURN (dir,), TACKLE (dir,), KICK (power, dir)); only params[id] is read. params may also be
one flat array of every parameter in the env's shared order (HFO: dash_power, dash_dir,
turn_dir, tackle_dir, kick_power, kick_dir), the layout of a P-DQN or PA-DDPG actor's output.
action_space is Tuple(Discrete(n), Tuple(Box per action)). A parameter outside the bounds is
neither refused nor clipped to them here: the env clamps it to the range it accepts, as the real
HFO does (HFO: powers to the server's range, where a negative dash power dashes backward;
directions to [-180, 180]), so that Python plays what `pamdp eval` plays. Env warns once when it
meets one; gymnasium.wrappers.ClipAction clips to the bounds instead.

Episodes end with terminated (a terminal outcome: GOAL, OUT_OF_BOUNDS, CAPTURED_BY_DEFENSE) or
truncated (OUT_OF_TIME, the time limit); info["outcome"] names it and info["status"] gives
its code. While an episode goes on info["outcome"] is "IN_GAME" in every env (HFO's word; the
toy envs' C++ traces call it IN_PROGRESS), info["status"] 0. Env options are keyword arguments named as the config file's env.* keys
(pamdp.make("hfo-1v0", noise=False, start="hfo")), validated the same way.
"""

from __future__ import annotations

import math
import numbers
import os
import tomllib

import numpy as np

from . import _pamdp
from . import spaces

__all__ = ["Env", "EnvSpec", "VectorEnv", "ParallelEnv", "TeamVectorEnv", "Policy", "make", "make_vec", "make_team",
           "make_team_vec", "load_policy", "evaluate", "env_ids",
           "spaces"]


def env_ids() -> dict:
    """Every env id make() accepts, with a line on each."""
    return dict(_pamdp.env_ids())


def _check_id(env_id) -> None:
    if not isinstance(env_id, str):
        raise TypeError(f"env id must be a str such as 'hfo-1v0', got {type(env_id).__name__}")


def _toml_value(env_id: str, key: str, value, default) -> str:
    """`value` for option `key` as TOML text, checked against the type of its default."""

    def wrong(kind: str):
        return TypeError(f"pamdp.make('{env_id}'): option '{key}' must be {kind}, got {type(value).__name__}")

    if isinstance(default, bool):
        if not isinstance(value, (bool, np.bool_)):
            raise wrong("a bool")
        return "true" if value else "false"
    if isinstance(default, int):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
            raise wrong("an int")
        return str(int(value))
    if isinstance(default, float):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise wrong("a number")
        v = float(value)
        return repr(v) if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    if isinstance(default, str):
        if not isinstance(value, str):
            raise wrong("a str")
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    raise wrong(type(default).__name__)


def _options(env_id, options: dict) -> dict:
    """Keyword options as {key: TOML text} for the C++ side, which checks names and ranges."""
    _check_id(env_id)
    valid = _pamdp.option_names(env_id)  # ValueError for an unknown id, naming the valid ones
    defaults = tomllib.loads(_pamdp.defaults_toml(env_id))["env"]
    out = {}
    for key, value in options.items():
        # An unknown or fixed key: the C++ side raises the ValueError naming the valid ones.
        out[key] = _toml_value(env_id, key, value, defaults[key]) if key in valid else "0"
    return out


class EnvSpec:
    """What builds an env again, as gymnasium.envs.registration.EnvSpec says it: id, entry_point,
    max_episode_steps and the keyword arguments; make() builds the same env."""

    def __init__(self, id: str, max_episode_steps: int, kwargs: dict):
        self.id = id
        self.entry_point = "pamdp:make"
        self.max_episode_steps = max_episode_steps
        self.kwargs = dict(kwargs)

    def make(self) -> "Env":
        return make(self.id, **self.kwargs)

    def __repr__(self):
        return f"EnvSpec(id={self.id!r}, entry_point={self.entry_point!r}, " \
               f"max_episode_steps={self.max_episode_steps}, kwargs={self.kwargs!r})"


class Env(_pamdp.Env):
    """One env with Gymnasium's API: reset(seed=None, options=None) -> (obs, info) and
    step(action) -> (obs, reward, terminated, truncated, info). Observations are fresh float32
    arrays. A fresh env never seeded plays the episodes of seed 0; reset() without a seed
    continues the env's own random stream, as `pamdp eval` does between episodes.

    As a gymnasium.Env: spec (EnvSpec: id and options), np_random (a NumPy Generator that
    reset(seed=s) reseeds from s; the env's own dynamics draw from the C++ env's stream),
    metadata["render_modes"] == ["ansi"] and render(): with render_mode="ansi" (make's keyword)
    or render("ansi"), the field as text (HFO: the half field with agent, goalie and ball, then
    their positions; the toy tasks: their state)."""

    metadata = {"render_modes": ["ansi"]}

    def __init__(self, env_id: str = "hfo-1v0", render_mode=None, **options):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or one of {self.metadata['render_modes']}, got {render_mode!r}")
        super().__init__(env_id, _options(env_id, options))
        self.render_mode = render_mode
        bound = self.observation_bound
        self.observation_space = spaces.Box(-bound, bound, (self.observation_size,), np.float32)
        self.action_space = spaces.action_space(self.actions)
        self.spec = EnvSpec(self.env_id, self.max_episode_steps, options)
        self._np_random = None
        self._np_random_seed = None

    def reset(self, seed=None, options=None):
        obs, info = super().reset(seed, options)
        if seed is not None:
            self._np_random = np.random.default_rng(seed)
            self._np_random_seed = seed
        return obs, info

    @property
    def np_random(self) -> np.random.Generator:
        """Gymnasium's per-env generator, seeded by reset(seed=...) (from the OS until then)."""
        if self._np_random is None:
            self._np_random = np.random.default_rng()
            self._np_random_seed = -1
        return self._np_random

    @np_random.setter
    def np_random(self, value: np.random.Generator):
        self._np_random = value
        self._np_random_seed = -1

    @property
    def np_random_seed(self) -> int:
        """The seed np_random was last seeded with (-1: not from a seed), as Gymnasium >= 1.0 has it."""
        if self._np_random is None:
            self.np_random  # noqa: B018 (creates it)
        return self._np_random_seed

    @property
    def unwrapped(self):
        return self

    @property
    def options(self) -> dict:
        """The env's settings that make() takes, defaults included: make(env.env_id, **env.options)
        builds the same env."""
        table = tomllib.loads(self.config_toml)["env"]
        return {k: table[k] for k in _pamdp.option_names(self.env_id)}

    def render(self, mode=None):
        """The field as text for mode "ansi" (default: the env's render_mode); None without a mode."""
        mode = self.render_mode if mode is None else mode
        if mode is None:
            return None
        if mode not in self.metadata["render_modes"]:
            raise ValueError(f"render mode must be one of {self.metadata['render_modes']}, got {mode!r}")
        return self.render_text()

    def close(self):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self):
        return f"pamdp.Env('{self.env_id}')"


class _BatchedEnv(_pamdp.VectorEnv):
    """What VectorEnv and TeamVectorEnv share: the argument checks, the spaces (a batch of
    num_envs, or of (num_envs, agents) for a team: agents given) and Gymnasium's vector-env
    conveniences."""

    metadata = {"render_modes": []}
    render_mode = None
    spec = None

    def __init__(self, env_id, num_envs, num_threads, autoreset_mode, copy, options, agents=None):
        team = agents is not None
        for name, value in (("agents", agents if team else 0), ("num_envs", num_envs), ("num_threads", num_threads)):
            if isinstance(value, bool) or not isinstance(value, numbers.Integral):
                raise TypeError(f"{name} must be an int, got {type(value).__name__}")
        if not isinstance(autoreset_mode, str):
            raise TypeError(f"autoreset_mode must be a str, got {type(autoreset_mode).__name__}")
        super().__init__(env_id, _options(env_id, options), int(num_envs), int(num_threads), autoreset_mode,
                         bool(copy), int(agents) if team else None)
        self.metadata = {"render_modes": [], "autoreset_mode": autoreset_mode}
        batch = (self.num_envs, self.num_agents) if team else (self.num_envs,)
        bound = self.observation_bound
        self.single_observation_space = spaces.Box(-bound, bound, (self.observation_size,), np.float32)
        self.single_action_space = spaces.action_space(self.actions)
        self.observation_space = spaces.Box(-bound, bound, batch + (self.observation_size,), np.float32)
        self.action_space = spaces.action_space(self.actions, batch)

    @property
    def unwrapped(self):
        return self

    def close(self):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class VectorEnv(_BatchedEnv):
    """num_envs envs stepped together in C++ (num_threads threads), writing into preallocated
    NumPy arrays: step(actions) -> (obs (N, obs), reward (N,), terminated (N,), truncated (N,),
    info) with info["status"] the envs' status codes. actions is (ids of shape (N,), params),
    params a tuple of one (N, k) float32 array per discrete action or one (N, num_params) array;
    action_space.sample() draws such a batch.

    Finished envs reset themselves (autoreset_mode): "next_step" (Gymnasium >= 1.0's default,
    EnvPool's) resets an env on the step after its episode ended, ignoring that step's action
    and returning the new episode's first obs with reward 0; "same_step" resets at once and puts
    the terminal obs in info["final_obs"] (rows where info["_final_obs"] is True).
    With copy=True (default) every call returns fresh arrays; copy=False returns the
    preallocated buffers themselves, which the next call overwrites (no copy at all).
    reset(seed=s) seeds env i with s + i (a sequence gives each env its own); the first reset
    without a seed uses 0 + i."""

    def __init__(self, env_id: str = "hfo-1v0", num_envs: int = 1, num_threads: int = 1,
                 autoreset_mode: str = "next_step", copy: bool = True, **options):
        super().__init__(env_id, num_envs, num_threads, autoreset_mode, copy, options)

    def __repr__(self):
        return f"pamdp.VectorEnv('{self.env_id}', num_envs={self.num_envs}, num_threads={self.num_threads})"


class TeamVectorEnv(_BatchedEnv):
    """num_envs embedded HFO games of `agents` learned players each (make_team's game), stepped
    together in C++ (num_threads threads) into preallocated NumPy arrays, with an agent axis:
    step(actions) -> (obs (N, A, obs), reward (N, A), terminated (N,), truncated (N,), info),
    info["status"] the games' status codes (N,). Player a of game i is make_team's "offense_a":
    obs[i, a] is its own observation and reward[i, a] its own reward; a game ends for all its
    players at once. actions is (ids of shape (N, A), params), params a tuple of one (N, A, k)
    float32 array per discrete action or one (N, A, num_params) array; action_space.sample()
    draws such a batch. Autoreset, copy and seeding are VectorEnv's: reset(seed=s) seeds game i
    with s + i, and game i then plays as make_team(env_id, agents).reset(seed=s + i) would."""

    def __init__(self, env_id: str = "hfo-1v1", agents: int = 2, num_envs: int = 1, num_threads: int = 1,
                 autoreset_mode: str = "next_step", copy: bool = True, **options):
        if agents is None:  # the base class reads None as make_vec's env
            raise TypeError("agents must be an int, got NoneType")
        super().__init__(env_id, num_envs, num_threads, autoreset_mode, copy, options, agents)
        self.possible_agents = [f"offense_{i}" for i in range(self.num_agents)]

    def step(self, actions):
        """One cycle of every game: actions = (ids (N, A), params (N, A, ...)), as action_space."""
        batch = (self.num_envs, self.num_agents)
        rows = self.num_envs * self.num_agents
        if not isinstance(actions, (tuple, list)) or len(actions) != 2:
            raise TypeError(f"actions must be a pair (ids of shape {batch}, params), got {type(actions).__name__}"
                            + (f" of {len(actions)} items" if isinstance(actions, (tuple, list)) else ""))
        ids, params = actions
        ids = np.asarray(ids)
        if ids.shape != batch:
            raise ValueError(f"actions[0], the discrete action ids, must have shape {batch} (games, agents), "
                             f"got {ids.shape}")

        def flat(a, what):
            a = np.asarray(a, dtype=np.float32)
            if a.ndim != 3 or a.shape[:2] != batch:
                raise ValueError(f"{what} must have shape {batch} + (k,) (games, agents, parameters), got {a.shape}")
            return a.reshape(rows, a.shape[2])

        if isinstance(params, np.ndarray):
            params = flat(params, "actions[1]")
        elif isinstance(params, (tuple, list)):
            params = tuple(flat(p, f"actions[1][{i}]") for i, p in enumerate(params))
        return super().step((ids.reshape(rows), params))

    def __repr__(self):
        return (f"pamdp.TeamVectorEnv('{self.env_id}', agents={self.num_agents}, num_envs={self.num_envs}, "
                f"num_threads={self.num_threads})")


class Policy(_pamdp.Policy):
    """A checkpoint's actor (of any learner, `algorithm`: "ddpg", "pdqn", "mpdqn"): policy(obs) for one observation (obs_size,) returns one action
    (id, params); for a batch (B, obs_size) it returns (ids (B,), params), the vector env's
    action format. Greedy by default: the action `pamdp eval` plays (the actor copy its run
    evaluated, masked actions never chosen, parameters as the actor outputs them; the env clamps
    them). With exploration=True: the checkpoint's ε-greedy selection at `epsilon` (default: its
    schedule's value at the checkpoint's update count), seeded by `seed`."""

    def make_env(self) -> Env:
        """The env the checkpoint was trained on, with its settings."""
        table = tomllib.loads(self.config_toml)["env"]
        return make(self.env_id, **{k: table[k] for k in _pamdp.option_names(self.env_id)})

    def __repr__(self):
        return f"pamdp.Policy({self.algorithm}, env '{self.env_id}', {self.updates} updates, actor {self.actor})"


def make(env_id: str = "hfo-1v0", render_mode=None, **options) -> Env:
    """A new env: make("hfo-1v0"), make("hfo-1v1"), make("reach_stop"), make("hfo", goalie=True),
    with env options as keyword arguments (noise=False, start="hfo", max_steps=300, ...) and
    render_mode=None or "ansi" (env.render() then returns the field as text)."""
    return Env(env_id, render_mode=render_mode, **options)


def _ids_help() -> str:
    return "\n\n    Env ids (pamdp.env_ids()):\n" + "\n".join(
        f"      {env_id:<12} {description}" for env_id, description in _pamdp.env_ids())


make.__doc__ += _ids_help()


class ParallelEnv:
    """N learned offense players in one embedded HFO game (HFO's --offense-agents N), with
    PettingZoo's parallel API and no PettingZoo dependency: agents are named "offense_0" ...
    "offense_{N-1}" (player 0 is the agent of the one-player env), and reset, step, the spaces
    and the infos are dicts keyed by those names.

        env = pamdp.make_team("hfo-1v1", agents=2)        # 2v1 against agent2d's goalie
        observations, infos = env.reset(seed=1)
        while env.agents:
            actions = {a: env.action_space(a).sample() for a in env.agents}
            observations, rewards, terminations, truncations, infos = env.step(actions)

    Each player observes its own features (58, then 8 per other player: its teammates nearest
    first, then its opponents) and earns its own reward (dqn-hfo's, from its own features); the
    episode ends for all at once, and infos[agent]["outcome"] names how (as Env's info). Actions
    are Env's: (id, params) per agent. Once an episode ends env.agents is empty until reset()."""

    metadata = {"render_modes": [], "name": "pamdp_hfo_team", "is_parallelizable": True}

    def __init__(self, env_id: str = "hfo-1v1", agents: int = 2, **options):
        if isinstance(agents, bool) or not isinstance(agents, numbers.Integral):
            raise TypeError(f"agents must be an int, got {type(agents).__name__}")
        self._team = _pamdp.TeamEnv(env_id, int(agents), _options(env_id, options))
        self.possible_agents = [f"offense_{i}" for i in range(self._team.num_agents)]
        self.agents = []
        bound = self._team.observation_bound
        self._observation_space = spaces.Box(-bound, bound, (self._team.observation_size,), np.float32)
        self._action_space = spaces.action_space(self._team.actions)
        self.max_episode_steps = self._team.max_episode_steps
        self.render_mode = None

    @property
    def num_agents(self) -> int:
        return len(self.agents)

    @property
    def max_num_agents(self) -> int:
        return len(self.possible_agents)

    def _check_agent(self, agent):
        if agent not in self.possible_agents:
            raise KeyError(f"no agent {agent!r}: the agents are {self.possible_agents}")

    def observation_space(self, agent):
        self._check_agent(agent)
        return self._observation_space

    def action_space(self, agent):
        self._check_agent(agent)
        return self._action_space

    def reset(self, seed=None, options=None):
        if options is not None and not isinstance(options, dict):
            raise TypeError(f"reset options must be a dict or None, got {type(options).__name__}")
        if seed is not None:
            self._action_space.seed(seed)
        observations = self._team.reset(seed)
        self.agents = list(self.possible_agents)
        infos = {a: {"outcome": "IN_GAME", "status": 0} for a in self.agents}
        return dict(zip(self.agents, observations)), infos

    def step(self, actions):
        if not self.agents:
            raise RuntimeError("step() before reset() or after the episode ended; call reset() first")
        if not isinstance(actions, dict):
            raise TypeError(f"actions must be a dict keyed by agent name, got {type(actions).__name__}")
        missing = [a for a in self.agents if a not in actions]
        extra = [a for a in actions if a not in self.agents]
        if missing or extra:
            raise KeyError(f"actions must hold one action for each of {self.agents}"
                           + (f"; missing {missing}" if missing else "") + (f"; unknown {extra}" if extra else ""))
        observations, rewards, outcome, status, terminated, truncated = self._team.step(
            [actions[a] for a in self.agents])
        names = self.agents
        infos = {a: {"outcome": outcome, "status": status} for a in names}
        result = (dict(zip(names, observations)), dict(zip(names, rewards)), {a: terminated for a in names},
                  {a: truncated for a in names}, infos)
        if terminated or truncated:
            self.agents = []
        return result

    def render(self):
        return None

    def close(self):
        pass


def make_team(env_id: str = "hfo-1v1", agents: int = 2, **options) -> ParallelEnv:
    """N offense players in one embedded HFO game with PettingZoo's parallel API (ParallelEnv):
    make_team("hfo-1v1", agents=2) is 2v1 against agent2d's goalie, make_team("hfo-1v0",
    agents=2) 2v0; env options as make's keyword arguments."""
    return ParallelEnv(env_id, agents, **options)


def make_team_vec(env_id: str = "hfo-1v1", agents: int = 2, num_envs: int = 1, num_threads: int = 1,
                  autoreset_mode: str = "next_step", copy: bool = True, **options) -> TeamVectorEnv:
    """num_envs games of make_team(env_id, agents, **options) stepped in C++, every per-player
    array with an agent axis (see TeamVectorEnv): make_team_vec("hfo-1v1", agents=2,
    num_envs=64) is 64 games of 2v1 against agent2d's goalie."""
    return TeamVectorEnv(env_id, agents, num_envs, num_threads, autoreset_mode, copy, **options)


def make_vec(env_id: str = "hfo-1v0", num_envs: int = 1, num_threads: int = 1,
             autoreset_mode: str = "next_step", copy: bool = True, **options) -> VectorEnv:
    """num_envs envs of make(env_id, **options) stepped in C++ (see VectorEnv)."""
    return VectorEnv(env_id, num_envs, num_threads, autoreset_mode, copy, **options)


def load_policy(path, exploration: bool = False, epsilon=None, seed: int = 0, actor: str = "evaluated") -> Policy:
    """The actor of a checkpoint (models/*.ckpt, a run's checkpoint.ckpt or best.ckpt) as a
    callable policy; actor is "evaluated" (the copy its run's evaluations played, as `pamdp eval`
    picks), "online", "target" or "average"."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no checkpoint at '{path}' (trained agents: models/*.ckpt)")
    if epsilon is not None and (isinstance(epsilon, bool) or not isinstance(epsilon, numbers.Real)):
        raise TypeError(f"epsilon must be a number or None, got {type(epsilon).__name__}")
    if not isinstance(actor, str):
        raise TypeError(f"actor must be a str, got {type(actor).__name__}")
    return Policy(path, bool(exploration), None if epsilon is None else float(epsilon), seed, actor)


def evaluate(policy, env=None, episodes: int = 100, seed: int = 1) -> dict:
    """Plays `episodes` episodes as `pamdp eval` does (the first reset with `seed`, later ones
    continuing the env's stream) and returns its JSON keys: episodes, goal_rate,
    avg_steps_to_goal, avg_return, avg_steps, outcomes. `env` is an Env or an env id as make()
    takes it ("hfo-1v0", "platform", ...); it defaults to policy.make_env(), the checkpoint's
    own env with its settings."""
    if env is None:
        env = policy.make_env()
    elif isinstance(env, str):
        env = make(env)
    elif not hasattr(env, "success_status"):
        raise TypeError(f"env must be a pamdp Env, an env id such as 'hfo-1v0' or None, got {type(env).__name__}")
    policy_size = getattr(policy, "observation_size", None)
    if policy_size is not None and policy_size != env.observation_size:
        raise ValueError(f"the policy reads observations of {policy_size} floats (env '{policy.env_id}'), and env "
                         f"'{env.env_id}' gives {env.observation_size}: evaluate it on its own env (env=None)")
    success = env.success_status
    outcomes = {name: 0 for status, name in env.outcomes if status != 0}
    total_return, total_steps, goal_steps, goals = 0.0, 0, 0, 0
    for ep in range(episodes):
        obs, _ = env.reset(seed=seed) if ep == 0 else env.reset()
        steps, done = 0, False
        while not done:
            obs, reward, terminated, truncated, info = env.step(policy(obs))
            total_return += reward
            steps += 1
            done = terminated or truncated
        total_steps += steps
        outcomes[info["outcome"]] += 1
        if info["status"] == success:
            goals += 1
            goal_steps += steps
    return {
        "episodes": episodes,
        "goal_rate": goals / episodes if episodes else 0.0,
        "avg_steps_to_goal": goal_steps / goals if goals else 0.0,
        "avg_return": total_return / episodes if episodes else 0.0,
        "avg_steps": total_steps / episodes if episodes else 0.0,
        "outcomes": outcomes,
    }


try:  # Gymnasium is optional: when it is importable, gymnasium.make("pamdp/hfo-1v0") works too.
    import gymnasium as _gymnasium  # noqa: F401
except ImportError:
    pass
else:
    from . import gymnasium_env as _gymnasium_env

    _gymnasium_env.register()
