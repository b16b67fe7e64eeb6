"""How good are random plans?  Criteria and predicted accuracy of many at once (paper Figure 1).

Every plan's criteria and predicted std are computed in batches of plans (one
stacked SVD per batch), not one plan at a time, on the arm's model: its noise
(weighted information) and its free parameters.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..criteria import CRITERIA
from ..doe.plans import random_plan
from ..models import PlanarArm, plan_svd
from ..models.information import display_std, mean_tip_variance
from ..models.planar.criteria import dstar, inverse_information_batch, model_singular_values
from ..progress import ProgressCallback
from ..simulate import chunk_size
from ..synthesis import simulated_noise

__all__ = [
    "PlanStudy",
    "random_plan_study",
]


@dataclass(frozen=True, eq=False)
class PlanStudy:
    """Criteria and predicted accuracy of many random plans (paper Figure 1).

    Attributes
    ----------
    arm : PlanarArm
        The arm as studied, with the noise model of the predictions
        (:func:`simulated_noise`).
    n_poses : int
        Poses per plan.
    sigma_mm : float
        Instrument noise (mm) for the predicted std: ``sigma`` when given, else
        the noise model's reference.
    det_d : ndarray, shape (N,)
        ``det D'``: determinant of the Hadamard-normalized information matrix,
        ``= d_efficiency ** p`` (1 for an orthogonal plan).  For a weighted or
        reduced model, the determinant of its information matrix ``H^T H``
        (:func:`armcal.models.planar.information.scaled_jacobian`, ``p_f x p_f``), which
        compares plans of that model but is no longer at most 1.
    det_c : ndarray, shape (N,)
        ``det C'`` with ``C' = C / m`` (eq. 20 corrected, see
        :class:`~armcal.models.planar.criteria.DStar`).
        The paper's D* assumes isotropic iid noise and every parameter free: it
        ignores the noise model and the fixed parameters.
    abs_det_s : ndarray, shape (N,)
        ``|det S'|`` with ``S' = S / m`` (the same caveat).
    std : ndarray, shape (N, p)
        Predicted std of the user parameters (mm, deg), 0 for fixed ones;
        ``inf`` rows for plans that cannot identify the parameters.
    position_rms : ndarray, shape (N,)
        Predicted RMS tip error after calibration at the test poses (mm; ``inf``
        if not identifiable).
    """

    arm: PlanarArm
    n_poses: int
    sigma_mm: float
    det_d: np.ndarray
    det_c: np.ndarray
    abs_det_s: np.ndarray
    std: np.ndarray
    position_rms: np.ndarray

    @property
    def identifiable(self) -> np.ndarray:
        return np.all(np.isfinite(self.std), axis=-1)

    def summary(self) -> dict[str, float]:
        """Medians of ``det D'``, ``det C'``, ``|det S'|``, the largest ``det D'`` and the
        share of plans with ``det D' < 0.5`` (the paper's "random plans are poor")."""
        return {
            "det_d_median": float(np.median(self.det_d)),
            "det_d_max": float(self.det_d.max()),
            "det_d_below_half": float(np.mean(self.det_d < 0.5)),
            "det_c_median": float(np.median(self.det_c)),
            "abs_det_s_median": float(np.median(self.abs_det_s)),
        }


def random_plan_study(
    arm: PlanarArm,
    poses: int,
    plans: int,
    *,
    sigma: float | None = None,
    rng: np.random.Generator | int | None = None,
    test_q: np.ndarray | None = None,
    progress: ProgressCallback | None = None,
) -> PlanStudy:
    """Evaluate ``plans`` random plans of ``poses`` poses (uniform within the joint limits).

    Every plan's criteria and predicted std are computed in batches of plans
    (one stacked SVD per batch), not one plan at a time, on the arm's model:
    its noise (weighted information) and its free parameters.

    Parameters
    ----------
    arm : PlanarArm
    poses : int
        Poses per plan.
    plans : int
        Number of random plans.
    sigma : float, optional
        Isotropic instrument noise (mm) overriding the arm's, its encoder noise
        kept; the arm's noise model when omitted (:func:`simulated_noise`).
    rng : numpy.random.Generator or int or None
    test_q : ndarray, shape (k, n), optional
        Poses for the positioning error (default: 1000 uniform within the limits).
    progress : callable, optional
        ``progress(done, total)`` after every batch.

    Returns
    -------
    PlanStudy

    Raises
    ------
    ArmcalError
        If ``sigma`` is not positive and finite, or is omitted for an arm
        without a noise model.

    Examples
    --------
    >>> study = random_plan_study(PlanarArm([260.0, 180.0, 120.0, 100.0]), 10, 500,
    ...                           sigma=0.1, rng=0)
    >>> bool(np.all(study.det_d < 1)), bool(np.all(study.det_c < 1))
    (True, True)
    """
    noise = simulated_noise(arm, sigma)
    model = arm.replace(noise=noise)
    reference = float(sigma) if sigma is not None else noise.sigma_mm
    rng = np.random.default_rng(rng)
    test_q = random_plan(arm, 1000, rng=rng) if test_q is None else np.asarray(test_q, dtype=float)
    p = model.n_free
    chunk = chunk_size(2 * poses * arm.n_params * 4, plans)
    test = model.jacobian(model.plan_conditions(test_q))  # (k, 2, p): once for every chunk
    parts: dict[str, list[np.ndarray]] = {key: [] for key in ("d", "c", "s", "std", "pos")}
    done = 0
    while done < plans:
        size = min(chunk, plans - done)
        q = random_plan(arm, size * poses, rng=rng).reshape(size, poses, arm.n_joints)
        # One SVD per plan serves det D' (the product of the squared singular values,
        # 0 for plans the rank policy calls singular; a weighted or reduced model's
        # unnormalized ones) and the covariance.
        svd = plan_svd(model, q)
        parts["d"].append(
            CRITERIA["D"].from_singular_values(model_singular_values(model, q, svd)) ** p
        )
        star = dstar(model, q)
        parts["c"].append(star.det_c)
        parts["s"].append(star.abs_det_s)
        inverse, _ = inverse_information_batch(model, q, svd=svd)
        parts["std"].append(display_std(model, reference**2 * inverse))
        parts["pos"].append(reference * np.sqrt(mean_tip_variance(test, inverse)))
        done += size
        if progress is not None:
            progress(done, plans)
    joined = {key: np.concatenate(value) for key, value in parts.items()}
    return PlanStudy(
        arm=model,
        n_poses=int(poses),
        sigma_mm=reference,
        det_d=joined["d"],
        det_c=joined["c"],
        abs_det_s=joined["s"],
        std=joined["std"],
        position_rms=joined["pos"],
    )
