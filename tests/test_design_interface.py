"""Design through the one model interface: the engine knows no family.

A model family plugs into design, the criteria and the certificate by its
:meth:`~armcal.models.interface.FitModel.plan_information`.  The planar arm
brings its own (the paper's complex columns, analytic gradients); the generic
:class:`~armcal.models.information.BlockInformation` builds one for any model
from its whitened Jacobian, with central-difference gradients.  Here a planar
arm is seen *only* through the generic one (:class:`ThroughJacobian`, as a new
family would be), and everything the design layer computes must agree with the
planar family's own view wherever the answer does not depend on the design
coordinates:

* ratios of D-criteria and the gradient of ``log det M`` are invariant under a
  constant change of coordinates ``M -> T^T M T`` (``det`` scales by
  ``det(T)^2`` for every plan alike; ``d log det M`` does not change);
* the Kiefer-Wolfowitz certificate is a ratio of determinants and the variance
  function ``tr(M^-1 I(x))`` is invariant too;
* predicted std and predicted position errors do not depend on coordinates.
"""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import PlanarArm, random_plan
from armcal.criteria import d_efficiency, evaluate_plan, predicted_std
from armcal.doe import certify, design, feasible_poses
from armcal.models import Annulus, CompliantArm, Elastostatic, FitModel, Loads
from armcal.models.information import BlockInformation
from armcal.noise import NoiseModel


class ThroughJacobian:
    """A planar arm as a family without closed forms: design sees only its Jacobian."""

    def __init__(self, arm: PlanarArm) -> None:
        self._arm = arm

    def __getattr__(self, name: str):
        return getattr(self._arm, name)

    def plan_information(
        self, q: np.ndarray, loads: Loads | None = None, *, rows=None
    ) -> BlockInformation:
        return BlockInformation(self, q, loads, rows=rows)

    def closed_form_plans(self, m: int) -> None:
        return None

    def paper_criteria(self, q: np.ndarray) -> None:
        return None

    @property
    def information_bound(self) -> bool:
        return False


LIMITS = np.radians([[-170, 170], [-120, 120], [-120, 120]])
#: Weighted models whose planar design coordinates differ from the raw free parameters.
MODELS = {
    "isotropic": dict(sigma=0.05),
    "encoder": dict(noise=NoiseModel.isotropic(0.02, np.radians(0.01))),
    "per-axis, dq2 fixed": dict(noise=NoiseModel.per_axis(0.08, 0.02), fixed=("dq2",)),
}


def _arm(name: str, **extra) -> PlanarArm:
    return PlanarArm([300.0, 250.0, 150.0], LIMITS, name=name, **MODELS[name], **extra)


def _log_det(model: FitModel, q: np.ndarray) -> float:
    return float(np.log(d_efficiency(model, q)))


@pytest.mark.parametrize("name", list(MODELS))
def test_d_criterion_ratios_agree_between_the_planar_and_the_generic_information(name, rng):
    arm = _arm(name)
    generic = ThroughJacobian(arm)
    plans = [random_plan(arm, 9, rng=rng) for _ in range(4)]
    planar = np.array([_log_det(arm, q) for q in plans])
    through = np.array([_log_det(generic, q) for q in plans])
    # log D differs by the constant (1/p) log det(T^T T) between coordinates: every
    # difference of two plans agrees to round-off of the p x p factorizations.
    assert_allclose(np.diff(planar), np.diff(through), rtol=0, atol=1e-10)


@pytest.mark.parametrize("name", list(MODELS))
def test_gradient_of_log_det_agrees_between_the_planar_and_the_generic_information(name, rng):
    """``d/dq_i log det M = <M^-1, I_i> / R``: analytic (planar) against central differences."""
    arm = _arm(name)
    q = random_plan(arm, 8, rng=rng)
    grads = []
    for model in (arm, ThroughJacobian(arm)):
        info = model.plan_information(q)
        rows = q.shape[0] * info.rows_per_pose
        grads.append(info.gradient(np.linalg.inv(info.information()) / rows))
    # Central differences of step 1e-6 rad: truncation ~1e-12 times the curvature,
    # round-off ~1e-16 / 1e-6 of values O(1): 1e-8 of the largest entry is generous.
    assert_allclose(grads[1], grads[0], rtol=0, atol=1e-8 * np.abs(grads[0]).max())


@pytest.mark.parametrize("name", list(MODELS))
def test_predicted_std_and_position_error_do_not_depend_on_the_view(name, rng):
    arm = _arm(name)
    q = random_plan(arm, 10, rng=rng)
    test_q = random_plan(arm, 30, rng=rng)
    planar = evaluate_plan(arm, q, sigma=0.05, test_q=test_q)
    generic = evaluate_plan(ThroughJacobian(arm), q, sigma=0.05, test_q=test_q)
    assert_allclose(generic.predicted_std, planar.predicted_std, rtol=1e-9)
    assert generic.position is not None and planar.position is not None
    assert_allclose(generic.position.per_pose_mm, planar.position.per_pose_mm, rtol=1e-9)
    assert_allclose(
        predicted_std(ThroughJacobian(arm), q, 0.05), predicted_std(arm, q, 0.05), rtol=1e-9
    )
    assert generic.paper is None and planar.paper is not None


def test_the_certificate_is_the_same_through_the_generic_information(rng):
    """Kiefer-Wolfowitz bounds of one plan, planar and generic, from the same random draws.

    The bound is a ratio of determinants and a maximum of the variance function,
    both invariant; the two differ only by where the multistart ascents (analytic
    against central-difference gradients) stop, which moves the bound by far
    less than 1e-3 on this plan.
    """
    arm = _arm("encoder")
    q = feasible_poses(arm, 12, rng=rng)
    kwargs = dict(candidates=800, rounds=2, search=3000)
    planar = certify(arm, q, rng=5, **kwargs)
    generic = certify(ThroughJacobian(arm), q, rng=5, **kwargs)
    assert generic.certified_d_efficiency == pytest.approx(planar.certified_d_efficiency, abs=1e-3)
    assert generic.plan_only_bound == pytest.approx(planar.plan_only_bound, abs=1e-3)


def test_a_family_without_closed_forms_gets_a_certified_design_in_a_region():
    """The optimizer, the exchange and the certificate through the generic information.

    With every parameter free and isotropic noise the unconstrained optimum is an
    orthogonal plan (D = 1 in the paper's coordinates, where the planar view
    measures it); joints 2 and 3 within +-60 deg and an annulus keep every plan
    well below it, and the certificate says how far the plan is from the best
    within them.  The same design through the planar view is the reference: the
    generic one reaches its D-criterion within 1 % and is certified at least 0.95.
    """
    limits = np.radians([[-170, 170], [-60, 60], [-60, 60]])
    arm = PlanarArm([300.0, 250.0, 150.0], limits, sigma=0.05, region=Annulus((0, 0), 300, 650))
    made = design(ThroughJacobian(arm), 12, rng=3, order="none")
    reference = design(arm, 12, rng=3, order="none")
    assert made.method in ("optimize", "optimize+exchange")
    assert np.all(arm.feasible(made.q))
    assert made.certificate is not None and made.certificate.certified_d_efficiency >= 0.95
    assert d_efficiency(arm, reference.q) < 0.9  # the constraints bind
    assert d_efficiency(arm, made.q) / d_efficiency(arm, reference.q) >= 0.99


class ThreeCoordinates(ThroughJacobian):
    """A planar arm measured as points with a third coordinate ``z = 0.3 x``: a model of
    ``d = 3`` whose blocks have three rows, as a spatial family's will."""

    point_dim = 3

    def jacobian(self, conditions, params=None):
        jac = self._arm.jacobian(conditions, params)
        return np.concatenate([jac, 0.3 * jac[..., :1, :]], axis=-2)

    def whitening(self, conditions, params=None):
        return None


def test_a_model_of_three_coordinates_is_designed_and_certified():
    """Exchange works on planar points only (2 x 2 blocks in closed form): the designer
    then optimizes without it, and the certificate works on 3-row blocks."""
    model = ThreeCoordinates(PlanarArm([300.0, 250.0, 150.0]))
    assert model.plan_information(np.zeros((4, 3))).blocks().shape == (4, 3, 6)
    made = design(model, 8, rng=0)
    assert made.method == "optimize"
    assert made.certificate is not None and made.certificate.certified_d_efficiency >= 0.9


def test_batched_plans_keep_their_own_covariance(rng):
    """Plans (B, m, n) through the generic information: one factor per plan, equal to the
    plan's alone (a compliant arm, whose view is the generic one)."""
    arm = PlanarArm([300.0, 250.0, 150.0], sigma=0.05)
    model = CompliantArm(arm, Elastostatic.create(3, gravity_xy=[0, -1], payload_kg=10.0))
    plans = rng.uniform(-2.0, 2.0, (3, 8, 3))
    batched = predicted_std(model, plans, 0.05)
    alone = np.stack([predicted_std(model, q, 0.05) for q in plans])
    assert batched.shape == (3, model.n_params)
    assert_allclose(batched, alone, rtol=1e-10)


def test_loads_must_give_every_pose_one_row():
    model = CompliantArm(
        PlanarArm([300.0, 250.0, 150.0]),
        Elastostatic.create(3, gravity_xy=[0, -1], payload_kg=10.0),
    )
    with pytest.raises(ValueError, match="one row per pose"):
        model.plan_information(np.zeros((6, 3)), Loads.create(3, [0.0, 5.0, 10.0])).blocks()


def test_multiplicative_weights_match_the_textbook_update():
    """The certificate's weights by matrix products equal the update written out
    (Titterington 1976): w <- w d(x) / p with d(x) = tr(M^-1 I(x)), M = sum w I(x)."""
    from armcal.doe.weights import multiplicative_weights

    rng = np.random.default_rng(3)
    blocks = rng.normal(size=(40, 2, 5))
    weights = rng.uniform(0.5, 1.5, 40)
    weights /= weights.sum()
    expected = weights.copy()
    for _ in range(7):
        info = sum(w * b.T @ b for w, b in zip(expected, blocks, strict=True))
        inverse = np.linalg.inv(info)
        d = np.array([np.trace(inverse @ b.T @ b) for b in blocks])
        expected = expected * d / 5
        expected /= expected.sum()
    np.testing.assert_allclose(multiplicative_weights(blocks, weights, 7), expected, rtol=1e-10)
