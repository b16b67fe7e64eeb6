"""Design and sizing defects found by the battery of real runs (issue 34).

- ``poses-needed --length-std-mm/--angle-std-deg`` bounds the arm's own parameters of
  that unit (a spatial arm has no ``dl``/``dq`` lengths), and refuses a model with none
  free;
- ``design --candidates`` takes every pose from the candidates, for every family, and
  refuses the methods that make poses of their own;
- a pool of fewer distinct poses than the plan warns ``pool-repeats`` (refused with
  ``--distinct``);
- the pool certificate never claims more than the plan's efficiency relative to the
  best design over the pool, computed here independently.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from armcal.criteria import predicted_std
from armcal.doe import design
from armcal.doe.certificate import certify_pool
from armcal.doe.plans import random_plan
from armcal.doe.sizing import accuracy_metric, poses_needed, requirement_params
from armcal.errors import ArmcalError
from armcal.models import PlanarArm
from armcal.workflow.plan import moving_set
from helpers import VERTICAL_3LINK, run_cli
from helpers_spatial import ARMS

#: The battery's planar bench (/tmp/battery-planar/bench.toml): three links, limits.
BENCH = """name = "bench3"
link_lengths_mm = [300.0, 250.0, 150.0]
joint_limits_deg = [[-170, 170], [-150, 150], [-150, 150]]
"""


def _bench() -> PlanarArm:
    """:data:`BENCH` as an arm: candidate files are drawn within its limits."""
    return PlanarArm(
        [300.0, 250.0, 150.0], joint_limits=np.radians([[-170, 170], [-150, 150], [-150, 150]])
    )


REQUIREMENT_UNIT = {"length_std_mm": "mm", "angle_std_deg": "deg"}  # PRODUCT.md's units


def _own_params(model, requirement: str) -> list[str]:
    """The names a length/angle target should bound, from the model's own description:
    parameters in the target's unit that are not the instrument's pose or the targets."""
    unit = REQUIREMENT_UNIT[requirement]
    return [
        name
        for name, u, instrument in zip(
            model.param_names, model.param_units, model.instrument_params, strict=True
        )
        if u == unit and not instrument
    ]


def _picked(model, requirement: str) -> list[str]:
    """The names :func:`requirement_params` picks."""
    return [str(n) for n in np.array(model.param_names)[requirement_params(model, requirement)]]


def _spatial_model():
    """The four-joint spatial arm with a slide (RRPR), reduced to what moving every joint
    identifies (as the program does), so that its plans are identifiable."""
    return moving_set(ARMS["scara"](), 0)


# ---------------------------------------------------------------- item 1: requirement


@pytest.mark.parametrize("requirement", sorted(REQUIREMENT_UNIT))
def test_a_planar_requirement_bounds_exactly_the_link_lengths_or_the_joint_offsets(requirement):
    arm = PlanarArm([300.0, 250.0, 150.0], base_offset=True)
    picked = _picked(arm, requirement)
    assert picked == _own_params(arm, requirement)
    # the paper's names: dl_k are the lengths, dq_k the offsets; x0, y0 (the base) are not
    prefix = "dl" if requirement == "length_std_mm" else "dq"
    assert picked == [f"{prefix}{k}" for k in (1, 2, 3)]


@pytest.mark.parametrize("requirement", sorted(REQUIREMENT_UNIT))
def test_a_spatial_requirement_bounds_the_arm_s_own_parameters_and_reports_their_largest_std(
    requirement,
):
    """The battery's traceback: a spatial arm has no ``dl``; the target is over its joint
    placements and zeros of the unit, never the base, the tool or another unit."""
    model = _spatial_model()
    expected = _own_params(model, requirement)
    picked = _picked(model, requirement)
    assert picked == expected
    assert not any(n.startswith(("base.", "tool.")) for n in picked)
    assert ("dq3" in picked) == (requirement == "length_std_mm")  # joint 3 is a slide (mm)
    rng = np.random.default_rng(7)
    q = random_plan(model, 12, rng=rng)
    sigma = 0.02
    std = predicted_std(model, q, sigma)
    index = [model.param_names.index(n) for n in expected]
    found = accuracy_metric(model, q, requirement, sigma, q)
    assert found == pytest.approx(float(np.max(std[index])), rel=1e-12)
    # some of them are free, others fixed by the moving set: the largest is over the free
    assert np.any(std[index] > 0)


def test_poses_needed_reports_the_free_parameters_it_bounded_and_their_largest_std():
    model = _spatial_model()
    sigma, goal = 0.02, 0.05  # a loose target: a few random plans reach it
    found = poses_needed(model, "length_std_mm", goal, sigma=sigma, rng=3, plans="random")
    made = found.model
    assert made is not None
    expected = [n for n in _own_params(made, "length_std_mm") if n in made.free_names]
    assert list(found.measured) == expected
    std = predicted_std(made, found.plan, sigma)
    index = [made.param_names.index(n) for n in expected]
    assert found.achieved == pytest.approx(float(np.max(std[index])), rel=1e-12)
    assert found.achieved <= goal * (1 + 1e-9)


@pytest.mark.parametrize("family", ["planar", "spatial"])
def test_a_target_whose_parameters_are_all_fixed_is_refused(family):
    model = PlanarArm([300.0, 250.0, 150.0]) if family == "planar" else _spatial_model()
    fixed = [n for n in _own_params(model, "length_std_mm") if n not in model.fixed]
    reduced = model.with_fixed((*model.fixed, *fixed))
    with pytest.raises(ArmcalError, match="length_std_mm"):
        poses_needed(reduced, "length_std_mm", 0.01, sigma=0.02, rng=0)


# ---------------------------------------------------------------- item 2: candidates


def _rows_of(plan: np.ndarray, pool: np.ndarray, atol: float) -> bool:
    distance = np.abs(plan[:, None, :] - pool[None, :, :]).max(axis=2)
    return bool(np.all(distance.min(axis=1) <= atol))


@pytest.mark.parametrize("family", ["planar", "spatial"])
def test_every_pose_of_a_plan_from_candidates_is_a_candidate(family):
    model = PlanarArm([300.0, 250.0, 150.0]) if family == "planar" else _spatial_model()
    pool = random_plan(model, 40, rng=np.random.default_rng(11))
    made = design(model, 10, candidates=pool, rng=0)
    assert made.method.startswith("pool")
    assert _rows_of(made.q, pool, atol=0.0)  # indexed from the pool: exactly its rows
    assert made.certificate is not None and made.certificate.pool_size == 40
    assert made.warnings == ()


def _write_plan(path, q_deg: np.ndarray) -> None:
    header = ",".join(f"q{k + 1}_deg" for k in range(q_deg.shape[1]))
    path.write_text(header + "\n" + "\n".join(",".join(f"{v:.12g}" for v in row) for row in q_deg))


def test_the_program_s_planar_plan_from_candidates_takes_only_their_rows(tmp_path):
    """The battery's P500: a planar plan ignored the candidates."""
    (tmp_path / "bench.toml").write_text(BENCH)
    model = _bench()
    pool_deg = np.round(np.degrees(random_plan(model, 30, rng=np.random.default_rng(5))), 6)
    _write_plan(tmp_path / "cand.csv", pool_deg)
    run = run_cli(tmp_path, "design", "--robot", "bench.toml", "--poses", "8",
                  "--candidates", "cand.csv", "-o", "plan.csv")  # fmt: skip
    assert run.returncode == 0, run.stderr
    plan = np.loadtxt(tmp_path / "plan.csv", delimiter=",", skiprows=1)
    # the plan CSV prints at least 6 decimals of a degree: equal rows within 1e-6 deg
    assert _rows_of(plan[:, :3], pool_deg, atol=1e-6)


@pytest.mark.parametrize("method", ["analytic", "optimize"])
def test_methods_that_make_their_own_poses_are_refused_with_candidates(tmp_path, method):
    (tmp_path / "bench.toml").write_text(BENCH)
    model = _bench()
    _write_plan(tmp_path / "cand.csv", np.degrees(random_plan(model, 20, rng=1)).round(6))
    run = run_cli(tmp_path, "design", "--robot", "bench.toml", "--poses", "8",
                  "--candidates", "cand.csv", "--method", method, "-o", "plan.csv")  # fmt: skip
    assert run.returncode == 2
    assert run.stderr.startswith("armcal: error:") and "--method auto" in run.stderr
    assert "Traceback" not in run.stderr and not (tmp_path / "plan.csv").exists()


# ---------------------------------------------------------------- item 3: pool-repeats


def test_a_pool_of_fewer_poses_than_the_plan_warns_and_distinct_refuses():
    model = _spatial_model()
    pool = random_plan(model, 8, rng=np.random.default_rng(2))  # 8 distinct < 12 asked
    made = design(model, 12, candidates=pool, rng=0)
    assert [w.code for w in made.warnings] == ["pool-repeats"]
    assert _rows_of(made.q, pool, atol=0.0)
    with pytest.raises(ArmcalError, match="8 distinct"):
        design(model, 12, candidates=pool, rng=0, distinct=True)
    # as many distinct poses as asked for: no warning
    assert design(model, 8, candidates=pool, rng=0).warnings == ()


def test_the_program_warns_pool_repeats_on_stderr_and_in_the_json(tmp_path):
    (tmp_path / "bench.toml").write_text(BENCH)
    model = _bench()
    # 6 distinct poses (12 equations for the 8 parameters), each twice: 6 < 9 asked for
    pool = np.degrees(random_plan(model, 6, rng=np.random.default_rng(4))).round(6)
    _write_plan(tmp_path / "cand.csv", np.concatenate([pool, pool]))
    args = ("design", "--robot", "bench.toml", "--poses", "9", "--candidates", "cand.csv")
    run = run_cli(tmp_path, *args, "--json", "-o", "plan.csv")
    assert run.returncode == 0, run.stderr
    assert "armcal: warning: the candidate poses hold 6 distinct poses" in run.stderr
    codes = [w["code"] for w in json.loads(run.stdout)["warnings"]]
    assert "pool-repeats" in codes
    refused = run_cli(tmp_path, *args, "--distinct", "-o", "plan2.csv")
    assert (
        refused.returncode == 2
        and "6 distinct" in refused.stderr
        and "--poses 6" in refused.stderr
    )


# ---------------------------------------------------------------- item 4: certificate


def _d_optimal_weights(info: np.ndarray, iterations: int) -> np.ndarray:
    """The D-optimal weights over poses of information ``info`` ``(N, p, p)`` by the
    multiplicative algorithm (Titterington 1976), written here independently."""
    weights = np.full(info.shape[0], 1.0 / info.shape[0])
    p = info.shape[-1]
    for _ in range(iterations):
        inverse = np.linalg.inv(np.einsum("k,kij->ij", weights, info))
        weights = weights * np.einsum("ij,kji->k", inverse, info) / p
        weights /= weights.sum()
    return weights


def _true_pool_efficiency(model, plan: np.ndarray, pool: np.ndarray) -> float:
    """``(det M_plan / det M*)^(1/p)``, ``M*`` the best weighted design over ``pool``,
    checked optimal by the equivalence theorem (``max d <= p`` to 1e-6)."""
    blocks = model.plan_information(pool).blocks()
    info = np.einsum("krp,krq->kpq", blocks, blocks)  # any common scale cancels below
    weights = _d_optimal_weights(info, 20000)
    best = np.einsum("k,kij->ij", weights, info)
    p = info.shape[-1]
    variance = np.einsum("ij,kji->k", np.linalg.inv(best), info)
    assert variance.max() <= p * (1 + 1e-6)  # Kiefer-Wolfowitz: xi* is D-optimal
    plan_blocks = model.plan_information(plan).blocks()
    mine = np.einsum("krp,krq->pq", plan_blocks, plan_blocks) / plan.shape[0]
    return float(np.exp((np.linalg.slogdet(mine)[1] - np.linalg.slogdet(best)[1]) / p))


@pytest.mark.parametrize("chosen", ["designed", "random"])
def test_the_pool_certificate_never_overclaims_and_is_tight_on_a_designed_plan(chosen):
    model = _bench()
    pool = random_plan(model, 15, rng=np.random.default_rng(9))
    if chosen == "designed":
        plan = design(model, 6, candidates=pool, rng=0, with_certificate=False).q
    else:  # six pool poses at random: a poorer plan, well below the pool's best
        plan = pool[np.random.default_rng(1).choice(15, 6, replace=False)]
    truth = _true_pool_efficiency(model, plan, pool)
    found = certify_pool(model, plan, pool)
    assert found.pool_size == 15
    assert found.certified_d_efficiency <= truth * (1 + 1e-9)  # a lower bound, never more
    # the reference is 300 iterations of the multiplicative algorithm: close to xi*
    assert found.certified_d_efficiency >= 0.9 * truth


# ---------------------------------------------------------------- item 5: payload candidates

#: The battery's planar arm with compliance (/tmp/battery-pcomp/vertical.toml).
VERTICAL = VERTICAL_3LINK


@pytest.mark.parametrize("robot", ["vertical", "bench"])
def test_candidates_with_a_payload_column_are_refused_naming_the_column(tmp_path, robot):
    """The battery's C040: with [elastostatic] the refusal said the robot had no such
    table; without it the column is not the robot's.  Never dropped in silence."""
    (tmp_path / "robot.toml").write_text(VERTICAL if robot == "vertical" else BENCH)
    q = np.degrees(random_plan(_bench(), 12, rng=np.random.default_rng(6))).round(6)
    rows = [",".join(f"{v:.6f}" for v in row) + ",10.0" for row in q]
    (tmp_path / "cand.csv").write_text("q1_deg,q2_deg,q3_deg,payload_kg\n" + "\n".join(rows))
    run = run_cli(tmp_path, "design", "--robot", "robot.toml", "--poses", "8",
                  "--candidates", "cand.csv", "-o", "plan.csv")  # fmt: skip
    assert run.returncode == 2 and not (tmp_path / "plan.csv").exists()
    (line,) = run.stderr.splitlines()
    assert line.startswith("armcal: error: cand.csv:") and "payload_kg" in line
    if robot == "vertical":
        assert "[elastostatic]" in line and "--candidates" in line
        assert "has no [elastostatic]" not in line


# ---------------------------------------------------------------- item 6: flags, progress


@pytest.mark.parametrize(
    ("command", "flag", "what"),
    [
        ("simulate", "--trials", "trials"),
        ("reproduce", "--trials", "trials"),
        ("reproduce", "--random-plans", "random plans"),
    ],
)
def test_too_few_trials_is_one_line_naming_the_flag_and_the_minimum(tmp_path, command, flag, what):
    """The battery's P421: ``--trials 0`` said 'expected at least 1 pose'."""
    (tmp_path / "bench.toml").write_text(BENCH)
    _write_plan(tmp_path / "plan.csv", np.degrees(random_plan(_bench(), 8, rng=0)).round(6))
    given = {
        "simulate": ("--robot", "bench.toml", "--plan", "plan.csv"),
        "reproduce": ("-o", "out"),
    }
    for value, said in (
        ("0", f"expected at least 2 {what}, got 0"),
        ("x", f"whole number of {what}"),
    ):
        run = run_cli(tmp_path, command, *given[command], flag, value)
        assert run.returncode == 2
        (line,) = run.stderr.splitlines()
        assert line.startswith(f"armcal: error: argument {flag}: ") and said in line
        assert "pose" not in line


def test_poses_needed_reports_progress_while_each_size_is_designed():
    """The battery's B016: the bar stood still for the whole of one size's design.  The
    calls are never decreasing, end at 1000, and come between the sizes too."""
    calls: list[int] = []
    model = PlanarArm([300.0, 250.0, 150.0], joint_limits=np.radians([[-90, 90]] * 3))

    def progress(done: int, total: int) -> None:
        calls.append(1000 * done // total)

    found = poses_needed(model, "position_rms_mm", 0.05, sigma=0.02, rng=0, progress=progress)
    assert calls == sorted(calls) and calls[-1] == 1000
    # each size reports its end once; a design that optimizes reports as it goes
    assert found.method.startswith("optimize")
    assert len(calls) > len(found.evaluated) + 1
