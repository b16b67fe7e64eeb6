"""The one interface every family of arm implements: :class:`FitModel`.

Identification, design, Monte Carlo, validation and compensation see an arm
only through this protocol, so a new family (a spatial serial arm, a model of
joint compliance wrapped around a geometric one) plugs in by implementing it,
without a branch in those modules.

A model maps *conditions* -- what is known of every measured row besides the
measured point: the joint readings, the target measured, the loads, the
instrument's noise (:class:`Conditions`) -- and a parameter vector ``(p,)``
(internal units: mm and rad) to the measured points ``(m, d)``, ``d = 2`` for a
planar arm in its plane and 3 for a spatial one.  Everything is batched: a
parameter stack ``(..., p)`` gives points ``(..., m, d)`` and Jacobians
``(..., m, d, p)``.

What a model provides, by use:

* **parameters** -- names, units, the factors to display units, which are fixed
  (held at their nominal value, 0 for a deviation) and which place the
  instrument rather than the robot (:attr:`FitModel.instrument_params`);
* **measurement** -- :meth:`~FitModel.positions`, the parameter Jacobian, the joint
  Jacobian, and the noise of every row (:meth:`~FitModel.pose_covariances`,
  :meth:`~FitModel.whitening`);
* **fitting** -- the closed form where the family has one
  (:meth:`~FitModel.closed_form`), a starting point for Gauss-Newton, the scale
  of a step in mm, and a *nested* model (the same without an effect, e.g. the
  geometry without compliance) with which a fit starts and is judged;
* **analysis** -- identifiability on the model's own scaled Jacobian, the
  covariance factor of the free
  parameters, and which parameters are the robot's deviations and how large
  one is implausible (:class:`DeviationBounds`);
* **design** -- the poses a plan may hold (:meth:`~FitModel.feasible`, the
  instrument's view as smooth constraints), what a plan tells about the free
  parameters in the family's design coordinates (:meth:`~FitModel.plan_information`,
  a :class:`PlanInformation`), whether every design has ``det M <= 1``, the
  family's closed-form plans where it has them (:class:`ClosedFormPlans`), and
  the loads a design may choose;
* **the tool** -- its orientation and that orientation's Jacobians, for
  compensation.

Members return data and codes, never sentences: :mod:`~armcal.models.wording`
puts them in words, one place for every family (why no closed form, what is
held and why, an effect, implausible deviations, loads a model cannot predict,
a barely identifiable plan).

The identifiable subset of an over-complete parameter set is the model's
``fixed`` parameters: a family chooses them by a fixed rule (the planar arm
holds the joint offset a base rotation replaces), and ``identifiability`` names
what the rest cannot separate.  Nuisance parameters (the instrument's pose,
the targets' positions) are ordinary parameters marked by
:attr:`FitModel.instrument_params`: identified with the rest, left out of what
compensation and export call the robot.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Protocol, Self

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ArmcalError, action
from ..noise import NoiseModel
from ..numerics import ScaledSVD
from .identifiability import Identifiability

__all__ = [
    "ROW_BLOCK",
    "ClosedForm",
    "ClosedFormPlan",
    "ClosedFormPlans",
    "Conditions",
    "DesignEffort",
    "DeviationBounds",
    "Effect",
    "FitModel",
    "Held",
    "LinearPositions",
    "Loads",
    "Note",
    "PaperCriteria",
    "PlanInformation",
    "UnpredictedLoads",
    "array_key",
    "columns_jacobian",
    "equations_per_pose",
    "position_jacobian",
    "target_indices",
    "targets_missing",
]


@dataclass(frozen=True, eq=False)
class Loads:
    """The known static loads of every row: payload (kg) and tip force (N).

    Attributes
    ----------
    payload_kg : ndarray, shape (m,)
    force_n : ndarray, shape (m, 2)
        Force applied at the tip, in the measurement frame.
    """

    payload_kg: np.ndarray
    force_n: np.ndarray

    @classmethod
    def create(
        cls, m: int, payload_kg: ArrayLike = 0.0, force_n: ArrayLike | None = None
    ) -> Loads:
        """Loads of ``m`` rows (a scalar payload is every row's).

        Examples
        --------
        >>> Loads.create(3, [0, 10, 0]).known
        True
        >>> Loads.create(2).known
        False
        """
        payload = np.broadcast_to(np.asarray(payload_kg, dtype=float), (m,)).copy()
        force = np.zeros((m, 2)) if force_n is None else np.asarray(force_n, dtype=float)
        if force.shape != (m, 2):
            raise ArmcalError(f"tip forces must have shape ({m}, 2) in N, got {force.shape}")
        if not (np.all(np.isfinite(payload)) and np.all(np.isfinite(force))):
            raise ArmcalError("payloads and tip forces must be finite")
        if np.any(payload < 0):
            raise ArmcalError("payloads must not be negative")
        return cls(payload, force)

    @property
    def n_rows(self) -> int:
        return int(self.payload_kg.shape[0])

    @property
    def known(self) -> bool:
        """Whether any row carries a payload or a tip force."""
        return bool(np.any(self.payload_kg != 0) or np.any(self.force_n != 0))

    @property
    def varying(self) -> bool:
        """Whether the known loads differ between rows."""
        if self.n_rows == 0:
            return False
        return bool(np.ptp(self.payload_kg) > 0 or np.any(np.ptp(self.force_n, axis=0) > 0))

    def take(self, rows: np.ndarray | slice) -> Loads:
        """The loads of the rows ``rows`` (index, mask or slice)."""
        return Loads(self.payload_kg[rows], self.force_n[rows])

    def repeat(self, count: int) -> Loads:
        """Every row ``count`` times in a row (a pose measured at each of its targets)."""
        return Loads(np.repeat(self.payload_kg, count), np.repeat(self.force_n, count, axis=0))


#: Rows of a block of :meth:`Conditions.blocks`: a Jacobian of a few tens of columns over
#: this many rows is a few MB, and stays in the processor's cache.
ROW_BLOCK = 1 << 13


@dataclass(frozen=True, eq=False)
class Conditions:
    """What a model needs to know of measured rows besides the measured points.

    Attributes
    ----------
    q : ndarray, shape (m, n) or (..., m, n)
        Joint readings as the controller reports them, rad; leading axes batch
        over plans where a function says so.
    target : ndarray of int, shape (m,), or None
        The target (reflector, marker) every row measures, as an index into the
        model's targets; None when the model has one target.
    loads : Loads or None
        Every row's payload and tip force; None for the model's default load.
    sigma_mm : ndarray, shape (m,), or None
        Per-row instrument noise (1 std, mm), for instruments that report each
        point's uncertainty; replaces the instrument covariance row by row.
    frames : ndarray, shape (m, 3, 3), or None
        For a model that measures orientations: every row's reference
        orientation, about which the orientation part of a point is a rotation
        vector (:meth:`FitModel.anchor` puts it at the measured orientation); None:
        the instrument's axes.
    feature : ndarray of int, shape (m,), or None
        For an instrument of several features (the planes of a block, the fixed
        points of a fixture: :mod:`armcal.instruments`): the feature every row
        touches, as an index into the instrument's; None for one.

    Examples
    --------
    >>> cond = Conditions(np.zeros((4, 2)), sigma_mm=np.array([0.1, 0.1, 0.5, 0.1]))
    >>> cond.m, cond.take(np.array([True, False, True, False])).sigma_mm.tolist()
    (4, [0.1, 0.5])
    """

    q: np.ndarray
    target: np.ndarray | None = None
    loads: Loads | None = None
    sigma_mm: np.ndarray | None = None
    frames: np.ndarray | None = None
    feature: np.ndarray | None = None
    # Not an argument: a copy by dataclasses.replace (another q) starts with its own memo.
    _memo: dict[Hashable, Any] = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def m(self) -> int:
        """Number of rows."""
        return int(np.shape(self.q)[-2])

    def take(self, rows: np.ndarray | slice) -> Conditions:
        """The conditions of the rows ``rows`` (mask, index or slice) of an unbatched ``q``."""
        return Conditions(
            np.asarray(self.q)[rows],
            None if self.target is None else self.target[rows],
            None if self.loads is None else self.loads.take(rows),
            None if self.sigma_mm is None else self.sigma_mm[rows],
            None if self.frames is None else self.frames[rows],
            None if self.feature is None else self.feature[rows],
        )

    def blocks(self, size: int = 0) -> Iterator[tuple[Conditions, slice]]:
        """The rows (of an unbatched ``q``) in blocks of at most ``size`` (default
        :data:`ROW_BLOCK`): each block's conditions and its slice; these conditions
        themselves when they are one block.  What is made per row (a Jacobian, its
        products) is then made a block at a time: memory ``O(block p)``, not ``O(m p)``
        (each block's conditions, and what a model keeps on them, go with the block)."""
        size = size or ROW_BLOCK
        m = self.m
        if m <= size:
            yield self, slice(0, m)
            return
        for start in range(0, m, size):
            part = slice(start, min(start + size, m))
            yield self.take(part), part

    def with_frames(self, frames: np.ndarray | None) -> Conditions:
        """The same rows with reference orientations ``frames`` ``(m, 3, 3)``."""
        return Conditions(self.q, self.target, self.loads, self.sigma_mm, frames, self.feature)

    def memo(self, key: Hashable, compute: Callable[[], Any]) -> Any:
        """``compute()`` once for these conditions: a factorization several steps share.

        The conditions are immutable, so what is derived from them alone (with a
        key that names the model it was derived for) never goes stale.
        """
        if key not in self._memo:
            self._memo[key] = compute()
        return self._memo[key]

    def latest(self, slot: Hashable, key: tuple) -> Any:
        """What :meth:`keep` put in ``slot`` for ``key``, else None.

        One value per slot, for what depends on parameters as well as on these rows
        (the points at the latest parameters a fit evaluated: its Jacobian's pass has
        them, and its residuals and weights need them again).  Keys match item by
        item: ``bytes``, numbers and strings by value, anything else by identity.
        """
        found = self._memo.get(("latest", slot))
        if found is None or not _same_key(found[0], key):
            return None
        return found[1]

    def keep(self, slot: Hashable, key: tuple, value: Any) -> None:
        """Keep ``value`` in ``slot`` for ``key`` (:meth:`latest`), replacing what was there."""
        self._memo[("latest", slot)] = (key, value)


def array_key(values: np.ndarray) -> bytes:
    """An array as an item of a key of :meth:`Conditions.latest` (matched by value)."""
    return np.ascontiguousarray(values, dtype=float).tobytes()


def _same_key(kept: tuple, key: tuple) -> bool:
    """Whether two keys of :meth:`Conditions.latest` match, item by item."""
    if len(kept) != len(key):
        return False
    by_value = (bytes, str, int, float, tuple)
    return all(
        a is b or (isinstance(a, by_value) and type(a) is type(b) and a == b)
        for a, b in zip(kept, key, strict=True)
    )


@dataclass(frozen=True)
class DesignEffort:
    """How hard a plan search works for a family: what a start costs against how many
    local optima its criteria have.

    Attributes
    ----------
    starts, steps : int
        Random starting plans of the optimizer (batched) and its ascent's steps.
    polish : int
        Iterations of the quasi-Newton polish of the best plans.
    candidates : int
        Random feasible poses of a design with payloads' candidate pool
        (:func:`armcal.doe.design_with_loads`).
    reference, rounds, search : int
        The certificate's (:func:`armcal.doe.certify`): how many poses of its sample
        where the plan is least informed join the weighted design's candidates; the
        rounds of adding the variance function's maximizers to them; and the sample
        of random feasible poses, on which every variance function is evaluated first
        and from whose best poses its ascents start.
    last_starts : int or None
        The ascents of the certificate's last search, the one its bound rests on; None:
        as many as every search's.
    bounded : bool
        Whether the certificate's searches a bound rests on (the plan's, the last) keep to
        the view step by step (:func:`~armcal.doe.constrained.bounded_ascent`) rather
        than by a penalty and a Newton polish: where the variance function's maxima lie
        on the view's edges (a turn's range), the polish cannot follow an edge, and its
        maximum falls short (by 1e-6 of it: a dense search found more, and the bound
        overclaimed).
    """

    starts: int = 48
    steps: int = 400
    polish: int = 500
    candidates: int = 3000
    reference: int = 300
    rounds: int = 4
    search: int = 20000
    last_starts: int | None = None
    bounded: bool = False


@dataclass(frozen=True)
class Effect:
    """What a model adds to its nested model: data that :mod:`~armcal.models.wording`
    puts in words for reports and warnings.

    Attributes
    ----------
    name : str
        The effect ("joint compliance").
    short : str
        One word for it ("compliance"): the warning ``{short}-unseen``.
    nested : str
        What the nested model fits ("geometry").
    lumped : bool
        The effect's terms lump a stiffness with a weight (masses unknown: ``c``)
        rather than being the stiffness itself (``k``).
    stations : bool
        A lumped term belongs to a joint and a station along the arm (``c{j}.{s}``),
        not to a joint alone (``c{j}``).
    advice : str
        What to do when the data do not show it, a code of
        :data:`~armcal.models.wording.EFFECT_ADVICE`.
    positive : bool
        None of its parameters can be negative (joint compliances and lumped
        weights): one identified clearly below zero is warned of
        (``{short}-negative``).
    """

    name: str
    short: str
    nested: str
    lumped: bool
    stations: bool
    advice: str
    positive: bool = False


@dataclass(frozen=True)
class Note:
    """A fact a design or a report states: a code and the values its words place, which
    :func:`~armcal.models.wording.note_words` puts in words.

    Attributes
    ----------
    code : str
        What is said, a key of :data:`~armcal.models.wording.NOTES`.
    values : mapping
        The names and numbers the words place (a value may itself be a tuple of
        :class:`Note`, said one after the other).
    """

    code: str
    values: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Held:
    """Parameters held because the rows cannot separate them from others, or because
    the user holds them, and why: data that :func:`~armcal.models.wording.held_sentence`
    puts in words.

    Attributes
    ----------
    members : tuple of str
        The parameters held.
    into : tuple of str
        The kept parameters they merge into; empty when they cannot be seen at all
        (or the user holds them).
    reason : str
        Why, a code of :data:`~armcal.models.wording.HELD_REASONS`; empty when the
        geometry gives no reason.
    joints : tuple of int
        The 1-based joints the reason is about.
    targets : tuple of str
        The names of the arm's targets, which :attr:`into` groups ("the positions of
        A and B").
    oriented : bool
        The targets are measured in full pose.
    effect : bool
        The members are an effect's terms, merging into whatever they merge into
        (listed by name).
    said : str
        The words of a calibration file written before these codes, shown as they are.
    """

    members: tuple[str, ...]
    into: tuple[str, ...] = ()
    reason: str = ""
    joints: tuple[int, ...] = ()
    targets: tuple[str, ...] = ()
    oriented: bool = False
    effect: bool = False
    said: str = ""


@dataclass(frozen=True)
class UnpredictedLoads:
    """Loads a lumped model of joint compliance cannot predict: it saw one payload only.

    Attributes
    ----------
    terms : tuple of str
        The lumped terms that hold the deflection under that payload.
    payload_kg : float
        The one payload of the calibration's data.
    others : tuple of float
        The other payloads asked for (kg), ascending.
    forced : bool
        Tip forces are asked for.
    """

    terms: tuple[str, ...]
    payload_kg: float
    others: tuple[float, ...]
    forced: bool = False


@dataclass(frozen=True, eq=False)
class DeviationBounds:
    """Which parameters are the robot's deviations, and how large one is implausible.

    A calibration finds deviations of a few mm and about a degree; one far beyond
    its bound says that the robot file or the data are wrong (a unit, another
    variant of the arm), not the arm: the ``large-deviation`` warning
    (:func:`armcal.plausibility.deviation_warning`), in the words of
    :mod:`~armcal.models.wording`.

    Attributes
    ----------
    bounds : ndarray, shape (p,)
        Internal units (mm, rad): a deviation larger in magnitude is implausible;
        ``inf`` for a parameter that is no deviation of the robot (the
        instrument's pose, a target found from the data, an effect's parameter).
    reference_mm : ndarray, shape (p,)
        The length a bound is a fraction of (a link), shown beside a large value
        as a percentage; NaN where the bound is not a fraction of a length.
    reference_names : tuple of str, shape (p,)
        What that length is (``"link 2"``); empty where there is none.
    reference : str
        What a length's bound is a fraction of: ``"link"`` (each its own link),
        ``"reach"`` or ``"placement"`` (a joint's placement, a fraction of the reach).
    length_fraction : float
        That fraction.
    angle_deg : float
        The bound of an angle, degrees.
    check : str
        What to check, a code of :data:`~armcal.models.wording.DEVIATION_CHECKS`.
    turns : ndarray, shape (p,)
        With a base offset, the combination of deviations (coefficients) that also
        takes up any rotation of the instrument's axes; zeros without one.
    length_mm : float
        The bound of a length in mm where it is one number (NaN for one per link).
    """

    bounds: np.ndarray
    reference_mm: np.ndarray
    reference_names: tuple[str, ...]
    reference: str
    length_fraction: float
    angle_deg: float
    check: str
    turns: np.ndarray
    length_mm: float = float("nan")

    @property
    def absorbing(self) -> np.ndarray:
        """``(p,)`` bool: deviations that may also take up something that is no error of
        the robot (with a base offset, the joint offsets that turn the instrument's axes)."""
        return np.asarray(self.turns) != 0

    def extended(self, count: int) -> DeviationBounds:
        """The same bounds followed by ``count`` parameters that are no deviation of the
        robot (an effect's, appended after the arm's)."""
        return replace(
            self,
            bounds=np.concatenate([self.bounds, np.full(count, np.inf)]),
            reference_mm=np.concatenate([self.reference_mm, np.full(count, np.nan)]),
            reference_names=self.reference_names + ("",) * count,
            turns=np.concatenate([self.turns, np.zeros(count)]),
        )


@dataclass(frozen=True, eq=False)
class LinearPositions:
    """Points in the plane that are linear in coordinates of the parameters.

    ``x + i y = basis @ coordinates(params)`` at every row: the planar arm's tip
    is linear in its link phasors, so the mean square error of many estimates at
    many test rows follows from a small second-moment matrix
    (:func:`armcal.simulate.monte_carlo`).

    Attributes
    ----------
    basis : ndarray of complex, shape (k, L)
    coordinates : callable
        ``params (..., p) -> (..., L)`` complex.
    """

    basis: np.ndarray
    coordinates: Callable[[np.ndarray], np.ndarray]


class ClosedForm(Protocol):
    """A model's exact least-squares solution for given conditions, where it has one."""

    def solve(
        self, points: np.ndarray, whitening: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Parameters ``(N, p)`` of point sets ``(N, m, d)`` and whether each fit is full rank.

        ``whitening`` ``(m, d, d)`` or ``(N, m, d, d)`` weights every row (None:
        unweighted); the solution is the weighted least-squares optimum.
        """
        ...


class PlanInformation(Protocol):
    """What plans of poses tell about a model's free parameters, in its design coordinates.

    For plans ``q`` ``(..., m, n)`` every pose ``i`` has an information ``I_i``
    ``(p_f, p_f)``: the Gram matrix of its whitened rows (every target it is
    measured at) in the family's *design coordinates* of the free parameters,
    scaled so that the criteria compare plans (the planar arm's are the paper's
    Hadamard-normalized columns).  The plan's normalized information is
    ``M = sum_i I_i / R`` over its ``R = m T`` rows.  Design (the optimizer, the
    exchange, the certificate) and the criteria see a plan only through this.
    """

    @property
    def rows_per_pose(self) -> int:
        """``T``: the rows every pose is measured in (one per target)."""
        ...

    def information(self) -> np.ndarray:
        """``M`` ``(..., p_f, p_f)``."""
        ...

    def gradient(self, phi: np.ndarray) -> np.ndarray:
        """``d/dq_i <phi, I_i>`` ``(..., m, n)`` for a symmetric ``phi`` ``(p_f, p_f)``
        (or one per plan ``(..., p_f, p_f)``)."""
        ...

    def pose_variance(self, m_inv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``d(x_i) = tr(m_inv I_i) / T`` ``(k,)`` of every pose of ``q`` ``(k, n)``, and
        its gradient ``(k, n)``: the variance function of the equivalence theorem."""
        ...

    def blocks(self) -> np.ndarray:
        """Real factors ``F_i`` ``(..., m, r, p_f)`` with ``I_i = F_i^T F_i``."""
        ...

    def svd(self) -> ScaledSVD:
        """The rank policy's SVD of the stacked rows divided by ``sqrt(R)`` (``H^T H = M``)."""
        ...

    def singular_values(self) -> np.ndarray:
        """``(..., p_f)``: what the criteria are computed on, those the policy drops 0."""
        ...

    def check_identifiable(self) -> Identifiability:
        """Which parameter combinations the plan (one, ``(m, n)``) cannot separate; raises
        NotIdentifiableError (with why) when it cannot identify every parameter."""
        ...

    def covariance_factor(self, params: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``G`` ``(..., p, p_f)`` with ``(J_w^T J_w)^-1 = G G^T`` over the plan's rows
        (internal units, unit noise), and the full-rank mask; ``inf`` where singular."""
        ...


@dataclass(frozen=True, eq=False)
class ClosedFormPlan:
    """A family's closed-form plan that fits the constraints, and which of its kind it is."""

    q: np.ndarray
    label: str


class ClosedFormPlans(Protocol):
    """A family's closed-form ``m``-pose plans (the paper's orthogonal plans for planar arms).

    The designer takes one where the criteria say it is optimal for the model,
    starts its search from them otherwise, and reports the notes these give.
    """

    @property
    def model(self) -> FitModel:
        """The model the plans are for."""
        ...

    @property
    def plans(self) -> tuple[ClosedFormPlan, ...]:
        """The closed-form plans that fit the joint limits and view."""
        ...

    @property
    def failure(self) -> ArmcalError | None:
        """Why the family's own plan does not fit, or None."""
        ...

    def unconstrained(self) -> ClosedFormPlans:
        """The same plans for the model without joint limits and view."""
        ...

    def unfit(self) -> Note:
        """Why no closed-form plan fits the constraints."""
        ...

    def choice(
        self, chosen: ClosedFormPlan, d_criteria: Mapping[str, float], optimal: bool
    ) -> Note | None:
        """Why the chosen plan is (or is not) optimal for the model; None when nothing to say."""
        ...

    def searched(
        self,
        closed_d: float | None,
        plan_d: float,
        method: str,
        would_be_optimal: Callable[[], bool],
    ) -> Note | None:
        """What a searched plan is against the closed-form plans; None when nothing to say."""
        ...


@dataclass(frozen=True)
class PaperCriteria:
    """The paper's own criteria of a plan, for the arms its theory covers (planar).

    Attributes
    ----------
    det_c, abs_det_s : float
        The D* pair ``det C'`` and ``|det S'|`` (paper eq. 20, ``C' = C / m``).
    optimality_sums : dict of str to float
        Every sum of the optimality conditions (21) / Table I, by name.
    """

    det_c: float
    abs_det_s: float
    optimality_sums: dict[str, float]


class Core(Protocol):
    """The required core: names, units and free parameters; joints; the instrument's
    noise and points; positions and Jacobians; whitening; the start. A family that
    implements only these (:class:`~armcal.models.core.CoreModel` gives the rest) is
    identified, validated and simulated."""

    @property
    def name(self) -> str: ...

    @property
    def family(self) -> str:
        """The name of the model's family of arm (``"planar"``, ``"spatial"``): the key
        under which :mod:`armcal.families` finds its files, exports and pictures."""
        ...

    @property
    def param_names(self) -> tuple[str, ...]: ...

    @property
    def param_units(self) -> tuple[str, ...]:
        """Display units, e.g. ``mm``, ``deg``."""
        ...

    @property
    def display_scale(self) -> np.ndarray:
        """Factors ``(p,)`` from internal to display units."""
        ...

    @property
    def fixed(self) -> tuple[str, ...]:
        """Parameters held at their nominal value (0), not identified."""
        ...

    @property
    def free(self) -> np.ndarray:
        """Boolean ``(p,)``: the identified parameters."""
        ...

    @property
    def held_values(self) -> np.ndarray:
        """``(p,)``: the values the parameters that are not free keep (0, a deviation, for
        the planar families; the nominal base pose and targets for the spatial arm)."""
        ...

    @property
    def free_names(self) -> tuple[str, ...]: ...

    @property
    def n_params(self) -> int: ...

    @property
    def n_free(self) -> int: ...

    @property
    def angle_params(self) -> np.ndarray:
        """Boolean ``(p,)``: angles, wrapped into ``(-pi, pi]`` after a fit."""
        ...

    @property
    def instrument_params(self) -> np.ndarray:
        """Boolean ``(p,)``: the instrument's pose, not the robot's (nuisance parameters)."""
        ...

    @property
    def registration_params(self) -> np.ndarray:
        """Boolean ``(p,)``: what registering the nominal arm to measured points fits (the
        instrument's pose and the targets on the tool), the rest held at nominal: the
        honest baseline a calibration is judged against
        (:func:`armcal.identification.register_nominal`)."""
        ...

    @property
    def noise(self) -> NoiseModel | None: ...

    @property
    def n_joints(self) -> int: ...

    @property
    def joint_limits(self) -> np.ndarray:
        """``(n, 2)`` limits of the joint readings, rad (mm for a prismatic joint)."""
        ...

    @property
    def joint_kinds(self) -> tuple[str, ...]:
        """Every joint reading's kind: ``"R"`` (an angle, rad) or ``"P"`` (a slide, mm)."""
        ...

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Every joint's name in the arm's description (a URDF's), or ``joint 1`` ...."""
        ...

    @property
    def joint_map(self) -> np.ndarray:
        """``M`` ``(n, n)``: the chain's joint values (a planar arm's absolute link angles)
        are ``M q`` of the controller's readings ``q``."""
        ...

    def within_limits(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Boolean ``(..., m, n)``: every joint reading of ``q`` (rad) within its limits."""
        ...

    @property
    def target_labels(self) -> tuple[str, ...]:
        """The targets' labels (empty for the single end-of-arm target)."""
        ...

    @property
    def arm(self) -> Any:
        """The geometric arm the model is of (the model itself for a geometric family)."""
        ...

    def with_noise(self, noise: NoiseModel | None) -> Self:
        """The same model with another noise model."""
        ...

    def with_fixed(self, fixed: Sequence[str]) -> Self:
        """The same model with another set of fixed parameters."""
        ...

    @property
    def point_dim(self) -> int:
        """Coordinates of a measured point: 2 (in the plane) or 3, and 6 when the
        instrument also measures the target's orientation (then the last three are a
        rotation vector, rad)."""
        ...

    @property
    def position_dim(self) -> int:
        """The coordinates of a point that are a position (mm): the first ones.  Errors
        and RMS in mm are of these; the rest (an orientation) are reported apart."""
        ...

    def conditions(
        self,
        q: ArrayLike,
        *,
        target: ArrayLike | None = None,
        loads: Loads | None = None,
        sigma_mm: np.ndarray | None = None,
        feature: ArrayLike | None = None,
    ) -> Conditions:
        """Checked conditions of measured rows (ValueError naming what is wrong).

        ``q`` ``(m, n)`` rad; ``target`` ``(m,)`` target indices or labels
        (:func:`target_indices`), needed when the model has several (else
        :func:`targets_missing`); ``loads`` the rows' loads (default: the model's);
        ``sigma_mm`` ``(m,)`` per-row instrument noise; ``feature`` ``(m,)`` the feature
        of the instrument every row touches (:attr:`Conditions.feature`: its index or
        its label), which a model measured by a tracker refuses
        (:func:`refuse_feature`).
        """
        ...

    def positions(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """Measured points ``(..., m, d)`` in mm (nominal parameters when omitted)."""
        ...

    def jacobian(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """``d points / d params`` ``(..., m, d, p)``: mm per internal unit."""
        ...

    def joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``d points / d q`` ``(..., m, d, n)``: mm per rad of every joint reading."""
        ...

    def pose_covariances(
        self,
        conditions: Conditions,
        params: np.ndarray | None = None,
        *,
        noise: NoiseModel | None = None,
    ) -> np.ndarray:
        """Covariance ``(..., m, d, d)`` (mm^2) of every measured point under ``noise``.

        Default: the model's own noise; encoder noise linearized at ``params``.
        """
        ...

    def whitening(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray | None:
        """Relative whitening ``W_i`` ``(..., m, d, d)``, None where it is the identity.

        ``W_i^T W_i = sigma_ref^2 Sigma_i^-1`` (:mod:`armcal.noise`), with the
        rows' own sigma where the conditions give it.
        """
        ...

    def anchor(self, conditions: Conditions, points: np.ndarray) -> tuple[Conditions, np.ndarray]:
        """Measured rows as the fit compares them with :meth:`positions`: ``points``
        ``(m, d)`` as the instrument gives them (an orientation as a rotation vector in
        its frame); a model measuring orientations takes each as its row's reference
        (:attr:`Conditions.frames`) and leaves a zero turn from it, so the fit's
        orientation residuals are small rotation vectors at every orientation."""
        ...

    def unanchor(self, conditions: Conditions, points: np.ndarray) -> np.ndarray:
        """:meth:`anchor` undone: ``points`` ``(..., m, d)`` of these conditions as the
        instrument gives them."""
        ...

    def start(
        self, conditions: Conditions, points: np.ndarray, weights: np.ndarray | None = None
    ) -> np.ndarray:
        """Where Gauss-Newton starts ``(N, p)`` for point sets ``(N, m, d)``.

        ``weights`` ``(m,)`` or ``(N, m)`` weight the rows (0 leaves one out).  Used
        where the model has no :attr:`nested` model to start from.
        """
        ...

    def canonical(self, params: np.ndarray) -> np.ndarray:
        """The same points of the model ``(N, p)`` in canonical form: angles in ``(-pi, pi]``,
        and one of the equivalent parameter sets chosen by a fixed rule (the planar arm's
        positive link lengths: ``(L, dtheta)`` and ``(-L, dtheta + pi)`` are one link)."""
        ...

    def step_scale(self, conditions: Conditions) -> np.ndarray:
        """``(p,)``: how far (mm) a unit step of each parameter moves the points at most."""
        ...


class ClosedFormRole(Protocol):
    """The fit's shortcuts: a closed form (the planar arm's global optimum by one linear
    solve) and the linear positions behind it."""

    @property
    def has_closed_form(self) -> bool:
        """Whether :meth:`closed_form` exists for this model (the rule of ``method="auto"``)."""
        ...

    @property
    def closed_form_hold(self) -> tuple[str, ...] | None:
        """The held parameters that keep the family from its closed form (a closed form
        was asked of a model without one: the error names them); None when the family
        has no closed form at all."""
        ...

    def closed_form(self, conditions: Conditions) -> ClosedForm | None:
        """The exact least-squares solver at these conditions, or None."""
        ...

    def linear_positions(self, conditions: Conditions) -> LinearPositions | None:
        """The points as a linear map of coordinates of the parameters, where they are one."""
        ...

    def fit_details(self, conditions: Conditions, params: np.ndarray) -> dict[str, np.ndarray]:
        """What a report shows of a fit besides its parameters (e.g. the largest deflection)."""
        ...


class IdentifiabilityRole(Protocol):
    """What the rows can and cannot separate: the identifiable set a family's rule
    chooses for them, the rank analysis, the covariance."""

    def prepared(self, conditions: Conditions, points: np.ndarray | None = None) -> FitModel:
        """The model made ready for these rows: its nuisance parameters placed from the
        measured ``points`` (when given) and its identifiable set chosen for them.

        A family whose parameters are minimal returns itself; an over-complete one
        (the spatial arm) holds what the rows cannot separate, by a fixed rule, and
        says why in :attr:`held_reasons`.
        """
        ...

    def selected_by(
        self, rows: np.ndarray, conditions: Conditions, first: Sequence[str] = ()
    ) -> FitModel:
        """The model with what ``rows`` ``(r, p + t)`` cannot separate held by its rule:
        rows of its Jacobian as another measurement sees them (an instrument's readings,
        :mod:`~armcal.models.instrumented`), at the joint readings of ``conditions``,
        beside ``t`` columns of that measurement's own parameters ``first``, which are
        kept before any of the model's.  A family whose parameters are minimal returns
        itself."""
        ...

    def expressed(self, conditions: Conditions, params: np.ndarray) -> np.ndarray:
        """Parameters of this (prepared) model that put the points of these rows where
        ``params`` does, its held parameters included: a virtual arm's truth as a fit of
        its measurements sees it.  A family whose parameters are minimal returns
        ``params`` as they are."""
        ...

    @property
    def held_reasons(self) -> tuple[Held, ...]:
        """Why the parameters held by the family's rule (and an effect's terms the user
        holds) are held: what each merges into (:class:`Held`)."""
        ...

    @property
    def rule_held(self) -> tuple[str, ...]:
        """The parameters the family's rule holds because the measurements cannot separate
        them (:meth:`held_reasons` says why); empty for a family of minimal parameters."""
        ...

    @property
    def rank_bound(self) -> int | None:
        """The most free parameters any rows can identify, where the family's theory
        bounds it below its free count (an over-complete spatial arm as loaded, before
        :meth:`prepared`); None where it does not.  A model with more free parameters is
        known to need preparing without a rank analysis."""
        ...

    def identifiability(self, conditions: Conditions) -> tuple[Identifiability, ScaledSVD]:
        """Rank analysis of the model's scaled, whitened Jacobian at the nominal arm."""
        ...

    def check_identifiable(self, conditions: Conditions) -> Identifiability:
        """:meth:`identifiability`, raising NotIdentifiableError (with why) when rank deficient."""
        ...

    def covariance_factor(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """``G`` ``(..., p, p_f)`` with ``(J_w^T J_w)^-1 = G G^T`` and the full-rank mask.

        ``J_w`` the whitened free columns at ``params`` (nominal when omitted);
        zero rows for fixed parameters, ``inf`` where not identifiable.
        """
        ...


class PlausibilityRole(Protocol):
    """What a calibration's size and the data's reach should be: a deviation far
    beyond its bound or a point beyond the reach says the robot file or the units are
    wrong."""

    @property
    def reach_mm(self) -> float:
        """A length scale of the arm (its stretched reach), for tolerances, mm."""
        ...

    @property
    def tip_reach_mm(self) -> float:
        """How far from the base a measured point can lie (mm): the links to the farthest
        target."""
        ...

    @property
    def deviation_bounds(self) -> DeviationBounds:
        """Which parameters are the robot's deviations, and how large one is implausible
        for a calibration (the ``large-deviation`` warning)."""
        ...

    @property
    def base_offset(self) -> bool:
        """Whether the base's place in the instrument's frame is identified."""
        ...

    @property
    def value_limits(self) -> np.ndarray | None:
        """``(n, 2)`` limits of the joint values ``u = M q`` that the arm's description sets
        (a URDF's ``<limit>``), beyond those of the readings; None where only the readings
        are limited."""
        ...


class DesignRole(Protocol):
    """The design view: which poses a plan may hold and what a plan tells."""

    def plan_conditions(self, q: np.ndarray, loads: Loads | None = None) -> Conditions:
        """The rows a plan of poses ``q`` ``(m, n)`` is measured in: every target of every pose."""
        ...

    @property
    def design_effort(self) -> DesignEffort:
        """How hard the plan optimizer and the certificate search for this family."""
        ...

    def feasible(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Mask ``(..., m)`` of poses within the joint limits and the instrument's view."""
        ...

    @property
    def has_view(self) -> bool:
        """Whether the instrument's view constrains the poses (:meth:`view_constraints`)."""
        ...

    def view_constraints(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The instrument's view as smooth constraints of poses ``q`` ``(..., m, n)``:
        values ``g`` ``(..., m, k)`` (>= 0 inside) and ``dg/dq`` ``(..., m, k, n)``; None
        when every pose within the limits is seen."""
        ...

    @property
    def rotation_invariant(self) -> bool:
        """Whether turning joint 1 leaves every pose's information unchanged."""
        ...

    @property
    def information_bound(self) -> bool:
        """Whether every pose's information has trace ``p_f``, so that every design has
        ``det M <= 1`` with equality iff ``M = I`` (the criteria are then efficiencies)."""
        ...

    @property
    def constrained(self) -> bool:
        """Whether a pose is measured only where the tool meets the instrument (touches a
        plane, sits in a point, lies within a distance's range): plans are then made of
        poses moved there (:meth:`meeting_poses`), not of any pose within the limits."""
        ...

    @property
    def feature_labels(self) -> tuple[str, ...]:
        """The features of the instrument rows touch (:attr:`Conditions.feature` indexes
        them: planes, fixed points), empty for one that sees the tool anywhere."""
        ...

    @property
    def reading_unit(self) -> str:
        """The unit of what a row reads and of its noise: ``"mm"``; a camera's ``"px"``."""
        ...

    def turn_rows(self, conditions: Conditions) -> np.ndarray | None:
        """Which rows read an angle (rad, shown in degrees) rather than
        :attr:`reading_unit`'s (partial coordinates' turns) ``(m,)``; None where none can."""
        ...

    @property
    def reads_turns(self) -> bool:
        """Whether some of a plan's rows read an angle (:meth:`turn_rows`): a report names
        the turns' sigma beside the coordinates'."""
        ...

    @property
    def touches(self) -> bool:
        """Whether a row reports only that the tool meets the instrument (a touch of a
        plane, a seating in a point): its reading is 0 by definition, and its noise is in
        where the arm stopped, so virtual rows carry it in their joint readings
        (:meth:`meeting_poses` with ``miss``)."""
        ...

    def meeting_poses(
        self,
        q: np.ndarray,
        params: np.ndarray | None = None,
        miss: np.ndarray | None = None,
        feature: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The poses of ``q`` ``(m, n)`` moved to meet the instrument at ``params``
        (default nominal): each to the nearest touch or seat of the feature it is nearest
        to, by the smallest joint change; and which of them do (boolean ``(m,)``: met,
        within the limits).  ``miss`` ``(m, d)``: where the instrument's miss is that
        instead of 0 (a touch off the plane by its noise); ``feature`` ``(m,)``: the
        feature each is moved onto instead of its nearest at the nominal parameters (a
        virtual lab's touch of the plane the plan meant).  An instrument that sees the
        tool anywhere (a tracker) leaves them, every one met.
        """
        ...

    def plan_information(
        self, q: np.ndarray, loads: Loads | None = None, *, rows: Conditions | None = None
    ) -> PlanInformation:
        """What plans ``q`` ``(..., m, n)`` (with ``loads``) tell about the free parameters;
        ``rows``, one plan's :meth:`plan_conditions` made already, shares what is memoized
        on them (a spatial arm's triangle from :meth:`prepared`)."""
        ...

    def closed_form_plans(self, m: int) -> ClosedFormPlans | None:
        """The family's closed-form ``m``-pose plans, None for a family without them."""
        ...

    def paper_criteria(self, q: np.ndarray) -> PaperCriteria | None:
        """The paper's D* and Table I sums of plan ``q``, None outside the paper's theory."""
        ...

    def design_loads(self, payloads: Sequence[float] | None) -> tuple[FitModel, np.ndarray] | None:
        """The model a design that chooses every pose's payload identifies, and the payloads
        (kg) it may choose (``payloads``, else the family's default); None where loads do
        not move the points."""
        ...


class EffectRole(Protocol):
    """An effect around an arm (joint compliance): its nested model, its loads and
    gravity; a rigid arm has none."""

    @property
    def nested(self) -> FitModel | None:
        """The model without its extra effect (the geometry without compliance), or None.

        A fit starts from the nested model's (:meth:`lift`), and a fit whose effect
        lowers the residual no more than noise would is said to be unseen.
        """
        ...

    @property
    def effect(self) -> Effect | None:
        """What the model adds to :attr:`nested`, in words; None without a nested model."""
        ...

    def lift(self, nested_params: np.ndarray) -> np.ndarray:
        """Parameters ``(..., p)``: the nested model's ``(..., p_nested)``, then the effect's at 0.

        The nested model's parameters are the first ``p_nested`` of the model's.
        """
        ...

    @property
    def default_payload_kg(self) -> float | None:
        """The payload (kg) of a row that gives none; None when loads do not move the points."""
        ...

    def unpredicted_loads(self, loads: Loads) -> UnpredictedLoads | None:
        """What of ``loads`` this model cannot predict; None when it predicts all.

        A calibration is applied (validation, compensation) under other loads than
        it was identified under; a model that saw one payload only and merged it
        into other parameters says so here, and the caller warns.
        """
        ...

    @property
    def uses_gravity(self) -> bool:
        """Whether the model's points depend on gravity's direction (joint compliance)."""
        ...

    def with_gravity(self, gravity: np.ndarray | None) -> FitModel:
        """The same model with gravity (m/s^2) in the frame of the measurements."""
        ...

    def alone(
        self, params: np.ndarray, covariance: np.ndarray
    ) -> tuple[FitModel, np.ndarray, np.ndarray]:
        """The arm measured, its parameters and their covariance, without what an
        instrument that does not see it whole adds (a plane's, a fixed point's, a
        distance's parameters: :mod:`~armcal.models.instrumented`): what compensation
        corrects and an export writes.  A model measured by a tracker is itself."""
        ...

    def in_robot_frame(self, params: np.ndarray) -> tuple[FitModel, np.ndarray]:
        """The model and parameters in the robot's own frame: the instrument's pose taken out.

        The instrument parameters become 0, and whatever the model states in the
        instrument's frame (gravity) is turned into the robot's.
        """
        ...

    def arm_params(self, params: np.ndarray) -> np.ndarray:
        """The parameters of :attr:`arm` within ``params`` ``(..., p)``."""
        ...


class ToolRole(Protocol):
    """The tool's orientation, for a 6-DoF instrument and compensation."""

    @property
    def orientation_dim(self) -> int:
        """Orientation coordinates of the tool: 1 in the plane, 3 in space."""
        ...

    @property
    def angle_scale_mm(self) -> float:
        """The distance (mm) at which a tool angle is counted as an arc, against positions."""
        ...

    def orientation(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """The tool's orientation ``(..., m, k)`` (rad) at every row."""
        ...

    def orientation_turn(
        self, conditions: Conditions, params: np.ndarray | None, reference: np.ndarray
    ) -> np.ndarray:
        """The small turn ``(..., m, k)`` (rad) from ``reference`` (orientations as
        :meth:`orientation` gives them) to the tool's orientation at every row: what the
        two orientation Jacobians below differentiate."""
        ...

    def orientation_joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``d orientation / d q`` ``(..., m, k, n)``."""
        ...

    def orientation_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``d orientation / d params`` ``(..., m, k, p)``."""
        ...


class FitModel(
    Core,
    ClosedFormRole,
    IdentifiabilityRole,
    PlausibilityRole,
    DesignRole,
    EffectRole,
    ToolRole,
    Protocol,
):
    """A family of arm as identification, design, simulation and validation see it.

    The required :class:`Core` and the optional roles, each with one default
    implementation in :class:`~armcal.models.core.CoreModel`: closed form,
    identifiability, plausibility, design, effect, tool.  Parameters are ``(p,)`` in
    internal units (mm, rad, and the family's own for other effects); every method is
    batched over leading axes of ``params``.  See the module notes for what each role
    is for.
    """


def position_jacobian(
    model: FitModel, conditions: Conditions, params: np.ndarray | None = None
) -> np.ndarray:
    """The rows of ``model.jacobian`` that are positions ``(..., m, position_dim, p)`` (mm
    per internal unit): what a predicted position error is made of, without a 6-DoF
    instrument's orientation rows (rad)."""
    return model.jacobian(conditions, params)[..., : model.position_dim, :]


def columns_jacobian(
    model: FitModel, conditions: Conditions, params: np.ndarray | None, columns: np.ndarray
) -> np.ndarray:
    """``model.jacobian(conditions, params)[..., columns]`` (``columns`` boolean ``(p,)``),
    from the family's own ``columns_jacobian`` where it has one and makes those columns
    for less than the whole Jacobian (the spatial arm: its instrument's columns, what
    registering the nominal arm fits), returning None for columns it does not; every
    other family's whole Jacobian, sliced."""
    own = getattr(model, "columns_jacobian", None)
    found = None if own is None else own(conditions, params, columns)
    return model.jacobian(conditions, params)[..., columns] if found is None else found


def equations_per_pose(model: FitModel) -> int:
    """Equations one pose measured at every target gives: ``point_dim`` per row of a
    plan's pose (a row per target; per axis or corner an instrument reads at every pose)."""
    rows = model.plan_conditions(np.zeros((1, model.n_joints))).m
    return model.point_dim * max(len(model.target_labels), rows, 1)


def target_indices(
    target: ArrayLike | None, labels: Sequence[str], m: int, *, what: str = "target"
) -> np.ndarray | None:
    """Every row's target index ``(m,)`` from ``target``, checked: the labels of
    ``labels`` looked up, indices as they are; None stays None.  ``what`` names them in
    errors (an instrument's ``feature``).

    What the families' :meth:`FitModel.conditions` take, so that a Python user gives the
    labels a measurement file has, where the command line derives the indices.  A
    model with one target (``labels`` empty or one) takes index 0.

    Raises
    ------
    ArmcalError
        For a label that is not one of ``labels`` (naming them), or indices that are
        not ``m`` integers in ``0..k-1``.

    Examples
    --------
    >>> target_indices(["B", "A", "B"], ("A", "B"), 3).tolist()
    [1, 0, 1]
    >>> target_indices(np.array([1, 0]), ("A", "B"), 2).tolist()
    [1, 0]
    """
    if target is None:
        return None
    given = np.asarray(target)
    count = max(len(labels), 1)
    if given.dtype.kind in "USO":
        lookup = {label: i for i, label in enumerate(labels)}
        texts = [str(label) for label in given.reshape(-1)]
        unknown = sorted(set(texts) - lookup.keys())
        if unknown:
            known = ", ".join(labels) if labels else "none"
            raise ArmcalError(
                f"unknown {what} {', '.join(map(repr, unknown))}; the model's {what}s are {known}"
            )
        given = np.array([lookup[text] for text in texts], dtype=int).reshape(given.shape)
    if given.shape != (m,) or not np.issubdtype(given.dtype, np.integer):
        raise ArmcalError(
            f"{what} must hold {m} {what} labels or integer indices, got shape {given.shape}"
        )
    if given.size and (given.min() < 0 or given.max() >= count):
        raise ArmcalError(f"{what} indices must lie in 0..{count - 1}")
    return given


def refuse_feature(name: str, feature: ArrayLike | None) -> None:
    """ArmcalError where rows of a model measured by a tracker (or a probe) name features:
    only an instrument with features (:mod:`armcal.instruments`) has them."""
    if feature is not None:
        raise ArmcalError(
            f"{name} is measured by a tracker, whose rows touch no feature: give no feature"
        )


def targets_missing(name: str, labels: Sequence[str]) -> ArmcalError:
    """The error for rows of a model with several targets given without theirs."""
    return ArmcalError(
        f"{name} has {len(labels)} targets ({', '.join(labels)}): give every row's target "
        f"with {action('target')} (its label or its index); every target of every pose is "
        "the rows of model.plan_conditions(q)"
    )
