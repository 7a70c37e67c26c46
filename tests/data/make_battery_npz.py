"""Write ``src/fohw/data/lg_m50lt_drive_cycle.npz`` from the three MATLAB files of the source.

Usage: ``python tests/data/make_battery_npz.py SOURCE_FOLDER [OUT]`` with SOURCE_FOLDER holding
``drive_cycle_80to20.mat``, ``electrode_ocp.mat`` and ``impedance_and_parameters.mat`` (PyBOP,
``papers/Hallemans et al/Data/LGM50LT/`` at commit d59569520de61c474ecbb5e0cbcb1b161c565055, renamed
as in ``src/fohw/data/README.md``). Every stored value is checked to decode to the source's float64
bit for bit; the zip members carry a fixed date, so the output is byte-reproducible.
"""

import io
import sys
import zipfile
from pathlib import Path

import numpy as np
import scipy.io

ROOT = Path(__file__).resolve().parents[2]


def arrays(folder):
    """The npz members, each checked to decode losslessly."""
    folder = Path(folder)
    drive = scipy.io.loadmat(folder / "drive_cycle_80to20.mat")
    ocp = scipy.io.loadmat(folder / "electrode_ocp.mat")
    imp = scipy.io.loadmat(folder / "impedance_and_parameters.mat")
    t, i, v = (drive[k].ravel() for k in ("t", "i", "v"))
    step = 0.15
    if np.max(np.abs(t - step * np.arange(t.size))) > 1e-9:
        raise SystemExit("the time vector is not uniform at 0.15 s")
    # The current is given to 6 significant decimal digits: an integer mantissa (|m| < 10**6)
    # and a decimal exponent, i = m / 10**(-e), which is the correctly rounded decimal.
    exponent = np.floor(np.log10(np.abs(np.where(i == 0, 1.0, i)))).astype(np.int64) - 5
    mantissa = np.round(i / 10.0 ** exponent)
    if not np.array_equal(mantissa / 10.0 ** (-exponent), i) or np.abs(mantissa).max() >= 1e6:
        raise SystemExit("the current is not 6 significant decimal digits")
    # The voltage is given in steps of 10 microvolts.
    code = np.round(v * 1e5)
    if not np.array_equal(code / 1e5, v):
        raise SystemExit("the voltage is not on a 10 uV grid")
    return {
        "time_step": np.float64(step),
        "current_mantissa": mantissa.astype(np.int32),
        "current_exponent": exponent.astype(np.int8),
        "voltage_10uV": code.astype(np.int32),
        "x_neg": ocp["x_neg"].ravel(), "U_neg": ocp["U_neg"].ravel(),
        "x_pos": ocp["x_pos"].ravel(), "U_pos": ocp["U_pos"].ravel(),
        "thetahat": imp["thetahat"].ravel(),
        "impedance_f": imp["f"].ravel(), "impedance_soc": imp["SOC"].ravel(),
        "impedance_Z": imp["Z"], "impedance_Zhat": imp["Zhat"],
    }


def write(members, out):
    """A compressed npz whose bytes depend on the arrays only (fixed member dates)."""
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=9) as zf:
        for name, value in members.items():
            buf = io.BytesIO()
            np.lib.format.write_array(buf, np.asarray(value), allow_pickle=False)
            info = zipfile.ZipInfo(name + ".npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            zf.writestr(info, buf.getvalue(), compresslevel=9)


if __name__ == "__main__":
    out = sys.argv[2] if len(sys.argv) > 2 else ROOT / "src" / "fohw" / "data" / "lg_m50lt_drive_cycle.npz"
    write(arrays(sys.argv[1]), out)
    print(out)
