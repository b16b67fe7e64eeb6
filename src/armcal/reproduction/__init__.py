"""The paper recomputed: Tables I-III, Figures 1-2, every printed equation, and where it differs.

Everything is computed from the model -- plans from :mod:`armcal.doe`,
accuracies from :mod:`armcal.criteria`, simulations from
:mod:`armcal.simulate`, equations from central differences of the printed
model.  The paper's printed numbers (:mod:`armcal.paper`) appear only in the
``paper_value`` column and in the comparison, never as a result.

* :mod:`~armcal.reproduction.compute` -- :func:`reproduce`: the tables, the
  data of the figures and the disagreements with the paper's tables and text;
* :mod:`~armcal.reproduction.equations` -- every printed equation of
  Sections II-V computed and compared (:func:`check_equations`);
* :mod:`~armcal.reproduction.catalogue` -- the words: where, what the paper
  says and why it differs, as data filled with the computed numbers.

:mod:`armcal.report` turns a :class:`Reproduction` into the files of
``armcal reproduce``; :mod:`armcal.plotting` draws the figures.
"""

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from .catalogue import Disagreement, EquationCheck
    from .compute import TABLE_COLUMNS, Reproduction, reproduce
    from .equations import check_equations

# Out of mypy's sight: it sees the names imported above, and still flags a misspelt one.
if not TYPE_CHECKING:
    __getattr__, __dir__ = exports(
        __name__,
        {
            ".catalogue": ("Disagreement", "EquationCheck"),
            ".compute": ("TABLE_COLUMNS", "Reproduction", "reproduce"),
            ".equations": ("check_equations",),
        },
    )

__all__ = [
    "TABLE_COLUMNS",
    "Disagreement",
    "EquationCheck",
    "Reproduction",
    "check_equations",
    "reproduce",
]
