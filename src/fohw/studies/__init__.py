"""Longer studies shipped with fohw: ``fohw reproduce robot-arm`` and ``fohw reproduce accuracy``.

Also runnable as ``examples/robot_arm.py`` and ``examples/accuracy_vs_crb.py``.
"""
