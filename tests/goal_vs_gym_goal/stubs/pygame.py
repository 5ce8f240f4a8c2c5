# Stand-in: gym-goal imports pygame only to render.
