"""A user's robot, guarded: each call to it (the factory, ``workspace``, ``observe``, ``press``,
``release``) runs in a worker thread under a time limit, and whatever goes wrong in it (an
exception, a ``SystemExit`` or ``KeyboardInterrupt``, a call that does not return, a result of
the wrong type, a press held away from its target) becomes one :class:`RobotFault`, naming the
environment, the call and what happened, raised in the run's own thread.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from deformap._validation import check_settings, setting
from deformap.cloud import PointCloud
from deformap.environment import Environment, PressObservation, Workspace
from deformap.errors import ConfigError, DeformapError

__all__ = ["GuardedEnvironment", "RobotConfig", "RobotFault"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, kw_only=True)
class RobotConfig:
    """How ``explore --environment`` guards a user's robot (simulated runs do not use it).

    Parameters
    ----------
    call_timeout_s : float
        Longest one call to the robot (factory, observe, press, release) may take, seconds.
        A press approaches, ramps and holds in tens of seconds; two minutes means it is stuck.
    target_tolerance_m : float or None
        Farthest a press's tip centre may lie from its target in x–y, metres; None: the tip's radius.
        Beyond the tip's radius the tip no longer covers the target.
    off_target : {"refuse", "warn"}
        What a press beyond the tolerance does: end the run, or be kept with a warning.
    """

    call_timeout_s: float = setting(120.0, gt=0.0)
    target_tolerance_m: float | None = setting(None, gt=0.0)
    off_target: Literal["refuse", "warn"] = "refuse"

    def __post_init__(self) -> None:
        check_settings(self)


class RobotFault(DeformapError):
    """The robot failed: ``error`` is what its code raised (None: it hung or returned something
    wrong); ``exit_code`` is 130 for a ``KeyboardInterrupt``, else 2."""

    def __init__(self, message: str, error: BaseException | None = None) -> None:
        super().__init__(message)
        self.error = error
        self.exit_code = 130 if isinstance(error, KeyboardInterrupt) else 2


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


class GuardedEnvironment:
    """The ``Environment`` the loop drives: ``spec``'s calls under ``config`` (module docstring).

    :meth:`build` calls the factory guarded; ``workspace`` is read once, there.
    """

    def __init__(self, spec: str, config: RobotConfig) -> None:
        self.spec, self.config = spec, config
        self._env: Any = None
        self._workspace: Workspace | None = None

    def call(self, what: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        """``fn(*args, **kwargs)`` in a daemon thread, waited for at most ``call_timeout_s``; a
        call that does not return is left running (nothing more is asked of the robot)."""
        box: dict[str, Any] = {}

        def work() -> None:
            try:
                box["value"] = fn(*args, **kwargs)
            except BaseException as exc:  # the robot's code: every way out is reported here
                box["error"] = exc

        worker = threading.Thread(target=work, name=f"deformap robot {what}", daemon=True)
        try:
            worker.start()
            worker.join(self.config.call_timeout_s)
        except KeyboardInterrupt as exc:  # Ctrl-C while the robot works: the same clean stop
            raise RobotFault(f"--environment {self.spec}: interrupted during {what}", exc) from None
        if worker.is_alive():
            raise RobotFault(f"--environment {self.spec}: {what} did not return within "
                             f"{self.config.call_timeout_s:g} s (robot.call_timeout_s); "
                             "stopped waiting for it")
        error = box.get("error")
        if error is None:
            return box["value"]
        if isinstance(error, SystemExit):
            text = f"called sys.exit({error.code!r})"
        else:
            text = f"raised {type(error).__name__}" + (f": {_one_line(error)}" if str(error) else "")
        raise RobotFault(f"--environment {self.spec}: {what} {text}", error)

    def build(self, factory: Callable[..., Any], args: dict[str, Any]) -> None:
        """Call ``factory(**args)`` and read its ``workspace`` (:class:`RobotFault`); arguments
        it does not take (a ``TypeError``) or a result that is not an ``Environment`` are a
        :class:`ConfigError`."""
        name = self.spec.partition(":")[2]
        try:
            self._env = self.call(f"{name}()", factory, **args)
        except RobotFault as exc:
            if not isinstance(exc.error, TypeError):
                raise
            raise ConfigError(f"--environment {self.spec!r}: the --env-arg values do not fit "
                              f"{name}(): {exc.error}") from None
        if not isinstance(self._env, Environment):
            raise ConfigError(f"--environment {self.spec!r} must return an Environment "
                              "(workspace, observe, press, release); got "
                              f"{type(self._env).__name__}")
        workspace = self.call("workspace", getattr, self._env, "workspace")
        self._workspace = self._checked("workspace", workspace, Workspace)

    def _checked(self, what: str, value: Any, kind: type) -> Any:
        if not isinstance(value, kind):
            raise RobotFault(f"--environment {self.spec}: {what} must return a {kind.__name__}; "
                             f"got {type(value).__name__}")
        return value

    @property
    def workspace(self) -> Workspace:
        assert self._workspace is not None, "build() first"
        return self._workspace

    def observe(self) -> PointCloud:
        cloud = self.call("observe()", self._env.observe)
        return self._checked("observe()", cloud, PointCloud)

    def press(self, target_xy: Any, force_n: float) -> PressObservation:
        target = np.asarray(target_xy, dtype=float)
        what = f"press(({target[0]:.4f}, {target[1]:.4f}) m, {force_n:g} N)"
        obs = self._checked(what, self.call(what, self._env.press, target_xy, force_n),
                            PressObservation)  # fmt: skip
        tip = obs.contact.tip_center[:2]
        off = float(np.hypot(*(tip - target)))
        tolerance = self.config.target_tolerance_m or obs.contact.tip_radius_m
        if off > tolerance:
            message = (f"--environment {self.spec}: {what} held the tip at ({tip[0]:.4f}, "
                       f"{tip[1]:.4f}) m, {off * 1e3:.1f} mm from the target (tolerance "
                       f"{tolerance * 1e3:.1f} mm, robot.target_tolerance_m)")
            if self.config.off_target == "refuse":
                self.release()
                raise RobotFault(message)
            logger.warning("%s; kept (robot.off_target: warn)", message)
        return obs

    def release(self) -> None:
        self.call("release()", self._env.release)
