"""The paper's reproduction and the studies that ``fohw reproduce`` runs.

Everything here uses the rest of fohw; nothing else in fohw imports it.
"""
