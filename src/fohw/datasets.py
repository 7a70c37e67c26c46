"""Data sets: the paper's academic example (Section 6.1) and DaISy-format files (Section 6.2)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ._validation import check_int, check_random_state, check_scalar
from .exceptions import DataFileError, ParameterError
from .model.system import HammersteinWiener, simulate

__all__ = ["SimulatedData", "MeasuredData", "paper_model", "paper_example", "load_daisy",
           "robot_arm"]


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
        infinity for most seeds at ``N = 10 000`` (SPEC §6: 28 of 40 seeds), which raises
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
    return _parse_table(path, n_columns=n_columns)[0]


def _parse_table(path, *, n_columns=None, header=False):
    """Numeric rows of a text file, with the errors of :func:`load_daisy`.

    DaISy mode (``header=False``): ASCII, whitespace-separated. Table mode (``header=True``):
    UTF-8, comma-separated where a line has a comma, and a first line of names allowed.
    Returns ``(data, names)``.
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"data file not found: {path!r}")
    rows, names = [], None
    encoding = "utf-8" if header else "ascii"
    with open(path, "rb") as fh:
        for lineno, raw in enumerate(fh, start=1):
            try:
                text = raw.decode(encoding).strip()
            except UnicodeDecodeError:
                label = "UTF-8" if header else "ASCII"
                raise DataFileError(f"{path}: line {lineno} is not {label} text.") from None
            if not text or text[0] in "%#":
                continue
            fields = [f.strip() for f in (text.split(",") if header and "," in text
                                          else text.split())]
            try:
                values = [float(f) for f in fields]
            except ValueError:
                if header and not rows and names is None:
                    names, n_columns = fields, len(fields)
                    continue
                bad = next(f for f in fields if not _is_float(f))
                raise DataFileError(f"{path}: line {lineno}: {bad!r} is not a number.") from None
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
    return np.array(rows, dtype=np.float64), names


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


#: sha256 of DaISy 96-009 ``robot_arm.dat`` as distributed (see the data README).
ROBOT_ARM_SHA256 = "4ee167a8a28ce0da868d1b42f6a2fe0c456ea0e56b60c70915bf6d4a2a933635"
ROBOT_ARM_FILENAME = "daisy_robot_arm.dat"


@dataclass(frozen=True, repr=False)
class MeasuredData:
    """A measured input–output record.

    Attributes
    ----------
    u, y : ndarray, shape (N,)
        Input and output.
    name : str
        Where the record comes from.
    sampling_time : float or None
        ``None`` where the source gives none.
    path : str
        The file read.
    """

    u: np.ndarray
    y: np.ndarray
    name: str
    sampling_time: float | None
    path: str

    @property
    def n_samples(self) -> int:
        """Number of samples ``N``."""
        return self.u.shape[0]

    def __repr__(self):
        return f"MeasuredData({self.name!r}, n_samples={self.n_samples}, path={self.path!r})"


def _robot_arm_help() -> str:
    return ("The flexible robot arm record is DaISy data set 96-009 (KU Leuven; De Moor et al., "
            "'DAISY: a database for identification of systems', 1997), file robot_arm.dat: "
            "1024 lines of 'u y' (reaction torque, arm acceleration). fohw does not ship it. "
            f"Save it as {ROBOT_ARM_FILENAME!r} and pass its path (command line: --data PATH), "
            "fohw.datasets.robot_arm(path=...), or set the environment variable FOHW_DATA_DIR "
            "to the folder that holds it.")


def robot_arm(path=None, *, verify=True):
    """The DaISy flexible robot arm record (paper Section 6.2).

    Parameters
    ----------
    path : str or os.PathLike, optional
        The file, or a folder holding ``daisy_robot_arm.dat``. Default: the folder named by the
        environment variable ``FOHW_DATA_DIR``.
    verify : bool, optional
        Check the file's sha256 against the published one (default True).

    Returns
    -------
    MeasuredData
        ``u`` = reaction torque, ``y`` = arm acceleration, 1024 samples; the source gives no
        sampling time (``sampling_time=None``; use one sample as the unit).

    Raises
    ------
    FileNotFoundError
        No path given and ``FOHW_DATA_DIR`` unset, or no file there; the message says what the
        file is and where to get it.
    DataFileError
        The file's checksum or content is wrong.

    Notes
    -----
    The second half of the record (samples 513–1024) is almost exactly the negative of the
    first half (correlation −0.996 for u, −0.998 for y: a periodic sweep), so a first-half /
    second-half split is a weak validation.
    """
    import hashlib

    if path is None:
        folder = os.environ.get("FOHW_DATA_DIR")
        if not folder:
            raise FileNotFoundError("no path given and FOHW_DATA_DIR is not set. "
                                    + _robot_arm_help())
        path = os.path.join(folder, ROBOT_ARM_FILENAME)
    path = os.fspath(path)
    if os.path.isdir(path):
        path = os.path.join(path, ROBOT_ARM_FILENAME)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"robot-arm data not found at {path!r}. " + _robot_arm_help())
    if verify:
        with open(path, "rb") as fh:
            digest = hashlib.sha256(fh.read()).hexdigest()
        if digest != ROBOT_ARM_SHA256:
            raise DataFileError(f"{path}: sha256 {digest} does not match DaISy 96-009's "
                                f"{ROBOT_ARM_SHA256}; the file is corrupted or another file. "
                                + _robot_arm_help())
    data = load_daisy(path, n_columns=2)
    if data.shape[0] != 1024:
        raise DataFileError(f"{path}: expected 1024 samples; got {data.shape[0]}.")
    return MeasuredData(u=data[:, 0].copy(), y=data[:, 1].copy(),
                        name="DaISy 96-009 flexible robot arm", sampling_time=None, path=path)
