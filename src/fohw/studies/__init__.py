"""Longer studies shipped with fohw, runnable as ``fohw reproduce robot-arm`` and
``fohw reproduce accuracy`` (and as ``examples/robot_arm.py``, ``examples/accuracy_vs_crb.py``)."""
