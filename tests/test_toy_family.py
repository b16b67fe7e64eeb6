"""A new family plugs in with the core alone, touching nothing outside models/ and the
registry: a two-joint arm in the plane whose second joint slides (R-P).

The toy arm puts its tool at ``b + (L + dL + d) (cos(q1 + dq1), sin(q1 + dq1))``
for a base offset ``b = (bx, by)`` (mm), a zero offset ``dq1`` (rad) of the turning
joint and an error ``dL`` (mm) of the slide's start ``L``; ``d = q2`` is the slide's
reading (mm).  It subclasses :class:`~armcal.models.core.CoreModel` and supplies
only the core (names, units, limits, noise, points and their Jacobian); it is
registered as a family with its calibration-file codec, and identification,
validation, Monte Carlo and the calibration file then work for it.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pytest

import armcal
from armcal.families import Family, register, unregister
from armcal.files import calibration_document, read_calibration, to_json
from armcal.models import Conditions
from armcal.models.core import CoreModel
from armcal.noise import NoiseModel

SLIDE_START_MM = 300.0
TRUTH = np.array([12.0, -7.0, 0.8, np.radians(0.4)])  # bx, by, dL (mm), dq1 (rad)


@dataclass(frozen=True, eq=False)
class SlidingArm(CoreModel):
    """The toy R-P arm: the core of a fit model, nothing more (module notes)."""

    name: str = "slider"
    fixed: tuple[str, ...] = ()
    noise: NoiseModel | None = None

    @property
    def family(self) -> str:
        return "toy-slider"

    @property
    def param_names(self) -> tuple[str, ...]:
        return ("bx", "by", "dL", "dq1")

    @property
    def param_units(self) -> tuple[str, ...]:
        return ("mm", "mm", "mm", "rad")

    @property
    def joint_limits(self) -> np.ndarray:
        return np.array([[-np.pi / 2, np.pi / 2], [0.0, 400.0]])  # rad, then mm

    @property
    def joint_kinds(self) -> tuple[str, ...]:
        return ("R", "P")

    @property
    def point_dim(self) -> int:
        return 2

    def with_noise(self, noise: NoiseModel | None) -> SlidingArm:
        return replace(self, noise=noise)

    def with_fixed(self, fixed: Sequence[str]) -> SlidingArm:
        return replace(self, fixed=tuple(fixed))

    def _parts(self, conditions: Conditions, params: np.ndarray | None) -> tuple[Any, ...]:
        p = np.zeros(4) if params is None else np.asarray(params, dtype=float)
        q = np.asarray(conditions.q, dtype=float)
        p = p[..., None, :]  # over rows
        angle = q[..., 0] + p[..., 3]
        reach = SLIDE_START_MM + p[..., 2] + q[..., 1]
        return p, np.cos(angle), np.sin(angle), reach

    def positions(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        p, c, s, reach = self._parts(conditions, params)
        return np.stack([p[..., 0] + reach * c, p[..., 1] + reach * s], axis=-1)

    def jacobian(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        _, c, s, reach = self._parts(conditions, params)
        one, zero = np.ones_like(c), np.zeros_like(c)
        dx = np.stack([one, zero, c, -reach * s], axis=-1)
        dy = np.stack([zero, one, s, reach * c], axis=-1)
        return np.stack([dx, dy], axis=-2)


def _encode(arm: SlidingArm) -> dict[str, Any]:
    return {"kind": "toy-slider", "name": arm.name}


def _decode(
    data: dict[str, Any], noise: NoiseModel | None, fixed: list[str], doc: dict[str, Any]
) -> SlidingArm:
    return SlidingArm(str(data["name"]), tuple(fixed), noise)


@pytest.fixture
def toy() -> Iterator[SlidingArm]:
    """The toy family, registered for the test and removed after it."""
    register(
        Family("toy-slider", "a toy R-P arm", "none", refs={"encode": _encode, "decode": _decode})
    )
    yield SlidingArm(noise=NoiseModel.isotropic(0.05, dim=2))
    unregister("toy-slider")


def _plan(m: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-1.4, 1.4, m), rng.uniform(0.0, 400.0, m)])


def test_the_toy_jacobian_is_the_derivative_of_its_points(toy):
    """The fixture's own Jacobian against central differences (steps 1e-6, tolerance
    1e-6 mm per unit: the truncation error of the cosine is ~1e-12 relative)."""
    rows = toy.conditions(_plan(5, 1))
    analytic = toy.jacobian(rows, TRUTH)
    numeric = np.empty_like(analytic)
    for k in range(4):
        step = np.zeros(4)
        step[k] = 1e-6
        numeric[..., k] = (
            toy.positions(rows, TRUTH + step) - toy.positions(rows, TRUTH - step)
        ) / 2e-6
    np.testing.assert_allclose(analytic, numeric, atol=1e-6)


def test_noiseless_data_of_the_toy_are_recovered_to_round_off(toy):
    q = _plan(12, 2)
    points = armcal.synthesize_measurements(toy, q, TRUTH, sigma=0.0, rng=0)
    cal = armcal.identify(toy, q, points)
    # round-off: the toy's points are ~700 mm; double precision gives ~1e-13 relative
    np.testing.assert_allclose(cal.params, TRUTH, atol=1e-9)
    assert cal.residual_rms < 1e-9


def test_the_toy_is_validated_and_simulated(toy):
    train, held = _plan(20, 3), _plan(10, 4)
    points = armcal.synthesize_measurements(toy, train, TRUTH, rng=5)
    cal = armcal.identify(toy, train, points)
    check = armcal.validate(
        cal.calibrated(), held, armcal.synthesize_measurements(toy, held, TRUTH, rng=6)
    )
    # calibrated: the noise (0.05 mm per coordinate) against 14 mm of base offset before
    rms_after = float(np.sqrt(np.mean(check.after_mm**2)))
    rms_before = float(np.sqrt(np.mean(check.before_mm**2)))
    assert rms_after < 0.2 < 5 < rms_before
    mc = armcal.monte_carlo(toy, train, TRUTH, None, 400, rng=7)
    # predicted std against the Monte Carlo's: 400 trials put a std within 7 % at 2 sigma
    np.testing.assert_allclose(mc.std, mc.predicted_std, rtol=0.15)


def test_the_toy_calibration_file_reads_back(toy, tmp_path):
    q = _plan(15, 8)
    cal = armcal.identify(toy, q, armcal.synthesize_measurements(toy, q, TRUTH, rng=9))
    path = tmp_path / "toy.json"
    path.write_text(to_json(calibration_document(cal)), encoding="utf-8")
    back = read_calibration(path)
    assert isinstance(back.model, SlidingArm) and back.model.family == "toy-slider"
    np.testing.assert_allclose(back.params, cal.params, rtol=1e-15)
