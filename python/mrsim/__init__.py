"""mrsim from Python: multi-robot navigation environments and planners.

- :class:`mrsim.gym.NavEnv`: one learning robot among robots driven by
  mrsim's built-in planners (Gymnasium).
- :class:`mrsim.pettingzoo.ParallelNavEnv`: every robot a learning agent
  (PettingZoo parallel API).
- :class:`mrsim.Sim`: the stepping engine both are built on (numpy in and
  out).
"""

from importlib import resources as _resources

from ._mrsim import Sim

__all__ = ["Sim", "scenario_path"]


def scenario_path(name: str = "circle-16") -> str:
    """The path of a scenario shipped with the package (``circle-16``)."""
    return str(_resources.files(__package__).joinpath("scenarios", f"{name}.toml"))
