"""The DaISy flexible robot arm (paper Section 6.2, Figs. 7-9, Table 3) and simulation fits.

    python examples/robot_arm.py --outdir results [--fast] [--data PATH]

The study lives in fohw.paper.robot_arm (also: fohw reproduce robot-arm); see its docstring.
"""

import sys

from fohw.paper.robot_arm import main

if __name__ == "__main__":
    sys.exit(main())
