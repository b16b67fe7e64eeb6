"""The paper's Sections V-VI recomputed: Tables I-III, Figures 1-2, and where the paper differs.

Everything is computed from the model -- plans from :mod:`armcal.doe`,
accuracies from :mod:`armcal.criteria`, simulations from
:mod:`armcal.simulate`.  The paper's printed numbers (:mod:`armcal.paper`)
appear only in the ``paper_value`` column and in the comparison, never as a
result.

* :mod:`~armcal.reproduction.compute` -- :func:`reproduce`: the tables and the
  data of the figures;
* :mod:`~armcal.reproduction.catalogue` -- the disagreements with the paper:
  what it says, what is computed, and why they differ.

:mod:`armcal.report` turns a :class:`Reproduction` into the files of
``armcal reproduce``; :mod:`armcal.plotting` draws the figures.
"""

from .catalogue import Disagreement
from .compute import TABLE_COLUMNS, Reproduction, reproduce

__all__ = ["TABLE_COLUMNS", "Disagreement", "Reproduction", "reproduce"]
