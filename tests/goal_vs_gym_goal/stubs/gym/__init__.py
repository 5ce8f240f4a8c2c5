"""Stand-in for the parts of gym that gym-goal's GoalEnv touches (base class, spaces, errors)."""


class Env:
    pass


class _Space:
    def __init__(self, *args, **kwargs):
        pass


class spaces:
    Tuple = _Space
    Box = _Space
    Discrete = _Space


class error:
    class InvalidAction(Exception):
        pass
