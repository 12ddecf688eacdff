"""afford: where a person could sit or lie in a 3D point cloud, and how.

The detector of the ``afford`` command line (Seib et al., "Affordance Origami",
sections 3-4), called from Python with numpy arrays in and out::

    import numpy as np, afford
    points = afford.read("data/sample/room.ply")          # (N, 3) float64, metres, z up
    result = afford.detect(points, threads=2)
    for d in result.detections:
        print(d.position, d.yaw_deg, d.affordances, d.score)
    result.labels                                       # (N,) int32, -1 for none

Arguments take the command line's words (``up="z"``, ``units="mm"``, ``camera=True``,
``floor="auto"``, ``affordances=("sitting", "lying")``, model files by path or built-in
name). Errors are ``ValueError`` (bad arrays and arguments) and ``OSError`` (files,
``FileNotFoundError`` when missing) with the command line's one-line messages.

Detection runs in native code with the GIL released; ``threads=n`` runs it in a pool of
``n`` threads of its own (default: every core), so several Dask or Ray workers on one
machine can share it. Results are plain data: they pickle and cross process boundaries.
"""

from __future__ import annotations

import csv
import io
import json
import os
import signal
import sys
from dataclasses import dataclass, field
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native

__version__: str = _native.__version__

__all__ = [
    "Detection",
    "Result",
    "Run",
    "detect",
    "detect_file",
    "read",
    "to_csv",
    "to_json",
    "to_summary",
]

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True)
class Run:
    """One model's run over an input: a body (agent at a height) with one hierarchy, and
    the counts of its stages (available hypotheses, stable fits, candidates before
    suppression)."""

    agent: str
    height: float
    hierarchy: str
    hypotheses: int
    fits: int
    candidates: int


@dataclass(frozen=True, eq=False)
class Detection:
    """One detected place and how it affords the hierarchy's action.

    Full precision (the ``--json`` document rounds). ``position`` is the agent's root
    joint (pelvis) in the detector's world frame, metres (z up, floor at z = 0; map it
    back to the input frame with ``Result.transform``). ``yaw_deg`` is the heading about
    z (0 faces +x). ``score`` is the accumulated score (paper Eq. 5), ``stability`` Eq. 1,
    ``availability`` the hypothesis availability (Fig. 5d). ``pose_deg`` gives every
    joint's angle of the goal pose and ``joints`` every joint's position in the world
    frame, metres (the ``--json`` document's ``joints``). ``segment`` holds the input rows of the points grown
    from this detection (its own run's segment).
    """

    index: int
    hierarchy: str
    agent: str
    height: float
    position: np.ndarray
    yaw_deg: float
    affordances: List[str]
    score: float
    stability: float
    availability: float
    local_scores: Dict[str, float]
    pose_deg: Dict[str, float]
    joints: Dict[str, Tuple[float, float, float]]
    segment_points: int
    segment: np.ndarray = field(repr=False)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Detection):
            return NotImplemented
        return all(
            np.array_equal(getattr(self, k), getattr(other, k))
            if k in ("position", "segment")
            else getattr(self, k) == getattr(other, k)
            for k in self.__dataclass_fields__
        )


class Result:
    """What detection found in one input.

    Attributes:
        file: the file as given, or the ``name`` given to ``detect``.
        points: points detected in (finite rows).
        dropped_non_finite: rows dropped for a NaN or infinite coordinate.
        detections: the detections, run after run, strongest first within a run.
        labels: int32 array, one per input row (``detect``) or per point of the file
            (``detect_file``, in ``read`` order): the index of the first detection whose
            segment holds the point, -1 for none (and for dropped rows).
        transform: (4, 4) float64, the affine map from input coordinates to the
            detector's world frame (identity when the input was used as given).
        affordances: the affordance ids found by any detection.
        affordance_ids: every affordance id of the hierarchies run.
        runs: one ``Run`` per body and hierarchy.
        frame: the command line's note of what was done to the frame, or None.
        warnings: warnings about the input (units that look wrong, a floor not at
            z = 0).
    """

    def __init__(self, data: Dict[str, Any]) -> None:
        self._data = data
        self.file: str = data["file"]
        self.points: int = data["points"]
        self.dropped_non_finite: int = data["dropped_non_finite"]
        self.labels: np.ndarray = data["labels"]
        self.transform: np.ndarray = data["transform"]
        self.affordances: List[str] = list(data["affordances"])
        self.affordance_ids: List[str] = list(data["ids"])
        self.runs: List[Run] = [Run(*r) for r in data["runs"]]
        self.frame: Optional[str] = data["frame"]
        self.warnings: List[str] = [
            w for w in [data["units_warning"], data["floor_warning"]] if w
        ]
        self.detections: List[Detection] = [
            Detection(
                index=i,
                hierarchy=d["hierarchy"],
                agent=d["agent"],
                height=d["height"],
                position=np.asarray(d["position"], dtype=np.float64),
                yaw_deg=d["yaw_deg"],
                affordances=list(d["affordances"]),
                score=d["score"],
                stability=d["stability"],
                availability=d["availability"],
                local_scores=dict(d["local_scores"]),
                pose_deg=dict(d["pose_deg"]),
                joints={n: tuple(p) for n, p in d["joints"]},
                segment_points=d["segment_points"],
                segment=d["segment"],
            )
            for i, d in enumerate(data["detections"])
        ]

    def __reduce__(self) -> Tuple[Any, ...]:
        return (Result, (self._data,))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Result):
            return NotImplemented
        return (
            self.to_json() == other.to_json()
            and np.array_equal(self.labels, other.labels)
            and np.array_equal(self.transform, other.transform)
            and self.detections == other.detections
        )

    def __repr__(self) -> str:
        return (
            f"<afford.Result {self.file!r}: {self.points} points, "
            f"{len(self.detections)} detections; affords: "
            f"{', '.join(self.affordances) or 'nothing'}>"
        )

    def to_json(self) -> str:
        """The ``--json`` document of this input, byte for byte as the command line
        writes it (``{"version": 4, "files": [...]}``, numbers rounded)."""
        return to_json([self])

    def to_dict(self) -> Dict[str, Any]:
        """The ``--json`` document of this input as a dict (``json.loads`` of it)."""
        return json.loads(self.to_json())

    def to_csv_rows(self) -> List[Dict[str, str]]:
        """The rows of the ``--csv`` detections file, as dicts of its text cells."""
        return list(csv.DictReader(io.StringIO(to_csv([self]))))

    def to_dataframe(self) -> Any:
        """The ``--csv`` detections as a pandas DataFrame (needs pandas)."""
        import pandas as pd

        return pd.read_csv(io.StringIO(to_csv([self])))


def _documents(results: Iterable[Result]) -> Tuple[str, str, str]:
    results = list(results)
    for r in results:
        if not isinstance(r, Result):
            raise ValueError(f"expected afford.Result objects, got {type(r).__name__}")
    return _native.documents([r._data for r in results])


def to_json(results: Iterable[Result]) -> str:
    """The ``--json`` document of a run over these results' files, in this order."""
    return _documents(results)[0]


def to_csv(results: Iterable[Result]) -> str:
    """The ``--csv`` detections document of a run over these results' files."""
    return _documents(results)[1]


def to_summary(results: Iterable[Result]) -> str:
    """The ``--summary`` document (one 0/1 row per file and body) of these results."""
    return _documents(results)[2]


def _words(value: Union[str, Sequence[str]], what: str) -> List[str]:
    items = [value] if isinstance(value, (str, os.PathLike)) else list(value)
    out = []
    for v in items:
        if not isinstance(v, (str, os.PathLike)):
            raise ValueError(f"{what}: expected names or paths, got {v!r}")
        out.append(os.fspath(v))
    return out


def _heights(heights: Union[float, Sequence[float]]) -> List[float]:
    try:
        return [float(h) for h in np.atleast_1d(np.asarray(heights, dtype=np.float64))]
    except (TypeError, ValueError):
        raise ValueError(f"heights: expected numbers (metres), got {heights!r}") from None


def _transform(transform: Any) -> Optional[str]:
    """The text of a 4x4 matrix: given as text, a file holding it, or an array."""
    if transform is None:
        return None
    if isinstance(transform, (str, os.PathLike)):
        path = os.fspath(transform)
        if os.path.isfile(path):
            with open(path, encoding="utf-8") as f:
                return f.read()
        return path
    m = np.asarray(transform, dtype=np.float64)
    if m.shape not in ((4, 4), (16,)):
        raise ValueError(f"transform: expected a 4x4 matrix, got shape {m.shape}")
    return " ".join(repr(float(v)) for v in m.reshape(-1))


def _frame(up: str, units: str, camera: bool, floor: Optional[str], transform: Any) -> Tuple:
    return (str(up), str(units), bool(camera), "keep" if floor is None else str(floor), _transform(transform))


def _points(points: Any) -> np.ndarray:
    a = np.asarray(points)
    if a.dtype not in (np.dtype(np.float32), np.dtype(np.float64)):
        # Other real numbers (integers, float16, another byte order) convert exactly.
        if a.dtype.kind in "iuf":
            a = a.astype(np.float64)
        else:
            raise ValueError(f"points: expected float32 or float64 numbers, got dtype {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"points: expected an array of shape (N, 3), got shape {a.shape}")
    return a


def detect(
    points: Any,
    *,
    heights: Union[float, Sequence[float]] = (1.75,),
    agents: Union[str, Sequence[str]] = ("human",),
    affordances: Union[str, Sequence[str]] = ("sitting", "lying"),
    up: str = "z",
    units: str = "m",
    camera: bool = False,
    floor: Optional[str] = None,
    transform: Any = None,
    threads: Optional[int] = None,
    name: str = "<array>",
) -> Result:
    """Detects where a person could sit or lie in ``points``.

    Args:
        points: array-like of shape (N, 3), float32 or float64, either memory order (an
            Open3D ``np.asarray(pcd.points)``, a torch tensor's ``.numpy()``). Rows with a
            NaN or infinite coordinate are dropped and counted; outputs keep input order.
        heights: body heights, metres (0.3 to 3.0).
        agents: body models: built-in names (``human``, ``child``) or TOML files.
        affordances: hierarchies: built-in names (``sitting``, ``lying``), TOML files or
            folders of them.
        up: the input axis pointing up: ``x``, ``y``, ``z``, ``-x``, ``-y``, ``-z``.
        units: ``m``, ``cm`` or ``mm``.
        camera: the points are a depth-camera frame (x right, y down, z forward).
        floor: ``"auto"`` finds the floor plane and moves it to z = 0; None or
            ``"keep"`` trusts the input.
        transform: a 4x4 affine matrix (array, text, or a file holding it), applied after
            the units scaling.
        threads: threads of a pool of its own; None uses every core.
        name: stands for the file name in the ``--json`` document and in messages.

    Returns:
        a ``Result``; its ``to_dict()`` is the command line's ``--json`` document.

    Raises:
        ValueError: a bad array or argument, a model that does not load, no floor found.
        OSError: a model file cannot be read (``FileNotFoundError`` when missing).
    """
    a = _points(points)
    data = _native.detect_array(
        a,
        str(name),
        _heights(heights),
        _words(agents, "agents"),
        _words(affordances, "affordances"),
        *_frame(up, units, camera, floor, transform),
        _threads(threads),
    )
    return Result(data)


def _threads(threads: Optional[int]) -> Optional[int]:
    if threads is None:
        return None
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads: expected a positive whole number, got {threads!r}")
    return threads


def detect_file(
    path: PathLike,
    *,
    heights: Union[float, Sequence[float]] = (1.75,),
    agents: Union[str, Sequence[str]] = ("human",),
    affordances: Union[str, Sequence[str]] = ("sitting", "lying"),
    up: str = "z",
    units: str = "m",
    camera: bool = False,
    floor: Optional[str] = None,
    transform: Any = None,
    sample: Optional[float] = None,
    threads: Optional[int] = None,
) -> Result:
    """Reads a cloud (PLY, PCD, XYZ/CSV) or samples a mesh (OBJ, OFF, STL) and detects in
    it exactly as ``afford detect`` does: ``to_dict()`` is its ``--json`` document, with
    ``file`` as given here. ``labels`` follow the points of ``read(path, ...)`` with the
    same options. ``sample`` is the mesh density, points per square metre. Other
    arguments as in ``detect``.
    """
    data = _native.detect_file(
        os.fspath(path),
        _heights(heights),
        _words(agents, "agents"),
        _words(affordances, "affordances"),
        *_frame(up, units, camera, floor, transform),
        None if sample is None else float(sample),
        _threads(threads),
    )
    return Result(data)


def read(
    path: PathLike,
    *,
    up: str = "z",
    units: str = "m",
    camera: bool = False,
    floor: Optional[str] = None,
    transform: Any = None,
    sample: Optional[float] = None,
) -> np.ndarray:
    """Reads a cloud or samples a mesh with the command line's readers, into the
    detector's frame (metres, z up; the frame options as in ``detect``): an (N, 3)
    float64 array of the finite points, in file order."""
    points, _dropped = _native.read(
        os.fspath(path),
        *_frame(up, units, camera, floor, transform),
        None if sample is None else float(sample),
    )
    return points


def _main() -> None:
    """The ``afford`` command line (the console script of the wheel)."""
    # Ctrl-C ends the command at once, as it does the native binary (Python's own handler
    # would only be looked at after the native call returns).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.stdout.flush()
    sys.exit(_native.cli_main(["afford", *sys.argv[1:]]))
