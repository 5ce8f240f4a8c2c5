"""pamdp's envs for Gymnasium (imported only when gymnasium is importable):
gymnasium.make("pamdp/hfo-1v0"), gymnasium.make("pamdp/hfo-1v1", noise=False), ..."""

from __future__ import annotations

import gymnasium

from . import _pamdp, make, spaces


class GymnasiumEnv(gymnasium.Env):
    """A pamdp env as a gymnasium.Env, with gymnasium.spaces for its spaces."""

    metadata = {"render_modes": ["ansi"]}

    def __init__(self, env_id: str = "hfo-1v0", render_mode=None, **options):
        self._env = make(env_id, render_mode=render_mode, **options)
        self.render_mode = render_mode
        self.observation_space = spaces.to_gymnasium(self._env.observation_space)
        self.action_space = spaces.to_gymnasium(self._env.action_space)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return self._env.reset(seed=seed, options=options)

    def step(self, action):
        return self._env.step(action)

    def render(self):
        """The field as text with render_mode "ansi"; None without a render mode."""
        return self._env.render()


def register() -> None:
    """Registers every env id as pamdp/<id>."""
    for env_id, _description in _pamdp.env_ids():
        name = f"pamdp/{env_id}"
        if name not in gymnasium.registry:
            gymnasium.register(id=name, entry_point=GymnasiumEnv, kwargs={"env_id": env_id})
