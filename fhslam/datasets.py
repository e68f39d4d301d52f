"""The real laser logs of the Freiburg SLAM benchmark: find them by name, or fetch them.

The files are not part of the package (nobody on the team wrote them; see
``shared/data/SOURCES.md``). :func:`find_dataset` looks for a dataset's file, in this order:

1. an explicit path to an existing file;
2. the folder named by the environment variable ``$FHSLAM_DATA`` (set, it must name a
   folder: a file or a path where nothing exists is an error, so that a mistyped path is
   not passed over for a copy elsewhere);
3. a ``shared/data`` folder beside the repository: ``<ancestor>/../shared/data`` for the
   current working directory and each of its ancestors, then beside this source tree (an
   editable install);
4. only with ``download=True``: a download, checked against the recorded sha256, into the
   user cache (``pooch.os_cache("fhslam")``).

A local copy is only checked by size (cheap); :func:`verify` computes its sha256.

Seven logs: the five benchmark logs (**intel**, **aces**, **fr079**, **fr-clinic**,
**mit-csail**) with their benchmark relations, and two scored against pseudo ground truth
(relations derived from a corrected log, with a floor of a few centimetres): **fr101**, the
raw Freiburg building 101 CARMEN log (gzipped), and **mit-killian-full**, MIT Killian Court
at full rate (1.9 km, a bag with synthetic stamps, so the benchmark's own
**mit-killian** relations, which come without a log, do not match it). All are development
data; further real logs that this project does not have check that the defaults
generalise. So no parameter is tuned to one log: a change must help
across all of them. :func:`is_held_out` is false for every dataset registered here.

The data comes from the Freiburg "SLAM benchmarking" page; cite R. Kümmerle et al., "On
measuring the accuracy of SLAM algorithms", Autonomous Robots 27(4):387-407, 2009.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

import numpy as np

from fhslam.errors import InputError, MissingInputError
from fhslam.io import Log, is_bag, read_bag, read_carmen

__all__ = [
    "DATASETS",
    "ENV_VAR",
    "MOUNT_NOTES",
    "SOURCE_COMMIT",
    "SOURCE_REPO",
    "DataFile",
    "Dataset",
    "DatasetNotFoundError",
    "find_dataset",
    "is_held_out",
    "load_log",
    "search_dirs",
    "verify",
]

ENV_VAR = "FHSLAM_DATA"
SOURCE_REPO = "INESCTEC/ricoslam"
SOURCE_COMMIT = "52bfaa91c8e5e56f119265d409b1692ca29d48d2"
_RAW_BASE = (
    f"https://raw.githubusercontent.com/{SOURCE_REPO}/{SOURCE_COMMIT}"
    "/inesctec_mrdt_slam_2d_datasets"
)

Kind = Literal["log", "relations"]
KINDS: tuple[str, ...] = ("log", "relations")


class DatasetNotFoundError(MissingInputError):
    """No copy of a dataset file was found, and none was downloaded: no download was asked
    for, or it failed (no network, a server error, a file whose sha256 is not the recorded
    one)."""


@dataclass(frozen=True)
class DataFile:
    """One file of a dataset: its name, where it lives upstream, its size and sha256."""

    name: str
    url: str
    size: int
    sha256: str

    @property
    def known_hash(self) -> str:
        """The hash in ``pooch``'s form, ``sha256:<hex>``."""
        return f"sha256:{self.sha256}"


@dataclass(frozen=True)
class Dataset:
    """A benchmark dataset: its laser log (``None`` if there is none) and its relations."""

    name: str
    log: DataFile | None
    relations: DataFile
    held_out: bool
    laser_offset: tuple[float, float, float] | None = None
    """The laser's mount (``robot_T_laser``: x, y metres, θ radians) where the log file's own
    statement is wrong; ``None``: the file's statement holds (see :data:`MOUNT_NOTES`)."""

    def file(self, kind: str) -> DataFile:
        """The :class:`DataFile` of ``kind`` (``"log"`` or ``"relations"``); an
        :class:`~fhslam.errors.InputError` naming the dataset if it has none (a dataset of
        relations only, such as mit-killian, has no log to read)."""
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, not {kind!r}")
        f = self.log if kind == "log" else self.relations
        if f is None:
            raise InputError(
                f"dataset {self.name!r} has only relations ({self.relations.name}), no laser "
                f"log to read; they evaluate a trajectory: fhslam evaluate TRAJECTORY "
                f"--relations {self.name}"
            )
        return f

    def files(self) -> Iterator[tuple[str, DataFile]]:
        """``(kind, file)`` for each file the dataset has."""
        for kind in KINDS:
            f = self.log if kind == "log" else self.relations
            if f is not None:
                yield kind, f


def _bag(name: str, size: int, sha256: str) -> DataFile:
    return DataFile(name, f"{_RAW_BASE}/bag/{name}", size, sha256)


def _text(name: str, size: int, sha256: str) -> DataFile:
    return DataFile(name, f"{_RAW_BASE}/data/{name}", size, sha256)


DATASETS: dict[str, Dataset] = {
    d.name: d
    for d in (
        Dataset(
            "intel",
            _bag(
                "intel.orig.bag",
                3954281,
                "b37cdd3988b49893edb7afe353d55739327a6e68196f257e62e7fb287860fb5d",
            ),
            _text(
                "intel.relations",
                265713,
                "330378f153eeae652d6756c1746f335801f66c3e097d90611548e6c4f593c359",
            ),
            held_out=False,
        ),
        Dataset(
            "aces",
            _bag(
                "aces.orig.bag",
                1377795,
                "f94635f90d6f91e06a557bfe7d544cdd560067128b2b7825dcbc645f941247bd",
            ),
            _text(
                "aces.relations",
                99426,
                "11a15800a751b6f9413078a021d49c7cda85a768c2a465433b4fae7ef57b03d5",
            ),
            held_out=False,
        ),
        Dataset(
            "fr079",
            _bag(
                "fr079.orig.bag",
                2235503,
                "50d56192e2d30ca502810b81d00f08a1a6097cf5c8ee172d5dac29a0b2e7abd2",
            ),
            _text(
                "fr079.relations",
                133044,
                "7e7f06b4aca455cb68f1f23d04e7c7316c5e17773e872734c860ed7a274cdfc7",
            ),
            held_out=False,
            laser_offset=(-0.04, 0.0, 0.0),
        ),
        Dataset(
            "fr-clinic",
            _bag(
                "fr-clinic_robotlaser.orig.bag",
                2396166,
                "0b5c3f5b24d277e2a0e38b385f6c09c6cf12e490f6ae7990978f0743bf1aebaf",
            ),
            _text(
                "fr-clinic.relations",
                260314,
                "583b7bba8c1a3ef1f7ad41221c151534333e71b52f5fc267d5e343c79355300c",
            ),
            held_out=False,
        ),
        Dataset(
            "mit-csail",
            _text(
                "mit-csail.clf",
                3843167,
                "f40f31cf9e561cb2a0cb0ca2f4a809abb319543cd1b2875f6c8c6a0138559ca4",
            ),
            _text(
                "mit-csail.relations",
                98468,
                "ffd7ebe97fa1738913931e39ca643ee0a1b67de80499b0197a3d01abad0f589d",
            ),
            held_out=False,
        ),
        Dataset(
            "fr101",
            DataFile(
                "fr101.carmen.log.gz",
                "https://raw.githubusercontent.com/FilipLindhe/Task4_OccupancyGrid/"
                "706cec1053db2bc2dc050783ed7a8d71c790e7d6/MapFiles/fr101.carmen.log.gz",
                2157180,
                "7cbce8efa61dad5d9bcbfbd9cb677e63e7c9267c7c5efd2a967d2935fe740a41",
            ),
            DataFile(  # derived from the log's GMapping-corrected poses: no upstream copy
                "fr101.relations",
                "",
                139254,
                "c90fee74a8fcc31268efd58e2e6de55e356887173013713a2d4be65eaebe8e52",
            ),
            held_out=False,
        ),
        Dataset(
            "mit-killian-full",
            _bag(
                "mit-killian.clf2bag.bag",
                3040898,
                "03ed49fe8a7532440d2811bb9f1763684df0a043946c2e4cc8db7be30ee0f223",
            ),
            DataFile(  # pseudo ground truth at the bag's stamps: no upstream copy
                "mit-killian.clf2bag.relations",
                "",
                1099195,
                "ab084974f2e57e90495d9e629da3bddc0b075d1d40085f7021403b30cea66ce6",
            ),
            held_out=False,
        ),
        Dataset(
            "mit-killian",
            None,
            _text(
                "mit-killian.relations",
                426269,
                "0b0f8dfc0746f9dee20b9d6d2a47a805674fd2f5be94f0ba11876bc6e97fab4b",
            ),
            held_out=False,
        ),
    )
}
"""The known datasets by name. Files and hashes are those of ``shared/data/SOURCES.md``."""


def _known() -> str:
    return ", ".join(sorted(DATASETS))


def _dataset(name: str) -> Dataset:
    try:
        return DATASETS[name]
    except KeyError:
        raise InputError(f"unknown dataset {name!r}; known datasets: {_known()}") from None


def is_held_out(name: str) -> bool:
    """Whether ``name`` is held out from development (evaluation only); none of the
    registered datasets is (see the module docs)."""
    return _dataset(name).held_out


def search_dirs() -> list[tuple[str, Path]]:
    """The local folders looked in, in order, as ``(why, folder)``; missing ones included."""
    dirs: list[tuple[str, Path]] = []
    env = os.environ.get(ENV_VAR)
    if env:
        dirs.append((f"${ENV_VAR}", Path(env).expanduser()))
    cwd = Path.cwd().resolve()
    for anc in (cwd, *cwd.parents):
        dirs.append(("../shared/data beside the working directory", anc.parent / "shared" / "data"))
    source_root = Path(__file__).resolve().parents[2]
    dirs.append(("../shared/data beside the source tree", source_root / "shared" / "data"))
    seen: set[Path] = set()
    unique = []
    for why, d in dirs:
        if d not in seen:
            seen.add(d)
            unique.append((why, d))
    return unique


def _by_file_name(name: str) -> tuple[Dataset, str] | None:
    for ds in DATASETS.values():
        for kind, f in ds.files():
            if f.name == name:
                return ds, kind
    return None


def _looks_like_path(s: str | os.PathLike[str]) -> bool:
    if isinstance(s, os.PathLike):
        return True
    return os.sep in s or (os.altsep is not None and os.altsep in s) or s.startswith("~")


def find_dataset(
    name_or_path: str | os.PathLike[str], kind: str = "log", download: bool = False
) -> Path:
    """The path of a dataset's ``kind`` file (``"log"`` or ``"relations"``).

    ``name_or_path`` is an existing file (returned as is), a dataset name (``"intel"``;
    see :data:`DATASETS`) or one of the datasets' file names (``"intel.relations"``, whose
    kind then overrides ``kind``). The places looked in are in the module docstring; nothing
    is downloaded unless ``download=True``.

    Raises :class:`DatasetNotFoundError` (a :class:`~fhslam.errors.MissingInputError`) listing
    every place looked at, or naming the URL and the cause when a download fails (a network
    error, or a downloaded file whose sha256 is not the recorded one), or naming
    ``$FHSLAM_DATA`` when it is set to a path where nothing exists;
    :class:`~fhslam.errors.InputError` for an unknown name, for a
    dataset without a file of ``kind`` (mit-killian has no log), for a ``$FHSLAM_DATA`` that
    names a file (``"FHSLAM_DATA=<path>: is not a folder ..."``) and for a local copy whose
    size is not the recorded one, ``ValueError`` for an unknown kind.
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, not {kind!r}")
    p = Path(name_or_path).expanduser()
    if p.is_file():
        return p
    text = os.fspath(name_or_path)
    if text in DATASETS:
        ds = DATASETS[text]
    elif (hit := _by_file_name(text)) is not None:
        ds, kind = hit
    elif _looks_like_path(name_or_path):
        raise DatasetNotFoundError(f"{text}: no such file (and not a dataset name: {_known()})")
    else:
        raise InputError(f"unknown dataset {text!r}; known datasets: {_known()}")
    f = ds.file(kind)
    _check_env_folder(f.name)

    looked: list[str] = []
    if os.environ.get(ENV_VAR) is None:
        looked.append(f"${ENV_VAR} (not set)")
    for why, d in search_dirs():
        cand = d / f.name
        looked.append(f"{cand} ({why})")
        if cand.is_file():
            _check_size(cand, f)
            return cand

    if download and not f.url:
        raise DatasetNotFoundError(
            f"{f.name} ({ds.name} {kind}) has no copy to download (it was derived for this "
            f"benchmark); put it in ${ENV_VAR} or ../shared/data",
            f.name,
        )
    if download:
        import pooch

        try:
            got = pooch.retrieve(
                f.url, known_hash=f.known_hash, fname=f.name, path=pooch.os_cache("fhslam")
            )
        except (OSError, ValueError) as e:
            # requests' errors are OSErrors; pooch raises a ValueError for a hash mismatch
            cause = " ".join(str(e).split()) or type(e).__name__
            raise DatasetNotFoundError(
                f"could not download {f.name} for dataset {ds.name!r} from {f.url}: {cause}; "
                f"put a copy in ${ENV_VAR} or ../shared/data",
                f.name,
            ) from e
        return Path(got)

    places = "\n".join(f"  - {s}" for s in looked)
    raise DatasetNotFoundError(
        f"{f.name} ({ds.name} {kind}) not found. Looked in:\n{places}\n"
        f"Fix: set {ENV_VAR} to a folder holding {f.name}, or pass download=True "
        f"(`--download` on the command line) to fetch it from {f.url} "
        "(checked against its sha256) into the user cache."
    )


def _check_env_folder(name: str) -> None:
    """Refuse a ``$FHSLAM_DATA`` that is set (not empty) but names no folder: a file, or
    nothing at all (a typo would otherwise go unnoticed, and a copy elsewhere be used).

    Raises
    ------
    InputError
        ``"FHSLAM_DATA=<path>: is not a folder ..."``; a :class:`DatasetNotFoundError`
        ``"FHSLAM_DATA=<path>: no such folder ..."`` if nothing exists there.
    """
    env = os.environ.get(ENV_VAR)
    if not env:
        return
    d = Path(env).expanduser()
    fix = f"set {ENV_VAR} to the folder holding {name}, or unset it"
    if not d.exists():
        raise DatasetNotFoundError(
            f"{ENV_VAR}={env}: no such folder (looked for {d / name}); {fix}", str(d / name)
        )
    if not d.is_dir():
        raise InputError(f"{ENV_VAR}={env}: is not a folder (looking for {name}); {fix}")


def _check_size(path: Path, f: DataFile) -> None:
    size = path.stat().st_size
    if size != f.size:
        hint = " (a Git LFS pointer, not the data?)" if size < 1024 else ""
        raise InputError(
            f"{path}: {size} bytes, but {f.name} has {f.size} bytes{hint}; "
            f"replace it with the file from {f.url}"
        )


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def verify(name: str, download: bool = False) -> dict[str, Path]:
    """Find every file of dataset ``name`` and check its sha256; ``{kind: path}``.

    Raises :class:`~fhslam.errors.InputError` naming the file whose hash is not the recorded
    one, and :class:`DatasetNotFoundError` as :func:`find_dataset` does.
    """
    ds = _dataset(name)
    found: dict[str, Path] = {}
    for kind, f in ds.files():
        path = find_dataset(name, kind=kind, download=download)
        digest = _sha256(path)
        if digest != f.sha256:
            raise InputError(f"{path}: sha256 {digest}, but {f.name} has sha256 {f.sha256}")
        found[kind] = path
    return found


MOUNT_NOTES = {
    "fr079": (
        "the original CARMEN log states PARAM robot_frontlaser_offset -0.04 (the laser 4 cm "
        "behind the robot's centre); its bag's /tf_static publishes +0.04. The relations "
        "decide: the default SLAM gives 0.0301 m with -0.04, 0.0408 m with 0 and 0.0636 m "
        "with +0.04 (10 % of the scans dropped: 0.0308 m with -0.04, 0.0630 m with +0.04)"
    ),
}
"""Why a dataset's :attr:`Dataset.laser_offset` overrides its log file's statement."""


def _dataset_of(path: Path) -> Dataset | None:
    """The dataset whose log file ``path`` is (by file name and size), if any."""
    for ds in DATASETS.values():
        f = ds.log
        if (
            f is not None
            and path.name == f.name
            and path.is_file()
            and path.stat().st_size == f.size
        ):
            return ds
    return None


def load_log(
    source: str | os.PathLike[str],
    scan_topic: str | None = None,
    odom_topic: str | None = None,
    download: bool = False,
    max_range: float | None = None,
) -> Log:
    """A :class:`fhslam.io.Log` from a CARMEN file, a ROS bag, or a dataset name.

    ``max_range`` (metres) overrides the laser's maximum range found in the file (see
    :func:`fhslam.io.read_carmen` and :func:`fhslam.io.read_bag`): readings at or beyond it
    are no returns.

    A dataset's log file (by name, or its file found by name and size) whose stated laser
    mount is wrong gets the dataset's :attr:`Dataset.laser_offset` instead, with
    ``laser_offset_source="dataset"`` (:data:`MOUNT_NOTES` says why; so far only Freiburg
    079, whose bag has the mount's sign flipped). The readers themselves report the file as
    it is.

    Examples
    --------
    >>> log = load_log("intel")     # the bag found by :func:`find_dataset`  # doctest: +SKIP
    """
    path = Path(source)
    if not path.exists() and str(source) in DATASETS:
        path = find_dataset(str(source), "log", download=download)
    if is_bag(path):
        log = read_bag(path, scan_topic=scan_topic, odom_topic=odom_topic, max_range=max_range)
    elif scan_topic or odom_topic:
        raise InputError(f"{path}: --scan-topic/--odom-topic apply to ROS bags only")
    else:
        log = read_carmen(path, max_range=max_range)
    ds = _dataset_of(path)
    if ds is not None and ds.laser_offset is not None:
        # a known dataset whose file states its laser's mount wrongly (MOUNT_NOTES)
        log = replace(log, laser_offset=np.array(ds.laser_offset), laser_offset_source="dataset")
    return log
