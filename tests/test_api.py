"""The API a scientist meets: short readable reprs, parameters by name."""

import numpy as np
import pytest

import armcal
from armcal.models import CompliantArm, Elastostatic, Loads


@pytest.fixture(scope="module")
def story():
    """A calibration of the paper's 4-link arm and everything made from it."""
    spec = armcal.load_robot("paper-4link")
    arm, truth = spec.arm, spec.default_truth
    plan = armcal.orthogonal_plan(arm, 20)
    xy = armcal.synthesize_measurements(arm, plan, truth, 0.1, rng=0)
    cal = armcal.identify(arm, plan, xy, sigma=0.1)
    held = armcal.random_plan(arm, 30, rng=1)
    measured = armcal.synthesize_measurements(arm, held, truth, 0.1, rng=2)
    return {
        "arm": arm,
        "calibration": cal,
        "calibrated": cal.calibrated(),
        "quality": armcal.evaluate_plan(arm, plan, sigma=0.1, test_q=held),
        "design": armcal.design(arm, 8, rng=0),
        "monte carlo": armcal.monte_carlo(arm, plan, truth, 0.1, 200, rng=3),
        "validation": armcal.validate(cal.calibrated(), held, measured),
        "cross-validation": armcal.cross_validate(arm, plan, xy, 4, sigma=0.1, rng=4),
        "compensation": armcal.compensate(cal.calibrated(), held[:5]),
        "compliant arm": CompliantArm.for_loads(
            arm,
            Elastostatic.create(4, gravity_xy=[0, -1], link_masses_kg=[8, 6, 4, 2]),
            Loads.create(2, [0.0, 5.0]),
        ),
    }


@pytest.mark.parametrize(
    "what",
    [
        "arm",
        "calibration",
        "calibrated",
        "quality",
        "design",
        "monte carlo",
        "validation",
        "cross-validation",
        "compensation",
        "compliant arm",
    ],
)
def test_every_result_has_a_short_one_line_repr(story, what):
    """A repr is a sentence, not a dump of arrays (a calibration's used to be 2,700 chars)."""
    text = repr(story[what])
    assert "\n" not in text and len(text) <= 200, text
    assert "array(" not in text, text


def test_parameters_by_name_give_value_std_and_unit(story):
    cal = story["calibration"]
    estimate = cal["dq2"]
    i = cal.names.index("dq2")
    assert (estimate.value, estimate.std, estimate.unit) == (cal.values[i], cal.std[i], "deg")
    assert story["monte carlo"]["dq2"]["unit"] == "deg"
    assert story["quality"]["dl1"]["predicted_std"] == pytest.approx(0.1 / np.sqrt(20))
    for result in (cal, story["monte carlo"], story["quality"]):
        with pytest.raises(KeyError, match="dl1"):
            result["dl9"]
