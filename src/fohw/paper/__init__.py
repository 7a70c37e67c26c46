"""The paper's reproduction and the studies that ``fohw reproduce`` runs.

Applications on top of fohw: they import the library; nothing in the library imports them. Only the
command line (:mod:`fohw.cli`) imports this package, and ``import fohw`` does not load it.
One study per module, each with its command line ``main``:

* :mod:`~fohw.paper.common` — the paper's printed numbers, its example's structure, CSV text.
* :mod:`~fohw.paper.table2` — Table 2 and Figs. 3–6 (``fohw reproduce table2|figures``).
* :mod:`~fohw.paper.forgetting` — the method under a forgetting factor
  (``fohw reproduce forgetting``).
* :mod:`~fohw.paper.robot_arm` — the real system, Section 6.2 (``fohw reproduce robot-arm``).
* :mod:`~fohw.paper.accuracy` — the estimators against the Cramér–Rao bound
  (``fohw reproduce accuracy``).
"""
