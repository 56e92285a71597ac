"""GaussianRandomField speaks scikit-learn's parameter API: get_params, set_params, clone."""

from __future__ import annotations

import numpy as np
import pytest

from deformap.errors import InvalidArgumentError
from deformap.gp import GaussianRandomField

PARAMS = {"length_scale": 0.05, "signal_std": 0.01, "noise_std": 1e-3, "method": "exact",
          "inducing_spacing": 0.02, "jitter": 1e-9, "max_jitter": 1e-5}  # fmt: skip


def _data() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    xy = rng.uniform(0.0, 0.2, size=(30, 2))
    return xy, 0.01 * np.sin(20 * xy[:, 0])


def test_get_params_returns_the_constructors_parameters() -> None:
    field = GaussianRandomField(**PARAMS)
    assert field.get_params() == PARAMS
    assert field.get_params(deep=False) == PARAMS


def test_sklearn_clone_gives_an_unfitted_copy_with_the_same_parameters() -> None:
    base = pytest.importorskip("sklearn.base")
    field = GaussianRandomField(**PARAMS).fit(*_data())
    copy = base.clone(field)
    assert type(copy) is GaussianRandomField and copy is not field
    assert copy.get_params() == PARAMS
    assert not hasattr(copy, "xy_")
    with pytest.raises(InvalidArgumentError, match="not fitted"):
        copy.predict(np.zeros((1, 2)))
    # the copy fits to the same predictions
    xy, z = _data()
    assert np.allclose(copy.fit(xy, z).predict(xy[:5]), field.predict(xy[:5]))


def test_set_params_checks_like_the_constructor_and_unfits() -> None:
    xy, z = _data()
    field = GaussianRandomField(**PARAMS).fit(xy, z)
    assert field.set_params(length_scale=0.1, method="grid") is field
    assert field.get_params() == {**PARAMS, "length_scale": 0.1, "method": "grid"}
    assert not hasattr(field, "xy_") and not hasattr(field, "mean_")
    with pytest.raises(InvalidArgumentError, match="not fitted"):
        field.predict(xy[:1])
    with pytest.raises(InvalidArgumentError, match="`length_scale`"):
        field.set_params(length_scale=-1.0, signal_std=5.0)
    assert field.get_params()["signal_std"] == PARAMS["signal_std"]  # all or nothing
    with pytest.raises(InvalidArgumentError, match=r"set_params.*\['lengthscale'\]"):
        field.set_params(lengthscale=0.1)


def test_sklearn_grid_search_style_parameter_sweep() -> None:
    # what a sklearn utility does with the API: clone, set_params, fit
    base = pytest.importorskip("sklearn.base")
    xy, z = _data()
    scores = {}
    for length in (0.02, 0.05, 0.1):
        model = base.clone(GaussianRandomField(**PARAMS)).set_params(length_scale=length)
        scores[length] = model.fit(xy, z).log_marginal_likelihood_
    assert len(set(scores.values())) == 3
