"""The simulated world: scenario + foam physics + depth camera + probe, as an ``Environment``.

``WorldConfig.physics`` picks how the foam answers a press; each physics displaces the same
hexahedral mesh, which the camera sees. The force–travel record and each frame's colour draw their
noise from streams of their own, so the depth's and the press's draws are those of a world without
them. Ground truth is ``-1`` (labels) or ``inf`` (hardness, modulus) on the bare table.
"""

from __future__ import annotations

import logging
from dataclasses import replace
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from deformap._validation import (
    SettingError,
    check_positive,
    check_vector,
)
from deformap.cloud import PointCloud
from deformap.environment import (
    MIN_FORCE_RISE_N,
    ForceTravel,
    PressObservation,
    TactileContact,
    Workspace,
)
from deformap.errors import EnvironmentStateError, InvalidArgumentError
from deformap.world._camera import DepthCamera, Frame
from deformap.world._config import WorldConfig, check_world_budget
from deformap.world._foam import Dent, FoamModel
from deformap.world._force_travel import (
    force_levels,
    press_schedule,
    sensor_depths,
    simulated_force_travel,
    with_phases,
)
from deformap.world._looks import HAND, STICK, TABLE, TIP, SceneLooks
from deformap.world._plastic import PlasticPress, plastic_press
from deformap.world._scenario import BARE_TABLE, Scenario
from deformap.world._stiffening import StiffeningFoam
from deformap.world._stiffening_fem import StiffeningFem
from deformap.world._truth import WorldTruth
from deformap.world._viscoelastic import PressHistory, press_history, recovered

__all__ = ["MIN_RECORD_FORCE_N", "SimulatedWorld"]

log = logging.getLogger(__name__)

_UP = np.array([0.0, 0.0, 1.0])

#: The world records force against travel only for presses of at least this force [N]: the
#: record must rise by more than ``MIN_FORCE_RISE_N`` from contact, with room for the force
#: sensor's noise (the exploration presses with 0.3 N or more).
MIN_RECORD_FORCE_N = 0.1 + 5 * MIN_FORCE_RISE_N


class SimulatedWorld(WorldTruth):
    """A scenario on a table, seen by a depth camera and pressed by a force-controlled probe.

    One number is drawn from ``rng`` at construction; each event (the n-th observation at rest; a
    press by its target and force) then draws its noise from a stream keyed by that number and the
    event, so a resumed run sees the noise the uninterrupted run saw.
    """

    def __init__(self, scenario: Scenario, *, config: WorldConfig | None = None,
                 rng: np.random.Generator) -> None:
        if not isinstance(scenario, Scenario):
            raise InvalidArgumentError(f"`scenario` must be a Scenario; got {type(scenario)}")
        if not isinstance(rng, np.random.Generator):
            raise InvalidArgumentError(f"`rng` must be a numpy.random.Generator; got {type(rng)}")
        self.scenario = scenario
        self.config = config or WorldConfig()
        check_world_budget(self.config, scenario)
        special = [b.name for b in scenario.blocks if b.viscoelastic is not None
                   or b.anisotropy is not None or b.plastic is not None]
        if special and self.config.physics != "linear-fem":
            raise SettingError(
                "physics", f"must be 'linear-fem' for the blocks of other materials "
                f"{special}; got {self.config.physics!r}")
        self._noise_key = int(rng.integers(2**62))
        self._n_observed = 0
        c = self.config
        mesh: dict[str, Any] = dict(element_size_m=c.element_size_m, top_layer_m=c.top_layer_m,
                                    layer_growth=c.layer_growth, poisson_ratio=c.poisson_ratio)
        self.foam: FoamModel | StiffeningFoam  # StiffeningFem is a FoamModel
        if c.physics == "linear-fem":
            self.foam = FoamModel(scenario, **mesh)
        else:
            physics = StiffeningFem if c.physics == "stiffening-fem" else StiffeningFoam
            self.foam = physics(scenario, **mesh, densification_strain=c.densification_strain,
                                stiffening_exponent=c.stiffening_exponent)
        camera = c.camera if c.noise else replace(c.camera, noise=False)
        self.camera = DepthCamera(camera, scenario.workspace.center)
        self._force_noise_n = c.force_noise_n if c.noise else 0.0
        self._faces, self._owner = self._surface_triangles()
        self._table = self._table_mesh()
        self.looks = SceneLooks(scenario, self.config)
        self._pressed: PressObservation | None = None
        self._displacement = self.foam.zero_displacement()
        self._history: tuple[tuple[float, float, float], PressHistory | PlasticPress] | None = None
        self._left: PressHistory | PlasticPress | None = None  # the last press released
        self._released = False

    # ---- Environment protocol ----
    @property
    def workspace(self) -> Workspace:
        return self.scenario.workspace

    def observe(self) -> PointCloud:
        """One depth frame of the scene as it is now, world frame."""
        if self._pressed is None:
            key: tuple[int, ...] = (0, self._n_observed)
            self._n_observed += 1
            return self._capture(self._displacement, None, self._event_rng(*key), key)
        p = self._pressed
        key = self._press_key(p.target_xy, p.force_n, 1)
        return self._capture(self._displacement, p.contact, self._event_rng(*key), key)

    def rgb_image(self) -> NDArray[np.float64]:
        """``(height, width, 3)`` sRGB in ``[0, 1]`` of the scene as the camera sees it now (noise
        from a stream of its own); NaN where a pixel has no return."""
        contact = None if self._pressed is None else self._pressed.contact
        frame = self.camera.capture(self.scene_mesh(self._displacement, contact),
                                    self._event_rng(5))
        c = self.camera.config
        image = np.full((c.height * c.width, 3), np.nan)
        image[frame.pixel] = self._colors(frame, contact is not None, self._event_rng(6))
        return image.reshape(c.height, c.width, 3)

    def press(self, target_xy: Any, force_n: float) -> PressObservation:
        """Press at ``target_xy`` with ``force_n`` newtons along the surface normal and hold."""
        target = check_vector("target_xy", target_xy, 2, what="metres")
        force = check_positive("force_n", force_n)
        if not self.workspace.contains(target)[0]:
            raise InvalidArgumentError(
                f"`target_xy` must lie in the workspace {self.workspace.lower}–"
                f"{self.workspace.upper}; got {tuple(target)}")
        if self._pressed is not None:
            raise EnvironmentStateError(
                "the probe is still pressing at "
                f"{tuple(np.round(self._pressed.target_xy, 4))}; call release() first")
        dent = self.dent(target, force)
        tip_center = self._tip_center(target, dent)
        key = self._press_key(target, force, 0)
        rng = self._event_rng(*key)
        noise = rng.normal(0.0, 1.0, size=3) * self._force_noise_n
        contact = TactileContact(tip_center=tip_center, force=-_UP * force + noise,
                                 tip_radius_m=self.config.tip_radius_m)
        cloud = self._capture(dent.displacement, contact, rng, key)
        self._displacement = dent.displacement
        self._pressed = PressObservation(
            cloud=cloud, contact=contact, target_xy=target, force_n=force,
            robot_points=self.config.probe.robot_points(tip_center, _UP),
            force_travel=self.force_travel(target, force, dent),
            released=self._released_cloud(target, force) if self.config.unload else None)
        return self._pressed

    def release(self) -> None:
        """Lift the probe; the foam springs back (an elastic block at once; a viscoelastic one
        over time, :meth:`released_displacement`, and is at rest again by the next press)."""
        p = self._pressed
        self._left = None if p is None else self._material_press(p.target_xy, p.force_n)
        self._released = p is not None or self._released
        self._pressed = None
        self._displacement = self.foam.zero_displacement()

    def released_displacement(self, after_s: float = 0.0) -> NDArray[np.float64]:
        """``(n_nodes, 3)`` displacement of the foam ``after_s`` seconds after the tip of the last
        released press left it: 0 for an elastic block; a viscoelastic one recovers in time
        (:mod:`deformap.world._viscoelastic`, the tip leaving at the end of the protocol); a
        plastic one keeps its residual dent (:mod:`deformap.world._plastic`).

        Raises
        ------
        EnvironmentStateError
            No press has been released yet, or the probe is pressing.
        """
        after = check_positive("after_s", after_s, allow_zero=True)
        if self._pressed is not None:
            raise EnvironmentStateError("the probe is still pressing: call release() first")
        if not self._released:
            raise EnvironmentStateError("no press has been released yet: press(), release(), then "
                                        "ask for the surface after release")
        return self._left_displacement(self._left, after)

    def _left_displacement(self, left: PressHistory | PlasticPress | None, after_s: float
                           ) -> NDArray[np.float64]:
        if isinstance(left, PlasticPress):
            return left.residual.copy()
        return self.foam.zero_displacement() if left is None else recovered(left.state, after_s)

    def _released_cloud(self, target: NDArray[np.float64], force: float) -> PointCloud:
        """The frame the camera takes as the tip leaves at the end of the protocol's unloading
        (the press's :attr:`PressObservation.released`)."""
        u = self._left_displacement(self._material_press(target, force), 0.0)
        key = self._press_key(target, force, 5)
        return self._capture(u, None, self._event_rng(*key), key)

    def observe_released(self, after_s: float = 0.0) -> PointCloud:
        """One depth frame ``after_s`` seconds after the tip of the last released press left
        (:meth:`released_displacement`), world frame, noise from a stream keyed by the time."""
        u = self.released_displacement(after_s)
        key = (4, round(after_s * 1e6), self._n_observed)
        self._n_observed += 1
        return self._capture(u, None, self._event_rng(*key), key)

    # ---- physics and ground truth ----
    @property
    def n_dofs(self) -> int:
        return self.foam.n_dofs

    @property
    def is_pressing(self) -> bool:
        return self._pressed is not None

    def dent(self, target_xy: Any, force_n: float) -> Dent:
        """The foam's response to a press, without noise or touching the world's state.

        Raises
        ------
        InvalidArgumentError
            When the tip would sink as deep as the block is thick (crushed onto the table).
        """
        target = check_vector("target_xy", target_xy, 2, what="metres")
        force = check_positive("force_n", force_n)
        history = self._material_press(target, force)
        if history is not None:
            dent = history.held
        else:
            self.foam.forget()  # a press is solved the same whatever was pressed before
            dent = self.foam.dent(target, force, tip_radius_m=self.config.tip_radius_m)
        label = int(self.scenario.labels(target[:1], target[1:])[0, 0])
        if label >= 0 and dent.depth_m >= self.scenario.blocks[label].thickness_m:
            block = self.scenario.blocks[label]
            raise InvalidArgumentError(
                f"`force_n` of {force:g} N would sink the tip {dent.depth_m:.3g} m into "
                f"{block.name!r}, which is {block.thickness_m:g} m thick: the foam would be "
                "crushed onto the table, where the world's physics does not hold; press with "
                "less force")
        return dent

    def force_travel(self, target_xy: Any, force_n: float, dent: Dent | None = None, *,
                     exact: bool = False) -> ForceTravel | None:
        """The force–travel record of the press at ``target_xy`` with ``force_n`` newtons (with
        ``exact``, without noise: the world's true indentations, for evaluation).

        One press solve per load level (:mod:`deformap.world._force_travel`), ``dent`` (the
        press's own solve) the last; the sensors read the ramp between the levels at
        ``sample_rate_hz``. None under :data:`MIN_RECORD_FORCE_N`, and, with a warning,
        where the solved indentations make no record (by a seam the FEM's indentation can fall
        from one level to the next): that press is read by the camera alone.
        """
        target = check_vector("target_xy", target_xy, 2, what="metres")
        force = check_positive("force_n", force_n)
        if force < MIN_RECORD_FORCE_N:
            return None
        c = self.config
        final = dent if dent is not None else self.dent(target, force)
        levels = force_levels(c.contact_threshold_n, force, c.force_travel_levels)
        schedule = press_schedule(levels, rate_n_per_s=c.ramp_rate_n_per_s, hold_s=c.hold_s,
                                  unload=c.unload)
        sensor = press_schedule(levels, rate_n_per_s=c.ramp_rate_n_per_s, hold_s=c.hold_s,
                                unload=c.unload, sample_rate_hz=c.sample_rate_hz)
        history = self._material_press(target, force)
        depths = history.ramp if history is not None else self._level_depths(target, levels,
                                                                               final)
        on = 1.0 if c.noise and not exact else 0.0
        noise = dict(encoder_noise_m=c.encoder_noise_m * on, force_noise_n=c.force_travel_noise_n
                     * on, force_noise_rel=c.force_travel_noise_rel * on)
        key = self._press_key(target, force, 2)
        try:
            ramp, hold, unloading = sensor_depths(schedule, sensor, depths, history)
            record = simulated_force_travel(ramp, sensor.levels, self._event_rng(*key), **noise)
            if not sensor.has_phases:
                return record
            # the encoder's reading at first contact: the ramp stream's first draw
            zero = ramp[0] + self._event_rng(*key).normal(0.0, 1.0, size=ramp.size)[0] * (
                noise["encoder_noise_m"])
            return with_phases(record, sensor, zero, hold, unloading,
                               self._event_rng(*self._press_key(target, force, 4)), **noise)
        except InvalidArgumentError as err:
            log.warning("no force–travel record for the press at %s with %g N: the solved "
                        "indentations %s mm are not a press's (%s)", tuple(np.round(target, 4)),
                        force, np.round(depths * 1e3, 2).tolist(), err)
            return None

    def _material_press(self, target: NDArray[np.float64], force: float
                        ) -> PressHistory | PlasticPress | None:
        """The press solved through its load history on a viscoelastic or plastic block (None on
        any other ground), its samples on the protocol's schedule; the last one is kept."""
        index = self.foam.block_at(target)
        block = None if index is None else self.scenario.blocks[index]
        if block is None or (block.viscoelastic is None and block.plastic is None):
            return None
        key = (float(target[0]), float(target[1]), force)
        if self._history is not None and self._history[0] == key:
            return self._history[1]
        c = self.config
        levels = force_levels(c.contact_threshold_n, force, c.force_travel_levels)
        plan = press_schedule(levels, rate_n_per_s=c.ramp_rate_n_per_s, hold_s=c.hold_s,
                              unload=c.unload)
        assert isinstance(self.foam, FoamModel) and index is not None
        history: PressHistory | PlasticPress
        if block.plastic is not None:
            history = plastic_press(self.foam, index, block.plastic, target, levels=levels,
                                    unload_forces=plan.unload_forces,
                                    tip_radius_m=c.tip_radius_m)
        else:
            assert block.viscoelastic is not None
            history = press_history(
                self.foam, block.viscoelastic, target,
                times=np.concatenate([plan.times, plan.hold_times, plan.unload_times]),
                forces=np.concatenate([levels, np.full(plan.hold_times.size, force),
                                       plan.unload_forces]),
                n_ramp=levels.size, n_hold=plan.hold_times.size, tip_radius_m=c.tip_radius_m)
        self._history = (key, history)
        return history

    def _level_depths(self, target: NDArray[np.float64], levels: NDArray[np.float64],
                      final: Dent) -> NDArray[np.float64]:
        """The tip's indentation at each force of ``levels`` (increasing, ending at ``final``'s),
        solved from the top down, each level's patch started from the level above's scaled as
        Hertz's ``a ∝ F^(1/3)`` and bounded by its radius."""
        depths = np.empty(levels.size)
        depths[-1], patch = final.depth_m, final
        for k in range(levels.size - 2, -1, -1):
            start = patch.contact_radius_m * (levels[k] / levels[k + 1]) ** (1.0 / 3.0)
            patch = self.foam.dent(target, float(levels[k]), tip_radius_m=self.config.tip_radius_m,
                                   initial_radius_m=start, max_radius_m=patch.contact_radius_m)
            depths[k] = patch.depth_m
        return depths

    # ---- internals ----
    def _tip_center(self, target: NDArray[np.float64], dent: Dent) -> NDArray[np.float64]:
        index = int(self.scenario.labels(target[:1], target[1:])[0, 0])
        top = 0.0 if index == BARE_TABLE else self.regions[index].thickness_m
        return np.array([target[0], target[1], top - dent.depth_m + self.config.tip_radius_m])

    def _surface_triangles(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """The blocks' surface triangles and the block that owns each."""
        tris, owner = [], []
        for k, (grid, off) in enumerate(zip(self.foam.grids, self.foam.offsets, strict=True)):
            q = grid.surface_quads() + off
            tris.append(np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]))
            owner.append(np.full(2 * len(q), k, dtype=np.int64))
        return np.concatenate(tris), np.concatenate(owner)

    def _table_mesh(self) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        m = self.config.table_margin_m
        (x0, y0), (x1, y1) = self.workspace.lower, self.workspace.upper
        verts = np.array([[x0 - m, y0 - m, 0.0], [x1 + m, y0 - m, 0.0],
                          [x1 + m, y1 + m, 0.0], [x0 - m, y1 + m, 0.0]])
        return verts, np.array([[0, 1, 2], [0, 2, 3]])

    def scene_mesh(self, displacement: NDArray[np.float64],
                   contact: TactileContact | None = None) -> trimesh.Trimesh:
        """Triangles of the table, the (deformed) blocks and, with a contact, the probe."""
        verts = self.foam.rest_nodes + displacement
        table_v, table_f = self._table
        parts_v, parts_f = [verts, table_v], [self._faces, table_f + len(verts)]
        if contact is not None:
            probe = self.config.probe.mesh(contact.tip_center, _UP)
            parts_f.append(np.asarray(probe.faces) + len(verts) + len(table_v))
            parts_v.append(np.asarray(probe.vertices))
        return trimesh.Trimesh(np.concatenate(parts_v), np.concatenate(parts_f), process=False)

    def _event_rng(self, *key: int) -> np.random.Generator:
        return np.random.default_rng([self._noise_key, *key])

    def _press_key(self, target: NDArray[np.float64], force: float, view: int
                   ) -> tuple[int, ...]:
        # Micrometres and micronewtons, shifted to be non-negative: SeedSequence takes naturals.
        x, y = (round(v * 1e6) + 2**40 for v in target)
        return 1, x, y, round(force * 1e6), view

    def _capture(self, displacement: NDArray[np.float64], contact: TactileContact | None,
                 rng: np.random.Generator, key: tuple[int, ...]) -> PointCloud:
        frame = self.camera.capture(self.scene_mesh(displacement, contact), rng)
        # the colour's own stream: a key no depth or force stream has (those start with 0 or 1)
        colors = self._colors(frame, contact is not None, self._event_rng(3, *key))
        return PointCloud(points=frame.points, colors=colors, frame="world")

    def _colors(self, frame: Frame, probe: bool, rng: np.random.Generator
                ) -> NDArray[np.float64]:
        owner = [self._owner, np.full(len(self._table[1]), TABLE)]
        if probe:
            owner += [np.full(n, part) for n, part in
                      zip(self.config.probe.part_faces(), (TIP, STICK, HAND), strict=True)]
        hit_owner = np.concatenate(owner)[frame.triangle]
        light = self.looks.radiance(hit_owner, frame.hit, frame.normal, self.camera.origin)
        return self.camera.sensor_colors(light, frame.pixel, rng)
