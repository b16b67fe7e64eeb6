"""A new user's first week: odd inputs armcal accepts, and the warning or policy each gets.

The bad-input catalogue (``test_cli_errors.py``) holds what is refused with exit
status 2.  This file holds the rest of issue 20's list: inputs that are legal
but lead a careless reading to a wrong answer.  Each test runs the program as a
user would and checks that the output says what is wrong and points the right
way -- never a calibration the data cannot support, reported with exit 0 in
silence.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from armcal import load_robot, random_plan, synthesize_measurements
from armcal.files import format_measurements_csv
from helpers import run_cli


def _warnings(run) -> dict[str, str]:
    return {w["code"]: w["message"] for w in json.loads(run.stdout)["warnings"]}


# --------------------------------------------------------------------------- a wrong --fix


@pytest.fixture
def held_wrong(tmp_path: Path) -> Path:
    """paper-3link measured at 15 random poses (sigma 0.05 mm); its dl3 and dq3 are not 0.

    The paper's deviations have dl3 = -0.4 mm and dq3 = 0.7 deg, so holding them
    at 0 leaves a misfit of about a millimetre at every pose: 20 times sigma.
    """
    spec = load_robot("paper-3link")
    q = random_plan(spec.arm, 15, rng=np.random.default_rng(0))
    xy = synthesize_measurements(
        spec.arm, q, spec.default_truth, sigma=0.05, rng=np.random.default_rng(10)
    )
    (tmp_path / "meas.csv").write_text(format_measurements_csv(q, xy))
    return tmp_path


IDENTIFY_HELD = (
    "identify",
    "--robot",
    "paper-3link",
    "--measurements",
    "meas.csv",
    "--fix",
    "dl3,dq3",
    "--sigma",
    "0.05",
    "--json",
)


def test_a_wrong_fix_is_named_as_the_cause_not_outliers(held_wrong: Path) -> None:
    """Freeing the held parameters fits to the noise: that, not --robust, is the advice."""
    run = run_cli(held_wrong, *IDENTIFY_HELD)
    assert run.returncode == 0, run.stderr
    message = _warnings(run)["fit-inconsistent"]
    causes = message.split("likely causes, in order: ")[1]
    assert causes.startswith("the fixed parameters dl3, dq3 are not at nominal")
    # Free, the model is right: chi2 on 2*15 - 6 = 24 dof is near 24, far below the 10-fold
    # drop that names the held parameters.
    chi2 = float(causes.split("chi2 = ")[1].split(" ")[0])
    assert chi2 < 3 * 24
    assert "try --robust" not in message
    assert "not outliers" in message


def test_a_robust_fit_never_drops_most_of_the_data(held_wrong: Path) -> None:
    """Most poses disagreeing is a model problem: none is left out, the dof stay, it says so."""
    run = run_cli(held_wrong, *IDENTIFY_HELD, "--robust")
    assert run.returncode == 0, run.stderr
    document = json.loads(run.stdout)
    warnings = _warnings(run)
    assert "model-misfit" in warnings
    assert "15 of 15 poses disagree" in warnings["model-misfit"]
    assert "the fixed parameters dl3, dq3" in warnings["model-misfit"]
    assert not any(o["removed"] for o in document["outliers"])
    assert document["poses_used"] == 15
    assert document["degrees_of_freedom"] == 2 * 15 - 4  # 4 free parameters
    assert "armcal: warning: 15 of 15 poses disagree" in run.stderr
