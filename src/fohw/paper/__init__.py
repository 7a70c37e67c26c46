"""The paper's reproduction and the studies that ``fohw reproduce`` runs.

Everything here uses the rest of fohw; only the command line (:mod:`fohw.cli`) imports it, and
``import fohw`` does not load it.
"""
