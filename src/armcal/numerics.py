"""The one rank and conditioning policy of armcal, and the factorizations it rests on.

Whether a plan can identify the parameters, the covariance of the estimates,
every efficiency and observability index, the D-efficiency certificate and
every Gauss-Newton step are decided from the singular values ``s_1 >= ... >= s_p``
of a Jacobian **with unit-norm columns** (columns in mm/mm and mm/rad are not
comparable until scaled).  This module holds that policy:

* :data:`RANK_RTOL` -- a direction whose relative singular value ``s_i / s_1``
  is at or below it is not identifiable: the plan is singular, efficiencies are
  0 and standard errors infinite, and armcal raises
  :class:`~armcal.errors.NotIdentifiableError` where it needs the inverse;
* :data:`COND_WARN` -- above this condition number ``s_1 / s_p`` results are
  computed but carry an ``ill-conditioned`` warning.

**Thin factorizations only.**  A matrix with ``r`` rows and ``p`` columns
(``r = 2m`` equations) is reduced by a thin QR to its ``p x p`` triangular
factor ``R``, which has the same singular values and right singular vectors;
the SVD is then taken of ``R``.  Memory is ``O(r p)``; no ``r x r`` matrix is
ever formed.  When ``r < p`` the matrix itself is small and its full SVD gives
the null space.  No normal matrix ``J^T J`` is factored, so accuracy degrades
with ``cond(J)``, not ``cond(J)^2``.  Nothing here raises
:class:`numpy.linalg.LinAlgError`: inputs are checked to be finite, and
singular cases are decided by the policy, never by a failing factorization.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .errors import ArmcalError

__all__ = [
    "COND_WARN",
    "RANK_RTOL",
    "LinearLeastSquares",
    "RowTriangle",
    "ScaledSVD",
    "box_image",
    "factor_least_squares",
    "gram_of_factor",
    "log_det",
    "nearest_in",
    "point_norms",
    "rms",
    "scaled_svd",
    "solve_least_squares",
    "spd_inverse",
    "steps_settled",
    "wrap_angle",
]


#: Relative singular value ``s_i / s_1`` of the column-scaled Jacobian at or below
#: which a direction in parameter space is not identifiable.  Such a plan would
#: give that combination a standard error more than 1e10 times the best-case one,
#: and round-off in double precision (``eps = 2.2e-16``) would corrupt its
#: estimate by more than ``1e10 eps ~ 2e-6`` of the parameter scale.
RANK_RTOL = 1e-10

#: Condition number ``s_1 / s_p`` of the column-scaled Jacobian above which a result
#: carries an ``ill-conditioned`` warning.
#:
#: Why 1e4.  With unit-norm columns ``sum s_i^2 = p`` and every ``s_i = 1`` for an
#: orthogonal plan (paper eq. 21-24), so ``1 <= s_1 <= sqrt(p)`` and the worst-
#: determined combination of the scaled parameters has a standard error
#: ``sigma / s_p`` between ``cond / sqrt(p)`` and ``cond`` times an orthogonal
#: plan's: the condition number bounds, within ``sqrt(p)``, how much worse the
#: plan is than the optimum in its worst direction.  At 1e4 matching that
#: direction's precision would take at least ``1e8 / p`` times more poses; random
#: plans never come close (the worst of 2000 random 4-pose plans of the paper's
#: 4-link arm has cond ~ 800, plans of 8 or more poses stay below 10).  The same
#: number is where round-off starts to matter: a backward-stable least-squares
#: solve errs by about ``cond * eps`` of the parameter scale (the reach,
#: ~1e3 mm), and ``1e4 * 2.2e-16 * 1e3 mm = 2e-9 mm`` reaches the 1e-9 mm
#: recovery promised for noiseless data.
COND_WARN = 1e4


def _check_finite(matrix: np.ndarray) -> None:
    if not np.all(np.isfinite(matrix)):
        raise ArmcalError(
            "a Jacobian has non-finite entries; joint angles and deviations must be finite"
        )


def _triangular_factor(scaled: np.ndarray) -> np.ndarray:
    """``R`` ``(..., min(r, p), p)`` with ``R^T R = A^T A`` for ``A`` ``(..., r, p)``.

    A thin QR when ``r > p`` (memory ``O(r p)``); the matrix itself otherwise.
    """
    r, p = scaled.shape[-2:]
    if r <= p:
        return scaled
    triangle: np.ndarray = np.linalg.qr(scaled, mode="r")  # type: ignore[assignment]
    return triangle


def _padded(values: np.ndarray, p: int) -> np.ndarray:
    missing = p - values.shape[-1]
    if missing == 0:
        return values
    return np.concatenate([values, np.zeros((*values.shape[:-1], missing))], axis=-1)


@dataclass(frozen=True, eq=False)
class ScaledSVD:
    """Singular values and right singular vectors of a matrix with unit-norm columns.

    For ``A`` ``(..., r, p)`` with column norms ``c`` the scaled matrix is
    ``A diag(1 / c)`` (zero columns are left as they are) and
    ``A diag(1 / c) = U diag(s) V^T``.

    Attributes
    ----------
    singular_values : ndarray, shape (..., p)
        ``s`` in descending order, padded with zeros when ``r < p``.
    vt : ndarray, shape (..., p, p)
        Rows are the right singular vectors ``V^T`` in the scaled coordinates
        ``c * x``; row ``i`` belongs to ``s_i``.
    column_norms : ndarray, shape (..., p)
        ``c`` (1 for zero columns).
    """

    singular_values: np.ndarray
    vt: np.ndarray
    column_norms: np.ndarray

    @property
    def relative(self) -> np.ndarray:
        """``s_i / s_1`` ``(..., p)`` (0 for a zero matrix)."""
        s = self.singular_values
        top = s[..., :1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(top > 0, s / np.where(top > 0, top, 1.0), 0.0)

    @property
    def kept(self) -> np.ndarray:
        """Boolean ``(..., p)``: directions the policy counts as identifiable."""
        return self.relative > RANK_RTOL

    @property
    def rank(self) -> np.ndarray:
        """Numerical rank ``(...)``: singular values above ``RANK_RTOL`` times the largest."""
        return np.sum(self.kept, axis=-1)

    @property
    def full_rank(self) -> np.ndarray:
        """Boolean ``(...)``: every direction identifiable."""
        return self.rank == self.singular_values.shape[-1]

    @property
    def truncated(self) -> np.ndarray:
        """Singular values ``(..., p)`` with those the policy calls zero set to 0."""
        return np.where(self.kept, self.singular_values, 0.0)

    @property
    def condition_number(self) -> np.ndarray:
        """``s_1 / s_p`` ``(...)``; inf when ``s_p = 0``."""
        s = self.singular_values
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(
                s[..., -1] > 0, s[..., 0] / np.where(s[..., -1] > 0, s[..., -1], 1), np.inf
            )

    def inverse_gram_factor(self) -> tuple[np.ndarray, np.ndarray]:
        """``G`` ``(..., p, p)`` with ``(A^T A)^-1 = G G^T``, and the full-rank mask ``(...)``.

        ``G = diag(1 / c) V diag(1 / s)``; computed from ``s`` and ``V`` (never
        by inverting ``A^T A``), so its relative accuracy is ``cond(A) eps``.
        Where the policy calls the matrix singular ``G`` is ``inf``.
        """
        ok = self.full_rank
        safe = np.where(ok[..., None], self.singular_values, 1.0)
        factor = (
            np.swapaxes(self.vt, -1, -2) / safe[..., None, :] / self.column_norms[..., :, None]
        )
        return np.where(ok[..., None, None], factor, np.inf), ok

    def inverse_gram(self) -> tuple[np.ndarray, np.ndarray]:
        """``(A^T A)^-1`` ``(..., p, p)`` (``inf`` where singular) and the full-rank mask."""
        factor, ok = self.inverse_gram_factor()
        return gram_of_factor(factor, ok), ok

    def log_det_gram(self) -> np.ndarray:
        """``log det(A^T A)`` ``(...)`` from the singular values; ``-inf`` where singular."""
        s = self.truncated
        with np.errstate(divide="ignore"):
            return 2.0 * np.sum(np.log(s), axis=-1) + 2.0 * np.sum(
                np.log(self.column_norms), axis=-1
            )

    def directions(self, rtol: float) -> np.ndarray:
        """Right singular vectors ``(k, p)`` with ``s_i / s_1 <= rtol``, in unscaled coordinates.

        ``rtol = RANK_RTOL`` gives a basis of the null space as the policy sees
        it; ``1 / COND_WARN`` adds the poorly determined directions.  Unbatched.
        """
        if self.vt.ndim != 2:
            raise ValueError("directions() needs a single matrix, not a stack")
        return self.vt[self.relative <= rtol] / self.column_norms


def scaled_svd(matrix: np.ndarray) -> ScaledSVD:
    """SVD of ``matrix`` ``(..., r, p)`` after scaling its columns to unit norm.

    Parameters
    ----------
    matrix : ndarray, shape (..., r, p)
        E.g. a Jacobian (rows: equations, columns: parameters); leading axes batch.

    Returns
    -------
    ScaledSVD

    Raises
    ------
    ArmcalError
        If ``matrix`` has a non-finite entry.

    Notes
    -----
    A thin QR reduces the matrix to its ``p x p`` triangle first (memory
    ``O(r p)``, no ``r x r`` factor); the SVD of that triangle has the same
    singular values and right singular vectors.

    Examples
    --------
    >>> svd = scaled_svd(np.array([[1.0, 0.0], [0.0, 1e-3], [0.0, 0.0]]))
    >>> svd.singular_values.tolist(), bool(svd.full_rank)
    ([1.0, 1.0], True)
    >>> bool(scaled_svd(np.array([[1.0, 2.0], [2.0, 4.0]])).full_rank)
    False
    """
    matrix = np.asarray(matrix, dtype=float)
    _check_finite(matrix)
    p = matrix.shape[-1]
    norms = np.linalg.norm(matrix, axis=-2)
    norms = np.where(norms > 0, norms, 1.0)
    factor = _triangular_factor(matrix / norms[..., None, :])
    if factor.shape[-2] == 0:
        shape = factor.shape[:-2]
        return ScaledSVD(np.zeros((*shape, p)), np.broadcast_to(np.eye(p), (*shape, p, p)), norms)
    _, s, vt = np.linalg.svd(factor, full_matrices=True)
    return ScaledSVD(_padded(s, p), vt, norms)


@dataclass(frozen=True, eq=False)
class LinearLeastSquares:
    """A thin factorization of one matrix ``A`` ``(r, p)`` for least squares, many right sides.

    ``A diag(1 / c) = Q U diag(s) V^T`` with ``Q`` ``(r, k)`` orthonormal columns
    (``k = min(r, p)``) and the SVD of the triangular factor.

    Attributes
    ----------
    basis : ndarray, shape (r, k)
        ``Q``.
    left : ndarray, shape (k, k)
        ``U``.
    svd : ScaledSVD
        ``s``, ``V^T`` and the column norms ``c``: the policy's view of ``A``.
    """

    basis: np.ndarray
    left: np.ndarray
    svd: ScaledSVD

    def project(self, rhs: np.ndarray) -> np.ndarray:
        """``Q^T b`` ``(..., k)`` for right-hand sides ``b`` ``(..., r)``."""
        return rhs @ self.basis

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Least-squares solutions ``(..., p)`` of ``A x = b`` for ``b`` ``(..., r)``.

        Directions the policy calls unidentifiable are left out (minimum norm
        in the scaled coordinates), so nothing is divided by a round-off-sized
        singular value.
        """
        s = self.svd.singular_values
        k = self.left.shape[0]
        kept = self.svd.kept[:k]
        inverse = np.where(kept, 1.0 / np.where(kept, s[:k], 1.0), 0.0)
        scaled = ((self.project(rhs) @ self.left) * inverse) @ self.svd.vt[:k]
        return scaled / self.svd.column_norms


def factor_least_squares(matrix: np.ndarray) -> LinearLeastSquares:
    """Thin QR, then SVD of the triangle, of one matrix ``(r, p)`` with unit-norm columns.

    Memory ``O(r p)``.  See :class:`LinearLeastSquares`.

    Raises
    ------
    ArmcalError
        If ``matrix`` has a non-finite entry.

    Examples
    --------
    >>> a = np.array([[1.0, 0.0], [1.0, 1.0], [1.0, 2.0]])
    >>> factor_least_squares(a).solve(np.array([1.0, 3.0, 5.0])).round(12).tolist()
    [1.0, 2.0]
    """
    matrix = np.asarray(matrix, dtype=float)
    if matrix.ndim != 2:
        raise ValueError(f"factor_least_squares needs one (r, p) matrix, got {matrix.shape}")
    _check_finite(matrix)
    p = matrix.shape[1]
    norms = np.linalg.norm(matrix, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    basis, triangle = _thin_qr(matrix, norms)
    left, s, vt = np.linalg.svd(triangle, full_matrices=True)
    return LinearLeastSquares(basis, left, ScaledSVD(_padded(s, p), vt, norms))


#: Rows of a block of the tall-skinny QR (:func:`_thin_qr`).
QR_BLOCK_ROWS = 1 << 15


def _thin_qr(matrix: np.ndarray, norms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Thin QR of ``matrix / norms`` ``(r, p)``, block of rows by block (TSQR).

    Every block ``A_i = Q_i R_i``, then the QR of the stacked triangles
    ``[R_1; R_2; ...] = Q' R`` gives ``R`` and ``Q = diag(Q_i) Q'``: as stable
    as one Householder QR, but beside its result it holds one block, not the
    copies of the whole matrix NumPy's QR makes (4 of them at 10^5 rows: the
    largest arrays of an identification).
    """
    r, p = matrix.shape
    if r <= 2 * QR_BLOCK_ROWS or r <= 2 * p:
        return np.linalg.qr(matrix / norms, mode="reduced")
    starts = list(range(0, r - QR_BLOCK_ROWS, QR_BLOCK_ROWS))  # the last block is the longest
    blocks = [slice(a, b) for a, b in zip(starts, [*starts[1:], r], strict=True)]
    basis = np.empty((r, p))
    triangles = []
    for rows in blocks:
        basis[rows], triangle = np.linalg.qr(matrix[rows] / norms, mode="reduced")
        triangles.append(triangle)
    mixing, triangle = np.linalg.qr(np.concatenate(triangles), mode="reduced")
    for i, rows in enumerate(blocks):
        basis[rows] = basis[rows] @ mixing[i * p : (i + 1) * p]
    return basis, triangle


#: Rows of a block that :class:`RowTriangle` reduces at once: a block this tall (of a few
#: tens of columns) stays in the processor's cache, where LAPACK's QR of the whole matrix
#: streams it from memory several times (4-8x faster at 10^5 rows, measured).
TRIANGLE_BLOCK_ROWS = 4096

#: Rows up to which a matrix given in one piece is factored whole, its columns scaled
#: first (as :func:`scaled_svd` does): small systems are solved exactly as they always
#: were, to the last bit.
WHOLE_ROWS = 1 << 15


class RowTriangle:
    """Least squares ``A x = b`` (stacks of them) from row blocks of ``[A | b]``, as they come.

    Every block is reduced with the triangle so far (a QR of the two stacked,
    ``R`` only: tall-skinny QR), so what is kept is ``O(p^2)`` per system however many
    rows: the triangle ``R`` of ``A`` (``R^T R = A^T A``, the same singular values and
    right singular vectors), ``Q^T b`` beside it, and the column norms of ``A``.  No
    ``Q`` is formed.  Householder QR's backward error is small column by column, so
    scaling the columns to unit norm after the QR rather than before gives the same
    result to round-off.  A matrix of at most :data:`WHOLE_ROWS` rows given in one
    piece is kept and factored whole, its columns scaled first.

    Parameters
    ----------
    columns : int
        ``p``, the columns of ``A``.
    sides : int, optional
        ``K`` right-hand sides of one ``A`` (``rhs`` ``(..., r, K)``, solutions
        ``(..., K, p)``): sets of data that share their rows' Jacobian, one
        factorization for them all.  Default one (``rhs`` ``(..., r)``).

    Examples
    --------
    >>> rows = RowTriangle(2)
    >>> rows.add(np.array([[1.0, 0.0], [1.0, 1.0]]), np.array([1.0, 3.0]))
    >>> rows.add(np.array([[1.0, 2.0]]), np.array([5.0]))
    >>> x, ok, _ = rows.solve()
    >>> x.round(12).tolist(), bool(ok)
    ([1.0, 2.0], True)
    """

    def __init__(self, columns: int, sides: int | None = None) -> None:
        self.columns = columns
        self.sides = sides
        self._whole: tuple[np.ndarray, np.ndarray] | None = None
        self._triangle: np.ndarray | None = None
        self._squares: np.ndarray | None = None

    def add(self, matrix: np.ndarray, rhs: np.ndarray | None = None) -> None:
        """Rows ``matrix`` ``(..., r, p)`` of ``A`` and ``rhs`` ``(..., r)`` of ``b``
        (``(..., r, K)`` with ``sides``; 0 when None).  Raises
        :class:`~armcal.errors.ArmcalError` for non-finite entries."""
        matrix = np.asarray(matrix, dtype=float)
        _check_finite(matrix)
        sides = 1 if self.sides is None else self.sides
        if rhs is None:
            right = np.zeros((*matrix.shape[:-1], sides))
        else:
            right = np.asarray(rhs, dtype=float)
            right = right[..., None] if self.sides is None else right
        _check_finite(right)
        if self._triangle is None and self._whole is None and matrix.shape[-2] <= WHOLE_ROWS:
            self._whole = (matrix, right)
            return
        if self._whole is not None:
            whole, self._whole = self._whole, None
            self._reduce(*whole)
        self._reduce(matrix, right)

    def _reduce(self, matrix: np.ndarray, right: np.ndarray) -> None:
        squares = np.einsum("...rp,...rp->...p", matrix, matrix)
        self._squares = squares if self._squares is None else self._squares + squares
        for start in range(0, matrix.shape[-2], TRIANGLE_BLOCK_ROWS):
            rows = slice(start, start + TRIANGLE_BLOCK_ROWS)
            block = np.concatenate([matrix[..., rows, :], right[..., rows, :]], axis=-1)
            if self._triangle is not None:
                block = np.concatenate([self._triangle, block], axis=-2)
            self._triangle = _r_only(block, self.columns)

    def _parts(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``R`` ``(..., k, p)`` (``k = min(rows, p)``), ``Q^T b`` ``(..., k, K)`` and the
        column norms ``(..., p)`` (1 for a zero column)."""
        if self._triangle is None or self._squares is None:
            raise ValueError("no rows were added")
        p = self.columns
        k = min(self._triangle.shape[-2], p)
        norms = np.sqrt(self._squares)
        norms = np.where(norms > 0, norms, 1.0)
        return self._triangle[..., :k, :p], self._triangle[..., :k, p:], norms

    def transformed(self, matrix: np.ndarray) -> RowTriangle:
        """The rows of ``A M`` and ``b``, for ``M`` ``(p, q)``: ``[R M | Q^T b]``, the same
        least squares in ``A M``'s columns (``(A M)^T (A M) = M^T R^T R M``), with no
        pass over the rows again."""
        if self._whole is not None:
            rows, right = self._whole
        else:
            rows, right, _ = self._parts()
        out = RowTriangle(matrix.shape[-1], self.sides)
        out.add(rows @ matrix, right if self.sides is not None else right[..., 0])
        return out

    def triangle(self) -> np.ndarray:
        """A matrix ``(..., k, p)`` with the column space and the column norms of ``A``, for
        :func:`scaled_svd`: ``R`` (``R^T R = A^T A``), or ``A`` itself when it was given
        whole."""
        return self._whole[0] if self._whole is not None else self._parts()[0]

    def svd(self) -> ScaledSVD:
        """The policy's view of ``A`` (:func:`scaled_svd` of the whole matrix, to round-off)."""
        if self._whole is not None:
            return scaled_svd(self._whole[0])
        triangle, _, norms = self._parts()
        _, s, vt = np.linalg.svd(triangle / norms[..., None, :], full_matrices=True)
        return ScaledSVD(_padded(s, self.columns), vt, norms)

    def solve(self) -> tuple[np.ndarray, np.ndarray, ScaledSVD]:
        """What :func:`solve_least_squares` returns for the rows added."""
        p = self.columns
        if self._whole is not None:  # scaled, then a thin QR and Q^T b
            matrix, rhs = self._whole
            norms = np.linalg.norm(matrix, axis=-2)
            norms = np.where(norms > 0, norms, 1.0)
            basis, triangle = np.linalg.qr(matrix / norms[..., None, :], mode="reduced")
            projected = np.einsum("...rk,...rs->...ks", basis, rhs)
            left, s, vt = np.linalg.svd(triangle, full_matrices=True)
        else:
            triangle, projected, norms = self._parts()
            left, s, vt = np.linalg.svd(triangle / norms[..., None, :], full_matrices=True)
        svd = ScaledSVD(_padded(s, p), vt, norms)
        k = triangle.shape[-2]
        kept = svd.kept[..., :k]
        inverse = np.where(kept, 1.0 / np.where(kept, s[..., :k], 1.0), 0.0)
        coeffs = np.einsum("...ks,...kj->...sj", projected, left) * inverse[..., None, :]
        x = np.einsum("...sk,...kp->...sp", coeffs, vt[..., :k, :]) / norms[..., None, :]
        return (x[..., 0, :] if self.sides is None else x), svd.full_rank, svd


def _r_only(block: np.ndarray, p: int) -> np.ndarray:
    """The triangle ``(..., min(r, c), c)`` of a QR of ``block`` ``(..., r, c)`` (``[A | b]``
    with ``p`` columns of ``A``); a block of no more rows than ``A`` has columns is its own
    (its rows are the system itself).  One of more rows is reduced even where the
    right-hand sides make it wider than tall: only its first ``p`` rows are kept."""
    if block.shape[-2] <= p:
        return block
    triangle: np.ndarray = np.linalg.qr(block, mode="r")  # type: ignore[assignment]
    return triangle


def solve_least_squares(
    matrix: np.ndarray, rhs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, ScaledSVD]:
    """Least-squares solutions of a stack of systems ``A x = b``, by the rank policy.

    Parameters
    ----------
    matrix : ndarray, shape (..., r, p)
        One matrix per system (leading axes batch).
    rhs : ndarray, shape (..., r)

    Returns
    -------
    x : ndarray, shape (..., p)
        Minimum-norm solutions in the column-scaled coordinates: directions the
        policy calls unidentifiable are left out.
    full_rank : ndarray of bool, shape (...)
    svd : ScaledSVD
        The policy's view of every matrix.

    Notes
    -----
    The triangle of ``[A | b]`` block of rows by block (:class:`RowTriangle`), then
    the SVD of ``R diag(1 / c)``: memory ``O(p^2)`` beyond the matrix, accuracy
    ``cond(A) eps``.  Raises :class:`~armcal.errors.ArmcalError` for non-finite entries.

    Examples
    --------
    >>> a = np.array([[[1.0, 0.0], [1.0, 1.0], [1.0, 2.0]]])
    >>> x, ok, _ = solve_least_squares(a, np.array([[1.0, 3.0, 5.0]]))
    >>> x.round(12).tolist(), ok.tolist()
    ([[1.0, 2.0]], [True])
    """
    matrix = np.asarray(matrix, dtype=float)
    rows = RowTriangle(matrix.shape[-1])
    rows.add(matrix, rhs)
    return rows.solve()


#: A step at most this fraction of the one before it (Gauss-Newton near its solution,
#: where its steps shrink at least linearly) bounds what the steps after it add up to:
#: ``size * rate / (1 - rate)``, ``rate`` the two steps' ratio.
FAST_RATE = 0.01


def steps_settled(size: ArrayLike, previous: ArrayLike, tol: float) -> np.ndarray:
    """Whether iterations whose step ``size`` followed one of ``previous`` shrank so fast
    (to at most :data:`FAST_RATE` of it) that the steps after it add up to at most
    ``tol``, were the rate to hold.

    Examples
    --------
    >>> steps_settled(np.array([1e-6, 1e-6, 1e-3]), np.array([1e-3, np.inf, 1e-2]), 1e-8)
    array([ True, False, False])
    """
    size, previous = np.asarray(size, dtype=float), np.asarray(previous, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        rate = np.where(np.isfinite(previous) & (previous > 0), size / previous, np.inf)
    return (rate <= FAST_RATE) & (size * rate / (1 - np.minimum(rate, 0.5)) <= tol)


def spd_inverse(matrix: np.ndarray) -> np.ndarray:
    """Inverse ``(..., p, p)`` of symmetric positive definite matrices, without raising.

    For Gram matrices that are positive definite by construction (each caller
    says why).  Computed from :func:`numpy.linalg.eigh`, with eigenvalues floored
    at ``p eps`` times the largest -- the accuracy to which ``eigh`` knows them --
    so round-off that makes a tiny eigenvalue zero or negative gives a huge but
    finite inverse rather than :class:`numpy.linalg.LinAlgError`.

    Raises
    ------
    ArmcalError
        If ``matrix`` has a non-finite entry.

    Examples
    --------
    >>> spd_inverse(np.array([[4.0, 0.0], [0.0, 0.5]])).tolist()
    [[0.25, 0.0], [0.0, 2.0]]
    """
    matrix = np.asarray(matrix, dtype=float)
    if not np.all(np.isfinite(matrix)):
        raise ArmcalError("a Gram matrix has non-finite entries")
    values, vectors = np.linalg.eigh(matrix)
    p = matrix.shape[-1]
    # At least 1e-290, so that even a zero matrix gives a huge but finite inverse.
    floor = np.maximum(p * np.finfo(float).eps * values[..., -1:], 1e-290)
    values = np.maximum(values, floor)
    return (vectors / values[..., None, :]) @ np.swapaxes(vectors, -1, -2)


def rms(values: np.ndarray) -> float:
    """The root mean square of ``values`` (0 for none).

    Of the points' error lengths it is the RMS *per point*; of their coordinates,
    the RMS *per coordinate*, ``1 / sqrt(d)`` of it for isotropic errors in ``d``
    dimensions.  Every RMS armcal reports says which.

    Examples
    --------
    >>> errors = np.array([[3.0, 4.0], [0.0, 0.0]])
    >>> rms(np.hypot(*errors.T)), rms(errors)   # per point, per coordinate
    (3.5355339059327378, 2.5)
    """
    values = np.asarray(values, dtype=float)
    return float(np.sqrt(np.mean(values**2))) if values.size else 0.0


def log_det(matrix: np.ndarray) -> np.ndarray:
    """``log det`` ``(...)`` of (stacks of) symmetric matrices; ``-inf`` where not positive.

    LU-based (:func:`numpy.linalg.slogdet`): never raises for a finite matrix.
    """
    sign, value = np.linalg.slogdet(matrix)
    return np.where(sign > 0, value, -np.inf)


def gram_of_factor(factor: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """``G G^T`` ``(..., p, p)`` of factors ``G`` ``(..., p, k)``, ``inf`` where ``ok`` is
    false: a covariance from its factor (:meth:`ScaledSVD.inverse_gram_factor`)."""
    ok = np.asarray(ok)
    safe = np.where(ok[..., None, None], factor, 0.0)
    return np.where(ok[..., None, None], safe @ np.swapaxes(safe, -1, -2), np.inf)


def point_norms(points: np.ndarray) -> np.ndarray:
    """Euclidean length ``(...)`` of every point ``(..., d)`` (``hypot`` in the plane)."""
    if points.shape[-1] == 2:
        return np.hypot(points[..., 0], points[..., 1])
    return np.linalg.norm(points, axis=-1)


def box_image(matrix: np.ndarray, box: np.ndarray) -> np.ndarray:
    """``[lower, upper]`` ``(k, 2)`` of every ``(A x)_i`` over the box ``box`` ``(n, 2)``.

    Each coordinate of a linear map is a sum of terms ``A_ij x_j``, each at its
    smallest (largest) at one end of ``x_j``'s interval.

    Examples
    --------
    >>> box_image(np.array([[1.0, 1.0], [0.0, -1.0]]), np.array([[-1.0, 2.0], [0.0, 3.0]]))
    array([[-1.,  5.],
           [-3.,  0.]])
    """
    low = matrix * box[:, 0]
    high = matrix * box[:, 1]
    return np.column_stack([np.minimum(low, high).sum(axis=1), np.maximum(low, high).sum(axis=1)])


def nearest_in(a: np.ndarray, b: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The point nearest ``v`` ``(n,)`` of ``{x : a x >= b}`` (``a`` ``(c, n)``): ``v + y`` with
    ``y`` the least-distance solution of ``a y >= b - a v`` from the non-negative least
    squares of ``[a^T; h^T] u ~ e_{n+1}`` (``h = b - a v``), ``y = -r[:n] / r[n]`` of its
    residual ``r`` (Lawson and Hanson, ch. 23); ``v`` where every row holds, and 0 (no
    step) where the linearization has no point at all (not expected: ``x = 0`` holds
    wherever the pose itself is inside)."""
    from scipy.optimize import nnls  # here: scipy's optimizers are slow to import

    h = b - a @ v
    if np.all(h <= 0.0):
        return v
    n = v.size
    e = np.concatenate([a.T, h[None, :]])
    f = np.zeros(n + 1)
    f[n] = 1.0
    u, _ = nnls(e, f, maxiter=50 * e.shape[1])
    r = e @ u - f
    if abs(r[n]) < 1e-12:
        return np.zeros(n)
    return v - r[:n] / r[n]


def wrap_angle(angle: ArrayLike) -> np.ndarray:
    """Wrap angles (rad) into ``(-pi, pi]``.

    Examples
    --------
    >>> wrap_angle(np.array([np.pi, -np.pi, 3 * np.pi / 2])).round(6).tolist()
    [3.141593, 3.141593, -1.570796]
    """
    wrapped = np.mod(np.asarray(angle, dtype=float) + np.pi, 2 * np.pi) - np.pi
    return np.where(wrapped <= -np.pi, wrapped + 2 * np.pi, wrapped)
