"""Data sets: the paper's example (Section 6.1), the robot arm (6.2), the cascaded tanks, a battery cell.

The measured records ship inside the package (``fohw/data``) with their citations and
checksums; the loaders verify the checksum of the shipped copies always, and of a user's copy
unless ``verify=False``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ._validation import check_int, check_random_state, check_scalar
from .exceptions import DataFileError, ParameterError
from .io.files import check_input_file
from .io.text import parse_number
from .model.lagged.system import HammersteinWiener
from .model.simulate import simulate
from .record import Benchmark, Record

__all__ = ["SimulatedData", "paper_model", "paper_example", "load_daisy",
           "robot_arm", "cascaded_tanks", "SHIPPED", "shipped_file", "BatteryCell",
           "battery_cell", "PulseTest", "pybamm_pulses"]


@dataclass(frozen=True, repr=False)
class SimulatedData:
    """A simulated record with the system that produced it.

    Attributes
    ----------
    u, y, noise : ndarray, shape (N,)
        Input, output and the equation noise ``v`` that was added.
    model : HammersteinWiener
        The true system.
    input_kind : str
        ``"uniform"`` or ``"gaussian"``.
    noise_variance : float
        Variance of ``v``.
    """

    u: np.ndarray
    y: np.ndarray
    noise: np.ndarray
    model: HammersteinWiener
    input_kind: str
    noise_variance: float
    info: dict = field(default_factory=dict)

    @property
    def n_samples(self) -> int:
        """Number of samples ``N``."""
        return self.u.shape[0]

    def __repr__(self):
        return (f"SimulatedData(n_samples={self.n_samples}, input_kind={self.input_kind!r}, "
                f"noise_variance={self.noise_variance:g}, model={self.model!r})")


def paper_model():
    """The academic example's true system (Section 6.1, Eq. 57).

    Returns
    -------
    HammersteinWiener
        ``a = [0.1, 0.2]``, ``b = [-0.4, -0.2]``, ``p = [1, 0.5]``, ``q = [1, 0.7, 0.35]``,
        ``alpha = 0.6``, ``f = [u, u**2]``, ``g = [y, y**2, y**3]``.

    Examples
    --------
    >>> import fohw
    >>> fohw.datasets.paper_model().theta.round(3)
    array([ 0.1  ,  0.2  ,  0.07 ,  0.14 ,  0.035,  0.07 , -0.4  , -0.2  , -0.2  , -0.1  ])
    """
    return HammersteinWiener(a=[0.1, 0.2], b=[-0.4, -0.2], p=[1.0, 0.5], q=[1.0, 0.7, 0.35],
                             alpha=0.6)


def paper_example(n_samples=10_000, *, noise_variance=0.01, input_kind="uniform",
                  random_state=None):
    """Simulate the paper's academic example (Section 6.1).

    Parameters
    ----------
    n_samples : int, optional
        Record length ``N`` (default 10 000, as in the paper).
    noise_variance : float, optional
        Variance of the white Gaussian equation noise (default 0.01, as in the paper).
    input_kind : {"uniform", "gaussian"}, optional
        The paper asks for a "random signal with zero mean and unit variance".
        ``"uniform"`` (default) draws from ``[-sqrt(3), sqrt(3)]``; ``"gaussian"`` from
        ``N(0, 1)``. With Gaussian input the ``y**3`` feedback makes the system escape to
        infinity for most seeds at ``N = 10 000`` (28 of 40 seeds; docs/reproduction.md), which raises
        :class:`fohw.SimulationDivergedError`.
    random_state : None, int or numpy.random.Generator, optional
        The input is drawn first, then the noise, from the same generator.

    Returns
    -------
    SimulatedData

    Examples
    --------
    >>> import fohw
    >>> data = fohw.datasets.paper_example(1000, random_state=0)
    >>> data.u.shape, round(float(data.u.var()), 1)
    ((1000,), 1.0)
    """
    n_samples = check_int(n_samples, "n_samples", minimum=3)
    noise_variance = check_scalar(noise_variance, "noise_variance", lower=0.0)
    if input_kind not in ("uniform", "gaussian"):
        raise ParameterError(f"`input_kind` must be 'uniform' or 'gaussian'; got {input_kind!r}.")
    rng = check_random_state(random_state)
    if input_kind == "uniform":
        u = rng.uniform(-np.sqrt(3.0), np.sqrt(3.0), n_samples)
    else:
        u = rng.standard_normal(n_samples)
    v = np.sqrt(noise_variance) * rng.standard_normal(n_samples)
    model = paper_model()
    y = simulate(model, u, noise=v)
    return SimulatedData(u=u, y=y, noise=v, model=model, input_kind=input_kind,
                         noise_variance=noise_variance)


def load_daisy(path, *, n_columns=None):
    """Read a DaISy-format data file (whitespace-separated numeric columns).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    n_columns : int, optional
        Expected number of columns; by default the first data line decides.

    Returns
    -------
    data : ndarray, shape (n_samples, n_columns)

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    DataFileError
        An empty file, a line that is not all numbers (reported with its 1-based line
        number), a line with another number of columns, or a non-finite value.

    Notes
    -----
    Blank lines and lines starting with ``%`` or ``#`` are skipped (DaISy headers use ``%``).

    Examples
    --------
    >>> import tempfile, os, fohw
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = os.path.join(d, "two.dat")
    ...     with open(path, "w") as fh:
    ...         _ = fh.write("   1.0e-01\\t  -2.0e-01\\t\\n   3.0e-01\\t   4.0e-01\\t\\n")
    ...     fohw.datasets.load_daisy(path)
    array([[ 0.1, -0.2],
           [ 0.3,  0.4]])
    """
    if n_columns is not None:
        n_columns = check_int(n_columns, "n_columns", minimum=1)
    return _parse_daisy(path, n_columns=n_columns)


def _parse_daisy(path, *, n_columns=None):
    """Numeric rows of a DaISy file (ASCII, whitespace-separated, ``%``/``#`` comments).

    Stricter than :func:`fohw.io.text.read_table` (the loader of general CSV and text
    records): no header, no empty fields, every line the same number of columns.
    """
    path = check_input_file(path, "a data file")
    rows = []
    with open(path, "rb") as fh:
        for lineno, raw in enumerate(fh, start=1):
            try:
                text = raw.decode("ascii").strip()
            except UnicodeDecodeError:
                raise DataFileError(f"{path}: line {lineno} is not ASCII text.") from None
            if not text or text[0] in "%#":
                continue
            fields = text.split()
            values = [parse_number(f) for f in fields]
            if None in values:
                bad = fields[values.index(None)]
                raise DataFileError(f"{path}: line {lineno}: {bad!r} is not a number.")
            if n_columns is None:
                n_columns = len(values)
            if len(values) != n_columns:
                raise DataFileError(f"{path}: line {lineno} has {len(values)} column(s); expected "
                                    f"{n_columns}.")
            if not all(np.isfinite(values)):
                raise DataFileError(f"{path}: line {lineno} holds a non-finite value: {text!r}.")
            rows.append(values)
    if not rows:
        raise DataFileError(f"{path}: no data lines found.")
    return np.array(rows, dtype=np.float64)


#: sha256 of the files shipped in ``fohw/data`` (see ``fohw/data/README.md``).
ROBOT_ARM_SHA256 = "4ee167a8a28ce0da868d1b42f6a2fe0c456ea0e56b60c70915bf6d4a2a933635"
ROBOT_ARM_FILENAME = "daisy_robot_arm.dat"
CASCADED_TANKS_SHA256 = "ef2388ed822f3aef4aa80d6b0f2b466dd80b361786b3eafc7a2957c31ea323a7"
CASCADED_TANKS_FILENAME = "cascaded_tanks.csv"

ROBOT_ARM_SOURCE = ("DaISy data set 96-009, 'Data from a flexible robot arm' (KU Leuven); B. De "
                    "Moor, P. De Gersem, B. De Schutter, W. Favoreel, 'DAISY: A database for "
                    "identification of systems', Journal A 38(3), 4-5, 1997.")
CASCADED_TANKS_SOURCE = ("M. Schoukens, P. Mattsson, T. Wigren, J.-P. Noel, 'Cascaded tanks "
                         "benchmark combining soft and hard nonlinearities', Workshop on "
                         "Nonlinear System Identification Benchmarks, Brussels, 2016; M. "
                         "Schoukens, J.-P. Noel, 'Three benchmarks addressing open challenges "
                         "in nonlinear system identification', IFAC World Congress, 2017.")

#: The record files shipped with fohw, by the name ``fohw data NAME`` and ``@NAME`` use:
#: ``{name: (file name, sha256, what it holds)}``.
SHIPPED = {
    "cascaded_tanks": (CASCADED_TANKS_FILENAME, CASCADED_TANKS_SHA256,
                       "the cascaded-tanks benchmark: columns uEst, uVal, yEst, yVal (volts) and "
                       "Ts = 4 s given once; estimate on uEst,yEst, validate on uVal,yVal"),
    "robot_arm": (ROBOT_ARM_FILENAME, ROBOT_ARM_SHA256,
                  "the DaISy 96-009 flexible robot arm: two whitespace columns, reaction torque "
                  "(input) and arm acceleration (output), 1024 samples"),
}


def shipped_file(name):
    """Path of a record file shipped with fohw (``SHIPPED``), its checksum verified.

    Parameters
    ----------
    name : {"cascaded_tanks", "robot_arm"}

    Returns
    -------
    str
        The path inside the installed package (read it, do not write to it).

    Raises
    ------
    ParameterError
        ``name`` is not one of ``SHIPPED``.
    DataFileError
        The installed file's checksum is wrong.

    Examples
    --------
    >>> import fohw
    >>> fohw.read_record(fohw.datasets.shipped_file("cascaded_tanks"), u="uEst", y="yEst").dt
    4.0
    """
    if not isinstance(name, str) or name not in SHIPPED:
        raise ParameterError(f"`name` must be one of {', '.join(SHIPPED)} (the records shipped "
                             f"with fohw); got {name!r}.")
    filename, sha256, _ = SHIPPED[name]
    return _packaged(filename, sha256)



#: The checksum reads at most this many bytes (the largest shipped file has 0.9 MB): a file
#: that is longer, or never ends, is not the published one.
MAX_DATA_BYTES = 64 * 2**20


def _sha256(path, advice):
    """sha256 of a regular file of at most MAX_DATA_BYTES; ``advice`` ends each error."""
    import hashlib

    try:
        check_input_file(path, "a data file")
    except DataFileError as err:
        raise DataFileError(f"{err} {advice}") from None
    digest, size = hashlib.sha256(), 0
    with open(path, "rb") as fh:
        while chunk := fh.read(1 << 20):
            size += len(chunk)
            if size > MAX_DATA_BYTES:
                raise DataFileError(f"{path}: longer than {MAX_DATA_BYTES} bytes (read so far), so "
                                    f"not the published file (a file that never ends?). {advice}")
            digest.update(chunk)
    return digest.hexdigest()


def _data_folder():
    from importlib import resources

    return resources.files("fohw") / "data"


def _packaged(filename, sha256):
    """Path of a data file shipped in ``fohw/data``, its checksum verified."""
    path = str(_data_folder() / filename)
    advice = "The installed fohw is damaged; reinstall it."
    if not os.path.lexists(path):
        raise DataFileError(f"{path}: the data file shipped with fohw is missing. {advice}")
    digest = _sha256(path, advice)
    if digest != sha256:
        raise DataFileError(f"{path}: sha256 {digest} does not match the published {sha256}: "
                            "the installed fohw is damaged; reinstall it.")
    return path


def _given(path, filename, sha256, what, verify):
    """A user's copy (the file, or a folder holding ``filename``), its checksum verified."""
    path = os.fspath(path)
    if os.path.isdir(path):
        path = os.path.join(path, filename)
    if not os.path.exists(path):
        raise FileNotFoundError(f"{what} not found at {path!r}; call the loader without a path "
                                "to use the copy shipped with fohw.")
    advice = "Call the loader without a path to use the copy shipped with fohw."
    if not verify:
        check_input_file(path, what)
    elif (digest := _sha256(path, advice)) != sha256:
        raise DataFileError(f"{path}: sha256 {digest} does not match the published {sha256}; "
                            "the file is corrupted or another file. Call the loader without a "
                            "path to use the copy shipped with fohw, or pass verify=False.")
    return path


def robot_arm(path=None, *, verify=True):
    """The DaISy flexible robot arm record (paper Section 6.2), shipped with fohw.

    Parameters
    ----------
    path : str or os.PathLike, optional
        Another copy to read (the file, or a folder holding ``daisy_robot_arm.dat``). Default:
        the copy shipped inside the package.
    verify : bool, optional
        Check a given file's sha256 against the published one (default True; the shipped copy
        is always checked).

    Returns
    -------
    Record
        ``u`` = reaction torque, ``y`` = arm acceleration, 1024 samples; the source gives no
        sampling time (``dt=None``; use one sample as the unit).

    Raises
    ------
    FileNotFoundError
        A given path holds no file.
    DataFileError
        The file's checksum or content is wrong.

    Notes
    -----
    The second half of the record (samples 513–1024) is almost exactly the negative of the
    first half (correlation −0.996 for u, −0.998 for y: a periodic sweep), so a first-half /
    second-half split is a weak validation.
    """
    if path is None:
        path = _packaged(ROBOT_ARM_FILENAME, ROBOT_ARM_SHA256)
    else:
        path = _given(path, ROBOT_ARM_FILENAME, ROBOT_ARM_SHA256, "robot-arm data", verify)
    data = load_daisy(path, n_columns=2)
    if data.shape[0] != 1024:
        raise DataFileError(f"{path}: expected 1024 samples; got {data.shape[0]}.")
    return Record(u=data[:, 0], y=data[:, 1], dt=None, name="DaISy 96-009 flexible robot arm",
                  input_name="reaction torque", output_name="arm acceleration",
                  source=ROBOT_ARM_SOURCE, path=path)


def cascaded_tanks():
    """The cascaded-tanks benchmark (Schoukens, Mattsson, Wigren, Noël 2016), shipped with fohw.

    A pump (input: voltage) fills an upper tank that drains into a lower one; the output is
    the lower tank's water level as the sensor's voltage. Outflows are square-root (soft)
    nonlinearities; a full tank overflows and the sensor saturates at 10 V (47 estimation and
    37 validation samples reach it).

    Returns
    -------
    Benchmark
        ``estimation`` and ``validation`` records of 1024 samples each, ``dt = 4`` s, in volts.
        The benchmark's rules: estimate on the estimation record, simulate the validation
        record in free run from its input alone, report the RMS error of the simulated output
        in volts. The initial water levels are not given.

    Examples
    --------
    >>> import fohw
    >>> tanks = fohw.datasets.cascaded_tanks()
    >>> tanks.validation.n_samples, tanks.validation.dt, float(tanks.validation.y.max())
    (1024, 4.0, 10.0)
    """
    from .io.text import read_table

    path = _packaged(CASCADED_TANKS_FILENAME, CASCADED_TANKS_SHA256)
    table = read_table(path)
    if table.names != ["uEst", "uVal", "yEst", "yVal"] or "Ts" not in table.scalars:
        raise DataFileError(f"{path}: unexpected columns {table.names} {sorted(table.scalars)}.")
    values, dt = table.data, table.scalars["Ts"]
    common = dict(dt=dt, input_name="pump voltage", output_name="lower tank level",
                  input_unit="V", output_unit="V", time_unit="s", source=CASCADED_TANKS_SOURCE,
                  path=path)
    return Benchmark(
        estimation=Record(u=values[:, 0], y=values[:, 2], name="cascaded tanks, estimation",
                          **common),
        validation=Record(u=values[:, 1], y=values[:, 3], name="cascaded tanks, validation",
                          **common),
        name="cascaded tanks with overflow", source=CASCADED_TANKS_SOURCE,
        rules="estimate on `estimation`; simulate `validation` in free run from its input "
              "alone; report the RMS error of the simulated output in volts")


BATTERY_SHA256 = "4517f5f43194878fcbc04487efdb59761f46bc728aff1d091ab00352a770ac62"
BATTERY_FILENAME = "lg_m50lt_drive_cycle.npz"
BATTERY_SOURCE = ("N. Hallemans et al., 'Physics-based battery model parametrisation from "
                  "impedance data', arXiv:2412.10896 (2024); data distributed with PyBOP "
                  "(B. Planden et al., 'PyBOP: a Python package for battery model optimisation "
                  "and parameterisation', 2024; BSD-3-Clause licence), measured by About:Energy.")


@dataclass(frozen=True, repr=False)
class BatteryCell:
    """A lithium-ion cell's drive cycle, its open-circuit voltage and its impedance spectra.

    Returned by :func:`battery_cell`; see there for the source, licence and citation.

    Attributes
    ----------
    i, v : ndarray, shape (N,)
        Current [A] (negative = discharge) and terminal voltage [V].
    soc : ndarray, shape (N,)
        State of charge by coulomb counting, ``soc[k] = soc0 + dt/(3600 capacity) sum_{j<k} i[j]``
        (the current held over each sample interval); after :meth:`decimate`, block means of the
        full-rate values.
    dt : float
        Sampling time [s].
    soc0, capacity : float
        The initial state of charge (0.80) and the capacity [Ah] (4.885) of the source's script.
    stoichiometry : dict
        The electrodes' lithium stoichiometries at SOC 0 and 1: ``y0, y1`` (positive) and
        ``x0, x1`` (negative), moving linearly in between.
    x_neg, U_neg, x_pos, U_pos : ndarray
        The electrodes' open-circuit potentials [V] against their stoichiometries.
    impedance_f, impedance_soc : ndarray, shapes (65,), (7,)
        Frequencies [Hz] and states of charge of the impedance spectra.
    impedance, impedance_fit : ndarray, complex, shape (65, 7)
        The measured impedance [ohm] (``Z``) and the source's physics-model fit (``Zhat``).
    thetahat : ndarray, shape (18,)
        The source's fitted parameter vector (its last four entries are the stoichiometries).
    source, path : str
    """

    i: np.ndarray
    v: np.ndarray
    soc: np.ndarray
    dt: float
    soc0: float
    capacity: float
    stoichiometry: dict
    x_neg: np.ndarray
    U_neg: np.ndarray
    x_pos: np.ndarray
    U_pos: np.ndarray
    impedance_f: np.ndarray
    impedance_soc: np.ndarray
    impedance: np.ndarray
    impedance_fit: np.ndarray
    thetahat: np.ndarray
    source: str = BATTERY_SOURCE
    path: str = ""

    @property
    def n_samples(self) -> int:
        """Number of samples ``N``."""
        return self.i.shape[0]

    @property
    def t(self) -> np.ndarray:
        """Sample times [s], ``k dt`` (after :meth:`decimate`: the first sample of each block)."""
        return self.dt * np.arange(self.n_samples)

    def ocv(self, soc):
        """Open-circuit voltage [V] at a state of charge: ``U_pos(y(soc)) - U_neg(x(soc))``.

        Parameters
        ----------
        soc : float or array_like
            State(s) of charge in [0, 1].

        Returns
        -------
        float or ndarray
            Linear interpolation of the electrodes' tabulated potentials, with
            ``y = y0 + soc (y1 - y0)`` and ``x = x0 + soc (x1 - x0)``.

        Examples
        --------
        >>> import fohw
        >>> round(float(fohw.datasets.battery_cell().ocv(0.5)), 3)
        3.72
        """
        soc = np.asarray(soc, dtype=np.float64)
        if not np.all(np.isfinite(soc)) or np.any((soc < 0.0) | (soc > 1.0)):
            raise ParameterError(f"`soc` must be in [0, 1]; got values from {np.nanmin(soc)!r} to "
                                 f"{np.nanmax(soc)!r}.")
        st = self.stoichiometry
        y = st["y0"] + soc * (st["y1"] - st["y0"])
        x = st["x0"] + soc * (st["x1"] - st["x0"])
        out = np.interp(y, self.x_pos, self.U_pos) - np.interp(x, self.x_neg, self.U_neg)
        return float(out) if out.ndim == 0 else out

    def ocv_table(self):
        """The open-circuit voltage as a :class:`fohw.OCVTable` (what a model file can hold).

        Both electrodes' potentials are linear between their tabulated stoichiometries, and the
        stoichiometries are linear in the state of charge, so the OCV is linear between the
        states of charge where either electrode has a table point: the table holds those (and
        0 and 1), and equals :meth:`ocv` at every state of charge in [0, 1] up to rounding.

        Returns
        -------
        OCVTable

        Examples
        --------
        >>> import numpy as np, fohw
        >>> cell = fohw.datasets.battery_cell()
        >>> soc = np.linspace(0, 1, 1001)
        >>> bool(np.max(np.abs(cell.ocv_table()(soc) - cell.ocv(soc))) < 1e-12)
        True
        """
        from .model.circuit import OCVTable

        st = self.stoichiometry
        knots = [np.array([0.0, 1.0])]
        for points, s0, s1 in ((self.x_pos, st["y0"], st["y1"]), (self.x_neg, st["x0"], st["x1"])):
            s = (np.asarray(points, dtype=np.float64) - s0) / (s1 - s0)
            knots.append(s[(s > 0.0) & (s < 1.0)])
        soc = np.unique(np.concatenate(knots))
        return OCVTable(soc, self.ocv(soc))

    def decimate(self, factor):
        """The record averaged over blocks of ``factor`` samples (``i``, ``v`` and ``soc``).

        Block means are an anti-aliasing filter that keeps the charge: the block-mean current
        times the new ``dt`` is the charge of the block. A trailing partial block is dropped.

        Parameters
        ----------
        factor : int
            Samples per block, ``>= 1``.

        Returns
        -------
        BatteryCell
            The same cell with ``dt * factor``.

        Examples
        --------
        >>> import fohw
        >>> cell = fohw.datasets.battery_cell().decimate(10)
        >>> cell.n_samples, cell.dt
        (16495, 1.5)
        """
        import dataclasses

        factor = check_int(factor, "factor", minimum=1)
        n = (self.n_samples // factor) * factor
        if n == 0:
            raise ParameterError(f"`factor` = {factor} exceeds the {self.n_samples} samples.")

        def block(x):
            return x[:n].reshape(-1, factor).mean(axis=1)

        return dataclasses.replace(self, i=block(self.i), v=block(self.v), soc=block(self.soc),
                                   dt=self.dt * factor)

    def __repr__(self):
        return (f"BatteryCell(n_samples={self.n_samples}, dt={self.dt:g} s, soc "
                f"{self.soc[0]:.3f} -> {self.soc[-1]:.3f}, {self.impedance_f.size} impedance "
                f"frequencies at SOC {', '.join(f'{s:g}' for s in self.impedance_soc)})")


def battery_cell():
    """Drive cycle, open-circuit voltage and impedance spectra of an LG M50LT cell, shipped with fohw.

    One LG M50LT 5 Ah cylindrical (21700) lithium-ion cell: a drive cycle from 80 % to 20 %
    state of charge (164 953 samples at 0.15 s, 6.9 h), the open-circuit potentials of its two
    electrodes with the stoichiometry limits (so the cell's open-circuit voltage at any state of
    charge), and its impedance measured separately at SOC 0.2, 0.3, ..., 0.8 (65 frequencies,
    4e-4 Hz to 1 kHz). Data of Hallemans et al., arXiv:2412.10896 (2024), distributed with PyBOP
    under the BSD-3-Clause licence (``fohw/data/README.md`` has the licence text, the
    provenance and the checksums); cite both when you use it.

    Returns
    -------
    BatteryCell
        At the full rate; :meth:`BatteryCell.decimate` averages blocks.

    Raises
    ------
    DataFileError
        The installed file's checksum is wrong.

    Notes
    -----
    Stored losslessly: the current to its 6 significant decimal digits, the voltage on its
    10 uV grid, everything else as the source's float64. The time is ``k * 0.15`` s (the
    source's time vector differs from it by at most 4e-12 s). The stoichiometries are the last
    four entries of the source's parameter vector in the order ``y1, y0, x0, x1`` (positive
    electrode at SOC 1 and 0, negative electrode at SOC 0 and 1): of the 24 orders, only this
    one puts the open-circuit voltage within 13 mV of the voltage after the record's 60 s rests
    (every other order is at least 59 mV off at one of them). Nothing is known about the cell
    before ``t = 0`` beyond its state of charge.

    Examples
    --------
    >>> import fohw
    >>> cell = fohw.datasets.battery_cell()
    >>> cell.n_samples, cell.dt, round(float(cell.soc[-1]), 3)
    (164953, 0.15, 0.201)
    """
    path = _packaged(BATTERY_FILENAME, BATTERY_SHA256)
    with np.load(path, allow_pickle=False) as data:
        d = {k: data[k] for k in data.files}
    i = d["current_mantissa"] / 10.0 ** (-d["current_exponent"].astype(np.int64))
    v = d["voltage_10uV"] / 1e5
    dt = float(d["time_step"])
    soc0, capacity = 0.8, 4.885
    soc = soc0 + np.concatenate([[0.0], np.cumsum(i[:-1])]) * dt / (3600.0 * capacity)
    y1, y0, x0, x1 = (float(s) for s in d["thetahat"][-4:])
    return BatteryCell(i=i, v=v, soc=soc, dt=dt, soc0=soc0, capacity=capacity,
                       stoichiometry={"y0": y0, "y1": y1, "x0": x0, "x1": x1},
                       x_neg=d["x_neg"], U_neg=d["U_neg"], x_pos=d["x_pos"], U_pos=d["U_pos"],
                       impedance_f=d["impedance_f"], impedance_soc=d["impedance_soc"],
                       impedance=d["impedance_Z"], impedance_fit=d["impedance_Zhat"],
                       thetahat=d["thetahat"], path=path)


PULSES_SHA256 = "60a5acf9d8b6e5902e09c335a7ba3a3effef2dd4a2a811e622115ef6af7816d8"
PULSES_FILENAME = "pybamm_pulses.npz"


@dataclass(frozen=True, repr=False)
class PulseTest:
    """One simulated pulse test of a cell: current, voltage, state of charge, temperature.

    Returned by :func:`pybamm_pulses`. ``u`` is the input of :class:`fohw.CircuitTables`
    (``[current, soc, temperature]``), ``y`` the voltage.

    Attributes
    ----------
    i, v, soc, temperature : ndarray, shape (N,)
        Current [A] (positive = charge), terminal voltage [V], coulomb-counted state of charge,
        cell temperature [degC].
    dt : float
        Sampling time [s].
    ambient : float
        The ambient (and initial) temperature [degC].
    soc0 : float
        The initial state of charge.
    """

    i: np.ndarray
    v: np.ndarray
    soc: np.ndarray
    temperature: np.ndarray
    dt: float
    ambient: float
    soc0: float

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return self.i.shape[0]

    @property
    def u(self) -> np.ndarray:
        """``[current, soc, temperature]``, shape ``(N, 3)``."""
        return np.column_stack([self.i, self.soc, self.temperature])

    @property
    def y(self) -> np.ndarray:
        """The voltage [V]."""
        return self.v

    def record(self) -> Record:
        """The test as a :class:`fohw.Record` (inputs current, soc, temperature; output voltage)."""
        return Record(self.u, self.v, dt=self.dt, name=f"T{self.ambient:g}_soc{self.soc0:g}",
                      input_name=("current", "soc", "temperature"), input_unit=("A", "", "degC"),
                      output_name="voltage", output_unit="V", time_unit="s",
                      source="PyBaMM DFN (Chen2020), benchmarks/generate_pybamm_pulses.py")

    def __repr__(self):
        return (f"PulseTest(T = {self.ambient:g} degC, soc0 = {self.soc0:g}, {self.n_samples} samples "
                f"at {self.dt:g} s)")


def pybamm_pulses(temperatures=None, socs=None, *, every=1):
    """Pulse tests of an LG M50 cell simulated by PyBaMM (DFN, ``Chen2020``), shipped with fohw.

    Fifteen records, one per ambient temperature (0, 10, 25, 35, 45 degC) and initial state of
    charge (0.3, 0.5, 0.8): rest 10 s, discharge at 1C (5 A) 10 s, rest 40 s, charge at 1C 10 s,
    rest 40 s, sampled at 0.1 s (1101 samples). Made by
    ``benchmarks/generate_pybamm_pulses.py`` with PyBaMM 26.10.1.1 (its docstring says how); fohw
    reads the file without PyBaMM. In ``Chen2020`` only the exchange-current densities depend
    on temperature.

    Parameters
    ----------
    temperatures, socs : sequence of float, optional
        Keep the records at these ambient temperatures [degC] / initial states of charge
        (default all).
    every : int, optional
        Keep every ``every``-th sample (a divisor of 100: 1, 2, 4, 5, 10, ...; default 1). The
        current changes only at multiples of 10 s, so the kept samples are the same record at
        the step ``0.1 every`` s exactly (each sample's current is still the one held over the
        interval before it); ``every=5`` gives 221 samples at 0.5 s.

    Returns
    -------
    records : list of PulseTest
        Temperature-major order.
    ocv : fohw.OCVTable
        The cell's open-circuit voltage at states of charge 0.05 to 0.95 (no entropic term).

    Examples
    --------
    >>> import fohw
    >>> records, ocv = fohw.datasets.pybamm_pulses(temperatures=[25.0])
    >>> [(r.ambient, r.soc0) for r in records]
    [(25.0, 0.3), (25.0, 0.5), (25.0, 0.8)]
    >>> records[0].u.shape, round(float(ocv(0.5)), 4)
    ((1101, 3), 3.7509)
    """
    from .model.circuit import OCVTable

    every = check_int(every, "every", minimum=1)
    if 100 % every:
        raise ParameterError(f"`every` must divide 100 (the current changes every 100 samples); "
                             f"got {every}.")
    path = _packaged(PULSES_FILENAME, PULSES_SHA256)
    with np.load(path, allow_pickle=False) as data:
        d = {k: data[k] for k in data.files}
    dt, capacity = float(d["dt"]), float(d["capacity_ah"])
    keep_t = None if temperatures is None else {float(t) for t in temperatures}
    keep_s = None if socs is None else {float(s) for s in socs}
    for name, keep, have in (("temperatures", keep_t, d["temperature_c"]), ("socs", keep_s, d["soc0"])):
        if keep is not None and not keep <= set(have.tolist()):
            raise ParameterError(f"`{name}` must be among {sorted(set(have.tolist()))}; got "
                                 f"{sorted(keep)}.")
    records = []
    for k in range(d["current"].shape[0]):
        amb, soc0 = float(d["temperature_c"][k]), float(d["soc0"][k])
        if (keep_t is not None and amb not in keep_t) or (keep_s is not None and soc0 not in keep_s):
            continue
        i = d["current"][k].astype(np.float64)
        soc = soc0 + np.concatenate([[0.0], np.cumsum(i[:-1])]) * dt / (3600.0 * capacity)
        keep = slice(None, None, every)
        records.append(PulseTest(i=i[keep], v=d["voltage_uv"][k][keep] / 1e6, soc=soc[keep],
                                 temperature=d["cell_temperature_uk"][k][keep] / 1e6, dt=dt * every,
                                 ambient=amb, soc0=soc0))
    return records, OCVTable(d["ocv_soc"], d["ocv_volts"])
