"""odocal from Python: calibrated wheel odometry for differential-drive robots.

Every number comes from odocal's Rust core (the extension ``odocal._core``);
the results carry the same keys as the command line's ``--json`` output, and
bad input raises :class:`InputError` (a ``ValueError``) with the message the
command line prints before exiting with code 2.

>>> import odocal
>>> sim = odocal.simulate("hall.mcap", scenario="hall", seed=3, duration=60,
...                       effects=["radius_scale:right=0.01,left=-0.005"])
>>> rec = odocal.read("hall.mcap")          # numpy arrays
>>> cal = odocal.calibrate("hall.mcap", method="dkf")
>>> cal["final"], cal["std"], cal.history["r_right"]
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Dict, Iterable, Optional, Union

import numpy as np

from . import _core
from ._core import InputError, OutputError

__all__ = [
    "InputError",
    "OutputError",
    "Recording",
    "Motions",
    "Calibration",
    "read",
    "icp",
    "calibrate",
    "eval",
    "diagnose",
    "simulate",
    "fleet",
]
__version__ = _core.__version__

PathLike = Union[str, "os.PathLike[str]"]


def _p(path: Optional[PathLike]) -> Optional[str]:
    return None if path is None else os.fspath(path)


class Recording(dict):
    """A recording read by odocal, as numpy arrays.

    Keys: ``source``; ``scan_stamps`` (s), ``angle_min``, ``angle_increment``
    (rad), ``range_min``, ``range_max`` (m), one value per scan; ``ranges``
    (scans × beams, m, float32; a list of arrays when the beam count varies);
    ``wheels`` (n × 3: t s, left rad, right rad); ``gyro`` (n × 2: t s, yaw
    rate rad/s); ``odom`` and ``reference`` (n × 4: t s, x m, y m, θ rad);
    ``base_from_laser`` (x m, y m, yaw rad, or ``None`` when the recording
    does not state it). ``path`` is the file it was read from.
    """

    path: str

    @property
    def scans(self) -> int:
        """How many scans."""
        return len(self["scan_stamps"])


class Motions(dict):
    """``odocal icp``'s result: its ``--json`` keys, plus ``trajectory``
    (n × 4: t, x, y, θ from the TUM file) and ``motions`` (a structured array
    of the per-pair motions CSV), and the files written (``tum``,
    ``motions_csv``)."""

    @property
    def trajectory(self) -> np.ndarray:
        return self["trajectory"]

    @property
    def motions(self) -> np.ndarray:
        return self["motions"]


class Calibration(dict):
    """``odocal calibrate``'s summary (the keys of its ``--json``:
    ``final``, ``std``, ``multipliers``, ``assumptions``, ``observability``…)
    plus ``history``: a structured array of the estimate after every step
    (the columns of ``calibration.csv``), and ``out``, the folder written."""

    @property
    def history(self) -> np.ndarray:
        return self["history"]


def _csv_table(path: Path) -> np.ndarray:
    """A CSV with a header line as a structured array (no pandas)."""
    with open(path, encoding="utf-8") as f:
        header = f.readline()
    if not header.strip():
        return np.zeros(0)
    data = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")
    return np.atleast_1d(data)


def _tum(path: Path) -> np.ndarray:
    """A TUM trajectory (t x y z qx qy qz qw) as n × 4: t, x, y, yaw."""
    rows = np.loadtxt(path, comments="#", ndmin=2)
    if rows.size == 0:
        return np.zeros((0, 4))
    qz, qw = rows[:, 6], rows[:, 7]
    yaw = 2.0 * np.arctan2(qz, qw)
    yaw = (yaw + np.pi) % (2.0 * np.pi) - np.pi
    return np.column_stack([rows[:, 0], rows[:, 1], rows[:, 2], yaw])


def read(path: PathLike, robot: Optional[PathLike] = None,
         config: Optional[PathLike] = None) -> Recording:
    """Read a recording (ROS 2 MCAP, ROS 1 bag, rosbag2 SQLite or folder,
    CARMEN log; recognised by content) into numpy arrays."""
    rec = Recording(_core.read(os.fspath(path), _p(robot), _p(config)))
    rec.path = os.fspath(path)
    return rec


def _input_path(rec: Union[PathLike, Recording]) -> str:
    if isinstance(rec, Recording):
        return rec.path
    return os.fspath(rec)


def _out_dir(out: Optional[PathLike], prefix: str) -> str:
    return os.fspath(out) if out is not None else tempfile.mkdtemp(prefix=prefix)


def icp(rec: Union[PathLike, Recording], out: Optional[PathLike] = None, *,
        robot: Optional[PathLike] = None, config: Optional[PathLike] = None) -> Motions:
    """Scan matching (``odocal icp``): consecutive scans into motions with
    covariance, and the chained trajectory. ``out`` is a folder for
    ``trajectory.tum`` and ``motions.csv`` (a temporary one when omitted)."""
    folder = Path(_out_dir(out, "odocal-icp-"))
    folder.mkdir(parents=True, exist_ok=True)
    tum, csv = folder / "trajectory.tum", folder / "motions.csv"
    res = Motions(json.loads(_core.icp(_input_path(rec), str(tum), str(csv), _p(robot), _p(config))))
    res["tum"], res["motions_csv"] = str(tum), str(csv)
    res["trajectory"] = _tum(tum)
    res["motions"] = _csv_table(csv)
    return res


def calibrate(rec: Union[PathLike, Recording, Motions, None] = None, out: Optional[PathLike] = None, *,
              method: Optional[str] = None, wheels: Optional[PathLike] = None,
              resampler: Optional[str] = None, trigger: Optional[str] = None,
              particles: Optional[int] = None, seed: Optional[int] = None,
              robot: Optional[PathLike] = None, config: Optional[PathLike] = None,
              init: Optional[str] = None) -> Calibration:
    """Calibrate the wheel radii and wheel base (``odocal calibrate``).

    ``rec`` is a recording (path or :class:`Recording`), or the
    :class:`Motions` of :func:`icp` (then ``wheels`` names the wheels CSV,
    ``t,left,right``). ``method``: ``adaptive-pf`` (default), ``pf``,
    ``dkf``, ``akf``, ``batch``, ``none``. Refusals (wiring, observability,
    implausible estimates) raise :class:`InputError` with the CLI's message.
    ``init``: ``nominal`` (default) or ``batch`` (``--init batch``: an online
    filter starts from the joint batch estimate of the same recording).
    """
    folder = _out_dir(out, "odocal-calibrate-")
    if isinstance(rec, Motions):
        if wheels is None:
            raise InputError("calibrate from motions needs wheels=WHEELS.csv")
        args = dict(motions=rec["motions_csv"], wheels=os.fspath(wheels))
    elif rec is None:
        raise InputError("calibrate needs a recording, or motions and wheels")
    else:
        args = dict(input=_input_path(rec))
    summary = _core.calibrate(folder, method=method, resampler=resampler, trigger=trigger,
                              particles=particles, seed=seed, robot=_p(robot),
                              config=_p(config), init=init, **args)
    res = Calibration(json.loads(summary))
    res["out"] = folder
    history = Path(folder) / "calibration.csv"
    res["history"] = _csv_table(history) if history.exists() else np.zeros(0)
    return res


def eval(estimate: PathLike, reference: Optional[PathLike] = None, *,
         relations: Optional[PathLike] = None, align: Optional[str] = None,
         t_max_diff: Optional[float] = None, t_offset: Optional[float] = None,
         interpolate: bool = False, resample_reference: Optional[bool] = None,
         max_gap: Optional[float] = None, rpe_delta: Optional[float] = None,
         rpe_unit: Optional[str] = None, plot: Optional[PathLike] = None,
         robot: Optional[PathLike] = None, config: Optional[PathLike] = None) -> Dict[str, Any]:
    """Evaluate a trajectory (``odocal eval``): APE/RPE as evo computes them,
    relation errors; ``align``: ``auto``, ``none``, ``origin``, ``se2``,
    ``sim2``, ``se3``, ``sim3``."""
    return json.loads(_core.eval(
        os.fspath(estimate), _p(reference), _p(relations), align, t_max_diff, t_offset,
        interpolate, resample_reference, max_gap, rpe_delta, rpe_unit, _p(plot),
        _p(robot), _p(config)))


def diagnose(rec: Union[PathLike, Recording], *, holdout: Optional[float] = None,
             report: Optional[PathLike] = None, robot: Optional[PathLike] = None,
             config: Optional[PathLike] = None) -> Dict[str, Any]:
    """Diagnose what the nominal model gets wrong (``odocal diagnose``): a
    dict with the JSON keys of ``odocal diagnose --json`` (``verdict``,
    ``causes``, ``gain``…)."""
    return json.loads(_core.diagnose(_input_path(rec), holdout, _p(report), _p(robot), _p(config)))


def simulate(out: PathLike, *, scenario: Optional[str] = None, seed: Optional[int] = None,
             duration: Optional[float] = None, effects: Iterable[str] = (),
             truth: Optional[PathLike] = None, robot: Optional[PathLike] = None,
             config: Optional[PathLike] = None, start: Optional[str] = None) -> Dict[str, Any]:
    """Simulate the wheelchair and write a ROS 2 bag (``odocal simulate``);
    ``effects`` are SPECs such as ``"radius_scale:right=0.01,left=-0.005"``;
    the truth goes to ``truth`` (JSON), kept apart from the bag; ``start``
    (``YYYY-MM-DD[THH:MM[:SS]]``, UTC) is the bag's clock at the run's start."""
    return json.loads(_core.simulate(os.fspath(out), scenario, seed, duration, list(effects),
                                     _p(truth), _p(robot), _p(config), start))


from . import fleet  # noqa: E402  (uses the functions above)
