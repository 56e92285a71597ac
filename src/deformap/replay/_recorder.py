"""An ``Environment`` wrapper that keeps what the wrapped environment returned, for a session."""

from __future__ import annotations

from typing import Any

from deformap.cloud import PointCloud
from deformap.environment import Environment, PressObservation, Workspace
from deformap.errors import EnvironmentStateError, InvalidArgumentError

__all__ = ["RecordingEnvironment"]


class RecordingEnvironment:
    """Pass every call through to ``env`` and keep each ``observe()`` and ``press()`` result,
    ready for :func:`~deformap.replay.write_session`."""

    def __init__(self, env: Environment) -> None:
        if not isinstance(env, Environment):
            raise InvalidArgumentError(
                f"`env` must implement the Environment protocol; got {type(env).__name__}")
        self._env = env
        self.observations: list[PointCloud] = []
        self.presses: list[PressObservation] = []

    @property
    def workspace(self) -> Workspace:
        return self._env.workspace

    @property
    def observation(self) -> PointCloud:
        """The first observation (the one the mapper is initialised with)."""
        if not self.observations:
            raise EnvironmentStateError("nothing recorded yet: `observe()` was never called")
        return self.observations[0]

    def observe(self) -> PointCloud:
        cloud = self._env.observe()
        self.observations.append(cloud)
        return cloud

    def press(self, target_xy: Any, force_n: float) -> PressObservation:
        obs = self._env.press(target_xy, force_n)
        self.presses.append(obs)
        return obs

    def release(self) -> None:
        self._env.release()
