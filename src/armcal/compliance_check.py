"""A self-check of elastostatic calibration anyone can rerun (``armcal check-compliance``).

A virtual vertical 3-link arm (links 600/450/200 mm of 20/12/6 kg, a 10 kg
payload, joint compliance 1.5/3/6 urad/(N m): up to about 0.8 mm of tip
deflection) is measured with sigma = 0.02 mm at 40 random poses within its
limits, every other pose carrying the payload.  The check shows:

* a geometry-only fit leaves residuals many times sigma, biases the lengths
  and says so (the ``fit-inconsistent`` warning);
* a fit with compliance has residuals at sigma, every parameter within 3 std
  of the truth, and predicts held-out poses (with and without payload) at the
  noise level;
* a Monte Carlo of that fit: empirical std against predicted, and bias;
* a D-optimal design of 40 poses and payloads, its certified efficiency and
  the predicted std it buys over the random plan.

Every number is computed on the run; the tests (``tests/test_compliance.py``)
assert the thresholds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .criteria import PlanQuality, evaluate_plan
from .doe import Design, design_with_loads
from .doe.plans import feasible_poses
from .identification import Calibration, identify
from .models import CompliantArm, Elastostatic, Loads, PlanarArm, forward_kinematics
from .models.information import display_std, predicted_covariance
from .simulate import MonteCarlo, monte_carlo
from .synthesis import synthesize_measurements
from .validation import validate

__all__ = [
    "ComplianceCheck",
    "check_compliance",
    "virtual_vertical_arm",
]

#: The virtual arm's geometric truth: dl (mm), dq (deg).
TRUTH_DL_MM = (1.0, -0.5, 0.8)
TRUTH_DQ_DEG = (0.3, -0.2, 0.4)
#: Its joint compliance, urad/(N m).
TRUTH_K = (1.5, 3.0, 6.0)
SIGMA_MM = 0.02
PAYLOAD_KG = 10.0


def virtual_vertical_arm() -> tuple[PlanarArm, Elastostatic, np.ndarray]:
    """The virtual arm, its loads and its truth (deviations then ``k``, internal units)."""
    arm = PlanarArm(
        [600.0, 450.0, 200.0],
        np.radians([[-170.0, 170.0], [-150.0, 150.0], [-150.0, 150.0]]),
        name="virtual-vertical-3link",
    )
    elastic = Elastostatic.create(
        3, gravity_xy=[0.0, -1.0], link_masses_kg=[20.0, 12.0, 6.0], payload_kg=PAYLOAD_KG
    )
    truth = np.concatenate(
        [arm.params_from_display(TRUTH_DL_MM, TRUTH_DQ_DEG), np.array(TRUTH_K) * 1e-6]
    )
    return arm, elastic, truth


@dataclass(frozen=True, eq=False)
class ComplianceCheck:
    """The results of :func:`check_compliance`."""

    truth: np.ndarray
    max_deflection_mm: float
    rigid: Calibration
    compliant: Calibration
    validation_rms_mm: float
    validation_predicted_mm: float
    validation_rigid_mm: float
    monte_carlo: MonteCarlo
    design: Design
    design_quality: PlanQuality
    random_std: np.ndarray

    @property
    def certified_d_efficiency(self) -> float:
        """The design's certified D-efficiency (Kiefer-Wolfowitz)."""
        assert self.design.certificate is not None  # a design with loads is certified
        return self.design.certificate.certified_d_efficiency

    @property
    def payload_counts(self) -> dict[float, int]:
        """How many poses of the design carry each payload it could choose (0 too)."""
        chosen = self.design.payload_kg
        assert chosen is not None  # a design with loads
        return {v: int(np.count_nonzero(chosen == v)) for v in self.design.payloads}

    @property
    def errors_in_std(self) -> np.ndarray:
        """``(estimate - truth) / std`` of the fit with compliance, every parameter."""
        std = self.compliant.std / self.compliant.display_scale
        return (self.compliant.params - self.truth) / std

    @property
    def rigid_length_bias_in_std(self) -> np.ndarray:
        """``(dl - truth) / std`` of the geometry-only fit."""
        n = self.rigid.arm.n_joints
        return (self.rigid.params[:n] - self.truth[:n]) / (self.rigid.std[:n])

    def to_dict(self) -> dict:
        mc = self.monte_carlo
        names = mc.names
        return {
            "sigma_mm": SIGMA_MM,
            "max_deflection_mm": self.max_deflection_mm,
            "geometry_only": {
                "residual_rms_per_coordinate_mm": self.rigid.residual_rms,
                "warnings": [w.code for w in self.rigid.warnings],
                "length_bias_in_std": self.rigid_length_bias_in_std.tolist(),
            },
            "with_compliance": {
                "residual_rms_per_coordinate_mm": self.compliant.residual_rms,
                "warnings": [w.code for w in self.compliant.warnings],
                "values": dict(zip(names, self.compliant.values.tolist(), strict=True)),
                "std": dict(zip(names, self.compliant.std.tolist(), strict=True)),
                "error_in_std": dict(zip(names, self.errors_in_std.tolist(), strict=True)),
                "validation_rms_per_point_mm": self.validation_rms_mm,
                "validation_predicted_rms_per_point_mm": self.validation_predicted_mm,
                "validation_geometry_only_rms_per_point_mm": self.validation_rigid_mm,
            },
            "monte_carlo": {
                "trials": mc.trials,
                "std_ratio": dict(zip(names, (mc.std / mc.predicted_std).tolist(), strict=True)),
                "bias_in_limit": dict(zip(names, (mc.bias / mc.bias_limit).tolist(), strict=True)),
            },
            "design": {
                "certified_d_efficiency": self.certified_d_efficiency,
                "payload_counts": {f"{k:g}": v for k, v in self.payload_counts.items()},
                "predicted_std": dict(
                    zip(names, self.design_quality.predicted_std.tolist(), strict=True)
                ),
                "random_plan_std": dict(zip(names, self.random_std.tolist(), strict=True)),
            },
        }


def check_compliance(*, seed: int = 0, trials: int = 4000, poses: int = 40) -> ComplianceCheck:
    """Run the self-check on the virtual vertical arm (see the module notes)."""
    rng = np.random.default_rng(seed)
    arm, elastic, truth = virtual_vertical_arm()
    q = feasible_poses(arm, poses, rng=rng)
    loads = Loads.create(poses, np.where(np.arange(poses) % 2 == 1, PAYLOAD_KG, 0.0))
    model = CompliantArm.for_loads(arm, elastic, loads)
    rows = model.conditions(q, loads=loads)
    clean = model.positions(rows, truth)
    deflection = np.linalg.norm(clean - forward_kinematics(arm, q, truth[: arm.n_params]), axis=1)
    xy = synthesize_measurements(model, q, truth, SIGMA_MM, rng=rng, loads=loads)
    rigid = identify(arm, q, xy, sigma=SIGMA_MM)
    compliant = identify(model, q, xy, sigma=SIGMA_MM, loads=loads)
    held = 200
    q_test = feasible_poses(arm, held, rng=rng)
    test_loads = Loads.create(held, rng.choice([0.0, PAYLOAD_KG], held))
    xy_test = synthesize_measurements(model, q_test, truth, SIGMA_MM, rng=rng, loads=test_loads)
    checked = validate(compliant.calibrated(), q_test, xy_test, loads=test_loads)
    rigid_check = validate(rigid.calibrated(), q_test, xy_test)
    mc = monte_carlo(model, q, truth, SIGMA_MM, trials, rng=rng, loads=loads)
    plan = design_with_loads(
        CompliantArm(arm, elastic), poses, payloads=(0.0, PAYLOAD_KG), rng=rng
    )
    assert plan.payload_kg is not None
    plan_loads = Loads.create(poses, plan.payload_kg)
    plan_quality = evaluate_plan(
        plan.model, plan.q, sigma=SIGMA_MM, test_q=np.zeros((0, 3)), loads=plan_loads
    )
    random_covariance, _ = predicted_covariance(model, rows, SIGMA_MM)
    return ComplianceCheck(
        truth=truth,
        max_deflection_mm=float(deflection.max()),
        rigid=rigid,
        compliant=compliant,
        validation_rms_mm=checked.summary()["rms_after_per_point_mm"],
        validation_predicted_mm=checked.summary()["predicted_rms_after_per_point_mm"],
        validation_rigid_mm=rigid_check.summary()["rms_after_per_point_mm"],
        monte_carlo=mc,
        design=plan,
        design_quality=plan_quality,
        random_std=display_std(model, random_covariance),
    )


def format_check(check: ComplianceCheck) -> str:
    """The self-check as a report."""
    mc = check.monte_carlo
    rigid, fit = check.rigid, check.compliant
    lines = [
        "elastostatic self-check: virtual vertical 3-link arm (600/450/200 mm, 20/12/6 kg, "
        f"payload {PAYLOAD_KG:g} kg on every other pose), sigma {SIGMA_MM} mm, "
        f"{fit.n_poses} random poses; tip deflection up to {check.max_deflection_mm:.3f} mm",
        "",
        f"geometry only: residual RMS {rigid.residual_rms:.4f} mm per coordinate "
        f"({rigid.residual_rms / SIGMA_MM:.1f} sigma); warnings: "
        f"{', '.join(w.code for w in rigid.warnings) or 'none'}",
        "  length errors in std: "
        + ", ".join(f"{v:+.1f}" for v in check.rigid_length_bias_in_std),
        f"with compliance: residual RMS {fit.residual_rms:.4f} mm per coordinate "
        f"({fit.residual_rms / SIGMA_MM:.3f} sigma); warnings: "
        f"{', '.join(w.code for w in fit.warnings) or 'none'}",
        f"held-out poses (200, payload 0 or {PAYLOAD_KG:g} kg): "
        f"RMS {check.validation_rms_mm:.4f} mm per point "
        f"with compliance (predicted {check.validation_predicted_mm:.4f} mm per point), "
        f"{check.validation_rigid_mm:.4f} mm per point with the geometry-only fit",
        "",
        f"{'parameter':<10}{'truth':>10}{'fit':>11}{'± std':>10}{'err/std':>9}"
        f"{'MC std/pred':>13}{'MC bias/limit':>15}{'design std':>12}{'random std':>12}  unit",
    ]
    truth = check.truth * fit.display_scale
    ratio = mc.std / mc.predicted_std
    bias = mc.bias / mc.bias_limit
    for i, (name, unit) in enumerate(zip(fit.names, fit.units, strict=True)):
        lines.append(
            f"{name:<10}{truth[i]:>10.4g}{fit.values[i]:>11.5g}{fit.std[i]:>10.3g}"
            f"{check.errors_in_std[i]:>+9.2f}{ratio[i]:>13.3f}{bias[i]:>+15.2f}"
            f"{check.design_quality.predicted_std[i]:>12.3g}{check.random_std[i]:>12.3g}  {unit}"
        )
    counts = ", ".join(f"{c} at {v:g} kg" for v, c in check.payload_counts.items())
    lines += [
        "",
        f"Monte Carlo: {mc.trials} trials, {mc.seconds:.1f} s",
        f"design of {fit.n_poses} poses and payloads: certified D-efficiency >= "
        f"{check.certified_d_efficiency:.4f}; payloads {counts}",
    ]
    return "\n".join(lines)
