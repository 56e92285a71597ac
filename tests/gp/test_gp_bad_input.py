from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.gp import (
    GaussianRandomField,
    GPHyperparameters,
    fit_hyperparameters,
    grid_points,
    squared_exponential,
)

XY = np.array([[0.0, 0.0], [0.01, 0.02], [0.03, 0.01]])
Z = np.array([0.0, 0.001, 0.002])
GOOD = {"length_scale": 0.04, "signal_std": 0.01, "noise_std": 0.001}


def _field(**kw) -> GaussianRandomField:
    return GaussianRandomField(**{**GOOD, **kw})


@pytest.mark.parametrize("name", ["length_scale", "signal_std", "noise_std"])
@pytest.mark.parametrize("value", [0.0, -1.0, np.nan, np.inf, "a"])
def test_non_positive_or_non_finite_hyperparameter(name, value) -> None:
    with pytest.raises(InvalidArgumentError, match=f"`{name}`"):
        _field(**{name: value})


@pytest.mark.parametrize("value", [0.0, -0.01, np.nan])
def test_bad_inducing_spacing(value) -> None:
    with pytest.raises(InvalidArgumentError, match="`inducing_spacing`"):
        _field(inducing_spacing=value)


def test_unknown_method() -> None:
    with pytest.raises(InvalidArgumentError, match="`method`"):
        _field(method="fast")


def test_max_jitter_below_jitter() -> None:
    with pytest.raises(InvalidArgumentError, match="`max_jitter`"):
        _field(jitter=1e-6, max_jitter=1e-8)


@pytest.mark.parametrize(
    ("xy", "message"),
    [
        (np.array([[0.0, np.nan], [0.0, 0.0], [1.0, 1.0]]), "NaN or infinite"),
        (np.array([[0.0, np.inf], [0.0, 0.0], [1.0, 1.0]]), "NaN or infinite"),
        (np.zeros((3, 3)), r"got shape \(3, 3\)"),
        (np.zeros(6), r"got shape \(6,\)"),
        (np.zeros((0, 2)), "at least 1 rows"),
    ],
)
def test_bad_xy_in_fit(xy, message) -> None:
    with pytest.raises(InvalidArgumentError, match=f"`xy`.*{message}|{message}"):
        _field().fit(xy, Z[: max(len(xy), 1)])


def test_nan_z() -> None:
    with pytest.raises(InvalidArgumentError, match=r"`z`.*NaN"):
        _field().fit(XY, np.array([0.0, np.nan, 1.0]))


def test_length_mismatch() -> None:
    with pytest.raises(InvalidArgumentError, match="`z` must have one value per row of `xy`"):
        _field().fit(XY, Z[:2])


@pytest.mark.parametrize(
    "noise",
    [
        np.array([0.001, 0.0, 0.001]),
        np.array([0.001, 0.001]),
        np.array([0.001, np.nan, 0.001]),
        -1.0,
    ],
)
def test_bad_per_point_noise(noise) -> None:
    with pytest.raises(InvalidArgumentError, match="`noise_std`"):
        _field().fit(XY, Z, noise_std=noise)


@pytest.mark.parametrize("call", ["predict", "predict_grid"])
def test_predict_before_fit(call) -> None:
    field = _field()
    args = (XY,) if call == "predict" else (np.zeros(2), np.zeros(2))
    with pytest.raises(InvalidArgumentError, match="not fitted yet"):
        getattr(field, call)(*args)


def test_bad_prediction_points() -> None:
    field = _field().fit(XY, Z)
    with pytest.raises(InvalidArgumentError, match="`xy`"):
        field.predict(np.zeros((2, 3)))
    with pytest.raises(InvalidArgumentError, match="`xs`"):
        field.predict_grid(np.array([np.nan]), np.zeros(2))
    with pytest.raises(InvalidArgumentError, match="`ys`"):
        field.predict_grid(np.zeros(2), np.zeros((2, 2)))


def test_grid_with_too_many_inducing_points() -> None:
    xy = np.array([[0.0, 0.0], [10.0, 10.0]])
    with pytest.raises(InvalidArgumentError, match="increase `inducing_spacing`"):
        _field(method="grid").fit(xy, np.zeros(2))


def test_kernel_bad_input() -> None:
    with pytest.raises(InvalidArgumentError, match="`x1`"):
        squared_exponential(np.zeros((2, 3)), XY, length_scale=1.0, signal_std=1.0)
    with pytest.raises(InvalidArgumentError, match="`length_scale`"):
        squared_exponential(XY, XY, length_scale=0.0, signal_std=1.0)


def test_grid_points_bad_input() -> None:
    with pytest.raises(InvalidArgumentError, match="`xs`"):
        grid_points(np.zeros((2, 2)), np.zeros(2))
    with pytest.raises(InvalidArgumentError, match="`ys`"):
        grid_points(np.zeros(2), [])


def test_fit_hyperparameters_bad_input() -> None:
    rng = np.random.default_rng(0)
    with pytest.raises(InvalidArgumentError, match="`rng`"):
        fit_hyperparameters(XY, Z, rng=0)
    with pytest.raises(InvalidArgumentError, match="`z` is constant"):
        fit_hyperparameters(XY, np.ones(3), rng=rng)
    with pytest.raises(InvalidArgumentError, match="`bounds`"):
        fit_hyperparameters(XY, Z, rng=rng, bounds=[[0.0, 1.0], [1.0, 2.0], [1.0, 2.0]])
    with pytest.raises(InvalidArgumentError, match="`max_points`"):
        fit_hyperparameters(XY, Z, rng=rng, max_points=1)
    with pytest.raises(InvalidArgumentError, match="`init`"):
        fit_hyperparameters(XY, Z, rng=rng, init=(0.1, 0.1, 0.1))
    with pytest.raises(InvalidArgumentError, match=r"`init\.length_scale`"):
        fit_hyperparameters(XY, Z, rng=rng, init=GPHyperparameters(-1.0, 0.1, 0.1))
    with pytest.raises(InvalidArgumentError, match="`z` must have one value per row"):
        fit_hyperparameters(XY, Z[:2], rng=rng)
