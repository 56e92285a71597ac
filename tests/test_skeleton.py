"""The package imports, the CLI answers, the protocol types validate their input."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

import deformap
from deformap.cli import app
from deformap.cloud import PointCloud
from deformap.environment import Environment, PressObservation, TactileContact, Workspace
from deformap.errors import DeformapError, InvalidArgumentError

runner = CliRunner()


def test_version_and_help() -> None:
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0
    assert deformap.__version__ in result.output
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0
    assert "bench" in result.output


def test_workspace_grid_is_the_papers_half_centimetre_grid() -> None:
    ws = Workspace()
    xs, ys = ws.grid(0.005)
    assert (xs.size, ys.size) == (120, 80)
    assert xs[0] == pytest.approx(0.0025) and ys[-1] == pytest.approx(0.3975)
    assert ws.contains([[0.3, 0.2], [0.7, 0.2]]).tolist() == [True, False]


def test_workspace_refuses_inverted_corners() -> None:
    with pytest.raises(InvalidArgumentError, match="`upper` must exceed `lower`"):
        Workspace(lower=(0.0, 0.5), upper=(0.6, 0.4))


def test_tactile_contact_geometry() -> None:
    c = TactileContact(tip_center=[0.1, 0.2, 0.06], force=[0, 0, -0.5], tip_radius_m=0.01)
    assert c.force_n == pytest.approx(0.5)
    np.testing.assert_allclose(c.contact_point, [0.1, 0.2, 0.05])
    with pytest.raises(InvalidArgumentError, match="`force`"):
        TactileContact(tip_center=[0, 0, 0], force=[0, 0, 0], tip_radius_m=0.01)
    with pytest.raises(InvalidArgumentError, match="`tip_radius_m` must be > 0"):
        TactileContact(tip_center=[0, 0, 0], force=[0, 0, -1], tip_radius_m=-0.01)


def test_press_observation_validates_robot_points() -> None:
    contact = TactileContact(tip_center=[0, 0, 0.06], force=[0, 0, -0.5], tip_radius_m=0.01)
    cloud = PointCloud(np.zeros((3, 3)))
    with pytest.raises(InvalidArgumentError, match="`robot_points` must have at least 4 rows"):
        PressObservation(cloud=cloud, contact=contact, robot_points=np.zeros((2, 3)),
                         target_xy=[0, 0], force_n=0.5)


def test_a_minimal_class_satisfies_the_protocol() -> None:
    class Tiny:
        workspace = Workspace()

        def observe(self) -> PointCloud:
            return PointCloud(np.zeros((1, 3)))

        def press(self, target_xy, force_n):  # type: ignore[no-untyped-def]
            raise NotImplementedError

        def release(self) -> None:
            return None

    assert isinstance(Tiny(), Environment)


def test_errors_are_one_family() -> None:
    assert issubclass(InvalidArgumentError, DeformapError)
    assert issubclass(InvalidArgumentError, ValueError)
