"""Reading ROS 1 and ROS 2 bags with ``sensor_msgs/LaserScan`` and ``nav_msgs/Odometry``.

Through the pure-Python :mod:`rosbags` package (no ROS installation needed). The scan and
odometry topics are found by message type, or named by the user. Each scan gets the odometry
pose interpolated at its header stamp; the laser's mount on the robot comes from
``/tf_static`` (``base_link`` → laser), when the bag has it.

Beam angles. Bags converted from old CARMEN ``FLASER`` logs carry no real angle information:
the converter wrote ``angle_min = -π/2`` and ``angle_increment = π/(n−1)``. For such scans
(``beams="carmen"``, the default) fhslam uses CARMEN's own rule instead — "if no information
is given, assume 1.0° resolution": :func:`fhslam.io.flaser_angles`, the same rule as for
``.clf`` files (``-90° + k · 1°`` for 180 or 181 beams, ``-90° + k · 0.5°`` for 360 or 361; for
181 and 361 beams it agrees with the converter). A bag whose increment is anything else (e.g.
from ``ROBOTLASER1`` lines, which state it) is taken as it is.

Maximum range: the bag's ``range_max``, or the log's detected "no return" code if smaller
(:func:`fhslam.io.log.no_return_reading`; the Freiburg hospital bag states 81.9 m but codes
no return as 81.83 and 81.91 m). The code is sought in the upper half of ``range_max``
only: a value read over and over far below it (a wall 2 m ahead in every scan of a robot
standing still) is a distance, not a code.

What no laser or odometry gives is a :class:`BagFormatError` naming the file, the topic and
the message (counted from 0 in the bag's order): a scan whose ``range_max`` is not a positive
number of metres below 1000 m (:func:`fhslam.io.log.stated_range_problem`: 0, -1, NaN,
inf), whose ``angle_min`` is not finite or beyond ±2π, whose ``angle_increment`` is not
positive (0, negative, NaN) or spreads its beams over more than 360°; a bag whose widest
scan has fewer than two beams; an odometry pose (or the ``/tf_static`` laser mount) with a
non-finite position or a quaternion that is not finite or not of unit length (tf2's rule:
its squared norm within 0.01 of 1; an all-zero quaternion is no rotation). Ignoring such a
field would only hide a corrupt bag. Readings of +inf, -inf and NaN are REP 117's codes
(no return, too close, invalid): no returns, without a warning.

Damaged data is a :class:`BagFormatError` too, and nothing is skipped: a bag that cannot be
opened names where its records first break (``its records break at byte N (record k, after
c chunks): ...``); a message that cannot be read names the message, its topic and, in a ROS 1
bag, its chunk and the chunk's bytes in the file (a chunk that does not decompress, a record
header or a message that does not parse). A compressed bag loses a damaged chunk's messages
together, hundreds of scans: a bag read with such a hole would pass for a whole one.

An interlaced laser, whose scans share the increment but start up to one beam apart (the
Freiburg hospital log: four layouts a quarter degree apart, 181 or 180 beams), is read with
the first layout's bearings and a per-scan ``Log.angle_offsets``; other mixed layouts are
refused. ``beams="bag"`` always takes the bag's values.
"""

from __future__ import annotations

import heapq
import itertools
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fhslam.errors import InputError, InputWarning
from fhslam.geometry import wrap_angle
from fhslam.io.carmen import flaser_angles
from fhslam.io.files import input_path
from fhslam.io.log import (
    Log,
    check_readings,
    check_sequence,
    effective_max_range,
    plural,
    stated_range_problem,
)

SCAN_TYPE = "sensor_msgs/msg/LaserScan"
ODOM_TYPE = "nav_msgs/msg/Odometry"


class BagFormatError(InputError):
    """A bag that cannot be read as a laser log (names the file and the topic)."""


class BagWarning(InputWarning):
    """A bag that is readable but implausible (scans out of time order, odometry jumps,
    impossible readings, scans without a return); read as documented, the file named."""


def is_bag(path: str | PathLike[str]) -> bool:
    """Whether a file is a ROS 1 bag (``#ROSBAG`` magic) or a ROS 2 bag folder/db3/mcap."""
    p = Path(path)
    if p.is_dir():
        return (p / "metadata.yaml").exists()
    if not p.is_file():  # missing, or a FIFO or device: opening it may block forever
        return False
    if p.suffix in (".db3", ".mcap"):
        return True
    try:
        with open(p, "rb") as f:
            return f.read(9) == b"#ROSBAG V"
    except OSError:
        return False


def _yaw(q) -> float:
    return float(np.arctan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y**2 + q.z**2)))


QUATERNION_TOLERANCE = 0.01
"""How far a quaternion's squared norm may be from 1 (tf2 refuses a transform beyond it)."""


def _pose_problem(position, q) -> str | None:
    """Why a ``(position, orientation)`` is no pose a robot can have, or ``None``."""
    xy = (float(position.x), float(position.y))
    if not all(np.isfinite(xy)):
        return f"non-finite position (x {xy[0]!r}, y {xy[1]!r})"
    quat = np.array([q.x, q.y, q.z, q.w], dtype=float)
    if not np.all(np.isfinite(quat)):
        return f"non-finite orientation quaternion {quat.tolist()}"
    with np.errstate(over="ignore"):  # a damaged quaternion: its norm is inf
        norm2 = float(quat @ quat)
    if abs(norm2 - 1.0) > QUATERNION_TOLERANCE:
        return (
            f"orientation quaternion {quat.tolist()} is not a rotation: its squared norm "
            f"{norm2:.6g} is not 1 (within {QUATERNION_TOLERANCE:g})"
        )
    return None


def _scan_problem(m) -> str | None:
    """Why a ``LaserScan`` message states a layout or range no laser has, or ``None``."""
    problem = stated_range_problem(float(m.range_max))
    if problem is not None:
        return f"range_max {problem}"
    a0, inc, n = float(m.angle_min), float(m.angle_increment), len(m.ranges)
    if not (np.isfinite(a0) and abs(a0) <= 2 * np.pi):
        return f"angle_min {a0:g} rad is not an angle within a full turn"
    if n < 2:
        return None  # no layout to check (the reader refuses a bag without a wider scan)
    if not (np.isfinite(inc) and inc > 0):
        return f"angle_increment {inc:g} rad: the angle between beams must be positive"
    if (n - 1) * inc > 2 * np.pi + 1e-6:
        return (
            f"angle_increment {inc:g} rad spreads its {n} beams over "
            f"{np.degrees((n - 1) * inc):g} degrees, more than a full turn"
        )
    return None


def _pick(reader, msgtype: str, topic: str | None, what: str, path: Path):
    conns = [c for c in reader.connections if c.msgtype == msgtype]
    if topic is not None:
        named = [c for c in reader.connections if c.topic == topic]
        if not named:
            have = sorted({c.topic for c in reader.connections})
            raise BagFormatError(f"{path}: no topic {topic!r} in the bag (topics: {have})")
        if named[0].msgtype != msgtype:
            raise BagFormatError(f"{path}: topic {topic!r} is {named[0].msgtype}, not {msgtype}")
        return named
    topics = sorted({c.topic for c in conns})
    if not topics:
        raise BagFormatError(f"{path}: the bag has no {what} ({msgtype}) topic")
    if len(topics) > 1:
        raise BagFormatError(
            f"{path}: several {what} topics {topics}; name one (--scan-topic/--odom-topic)"
        )
    return conns


def read_bag(
    path: str | PathLike[str],
    scan_topic: str | None = None,
    odom_topic: str | None = None,
    beams: str = "carmen",
    max_range: float | None = None,
) -> Log:
    """Read a ROS 1/2 bag into a :class:`Log` (timestamps = the scans' header stamps).

    Parameters
    ----------
    path : path-like
        A ROS 1 ``.bag`` file, or a ROS 2 bag folder.
    scan_topic, odom_topic : str, optional
        Topics to use; found by message type when omitted.
    beams : {"carmen", "bag"}
        Bearing convention for bags converted from old CARMEN logs (see the module docs).
    max_range : float, optional
        The laser's maximum range, metres (readings at or beyond it mean "no return");
        default: the bag's ``range_max`` or the detected "no return" code (module docs).

    Raises
    ------
    BagFormatError
        No scans, no odometry, ambiguous or unknown topics, odometry that does not cover
        the scans, scans whose angle layouts differ, or what no laser or odometry gives
        (module docs): a bad ``range_max``, ``angle_min`` or ``angle_increment``, scans of
        fewer than two beams, a non-finite pose or a quaternion that is no rotation.

    Warns
    -----
    BagWarning
        Scans whose header stamps are out of order in the bag (they are sorted by stamp),
        repeat or leap forward more than a day; odometry jumps; negative readings or
        readings beyond 1000 m (read as no return; NaN and ±inf are ROS's own codes,
        REP 117, read as no return without a warning); scans without a return; more than
        10,000 beams (:func:`fhslam.io.log.check_readings`). Without ``max_range``: a
        ``range_max`` or no-return code well below readings the bag repeats, which are then
        read as no return (:func:`fhslam.io.log.effective_max_range`).
    """
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    if beams not in ("carmen", "bag"):
        raise ValueError(f"beams must be 'carmen' or 'bag', got {beams!r}")
    p = Path(path)
    if not p.is_dir():  # a ROS 2 bag is a folder; else a regular file (a FIFO would block)
        input_path(p, "bag")  # raises MissingInputError, or InputError for a non-file
    try:
        reader = AnyReader([p], default_typestore=get_typestore(Stores.ROS1_NOETIC))
        reader.open()
    except Exception as e:  # rosbags raises its own error types for unreadable files
        raise BagFormatError(
            f"{p}: not a readable ROS bag ({_reason(e)}){_record_damage(p)}"
        ) from e
    try:
        scan_conns = _pick(reader, SCAN_TYPE, scan_topic, "laser scan", p)
        odom_conns = _pick(reader, ODOM_TYPE, odom_topic, "odometry", p)
        scans = _read_scans(reader, scan_conns, p)
        odo_t, odo = _read_odometry(reader, odom_conns, p)
        offset = _laser_offset(reader, p)
    finally:
        reader.close()

    rr = scans.ranges_array()
    n = rr.shape[1]
    a0, inc = scans.a0, scans.inc
    converted = abs(inc - np.pi / (n - 1)) < 1e-6
    angles = flaser_angles(n) if beams == "carmen" and converted else a0 + inc * np.arange(n)
    stated = scans.range_max
    if max_range is None:
        in_time = rr[np.argsort(scans.stamps, kind="stable")]  # repeated scans are found in order
        max_range, _ = effective_max_range(in_time, stated, stated, p, BagWarning)
    else:
        max_range = float(max_range)
    t = np.asarray(scans.stamps)
    order = np.argsort(t, kind="stable")
    odometry = _interpolate_poses(np.asarray(odo_t), np.asarray(odo), t[order], p)  # may refuse
    back = np.diff(t) < 0
    if back.any():
        k = int(np.flatnonzero(back)[0])
        warnings.warn(
            f"{p}: the header stamp goes back in time at {plural(int(back.sum()), 'scan')} of "
            f"the bag (first: scan {k + 1}, {float(t[k + 1])!r} after {float(t[k])!r}); the "
            "scans are sorted by stamp",
            BagWarning,
            stacklevel=2,
        )
    check_sequence(p, t[order], odometry, None, BagWarning)
    check_readings(p, rr[order], max_range, None, BagWarning, non_finite=False)
    return Log(
        name=p.stem.replace(".orig", ""),
        timestamps=t[order],
        ranges=rr[order],
        angles=angles,
        odometry=odometry,
        max_range=max_range,
        laser_offset=offset,
        angle_offsets=scans.angle_offsets(order),
        laser_offset_source="tf_static",
        stated_max_range=stated,
    )


def _stamp(m) -> float:
    """A message's header stamp, seconds."""
    return m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec


@dataclass
class _Scans:
    """The scans of a bag's laser topic in the bag's order (:func:`_read_scans`)."""

    stamps: list[float]  # header stamps
    ranges: list[NDArray[np.float64]]
    starts: list[float]  # angle_min of each scan
    layouts: set[tuple[float, float]]  # the (angle_min, angle_increment) met, rounded
    range_max: float  # the largest range_max stated
    a0: float  # angle_min of the first layout (the smallest)
    inc: float  # its angle_increment, which every layout shares

    def ranges_array(self) -> NDArray[np.float64]:
        """The readings as one array (T, B), B the widest scan's beams."""
        n = max(len(r) for r in self.ranges)
        rr = np.full((len(self.ranges), n), np.nan)
        for k, r in enumerate(self.ranges):
            rr[k, : len(r)] = r  # shorter scans of the same layout: missing beams are invalid
        return rr

    def angle_offsets(self, order: NDArray[np.intp]) -> NDArray[np.float64] | None:
        """Each scan's start beyond the first layout's, in ``order`` (an interlaced laser),
        or ``None`` where all scans share one layout."""
        return (np.asarray(self.starts)[order] - self.a0) if len(self.layouts) > 1 else None


def _read_scans(reader, conns, path: Path) -> _Scans:
    """The scans of the laser topic ``conns``; a scan stating what no laser has (module
    docs), no scans, no scan of two beams or more, and layouts that differ other than as an
    interlaced laser's are a :class:`BagFormatError`."""
    stamps, ranges, layouts, range_max, starts = [], [], set(), 0.0, []
    widest = (0, 0)  # beams, scan index
    for k, conn, m in _messages(reader, conns, "scan", path):
        problem = _scan_problem(m)
        if problem is not None:
            raise BagFormatError(f"{path}: scan {k} of topic {conn.topic!r}: {problem}")
        widest = max(widest, (len(m.ranges), -k))
        stamps.append(_stamp(m))
        ranges.append(np.asarray(m.ranges, dtype=float))
        layouts.add((round(float(m.angle_min), 6), round(float(m.angle_increment), 7)))
        starts.append(float(m.angle_min))
        range_max = max(range_max, float(m.range_max))
    if not stamps:
        raise BagFormatError(f"{path}: topic {conns[0].topic!r} holds no scans")
    if widest[0] < 2:
        raise BagFormatError(
            f"{path}: scan {-widest[1]} of topic {conns[0].topic!r}: the widest scan "
            f"has {plural(widest[0], 'beam')}; a laser scan has at least 2"
        )
    a0, inc = min(layouts)
    interlaced = all(i == inc and 0 <= a - a0 < inc for a, i in layouts)
    if len(layouts) > 1 and not interlaced:
        raise BagFormatError(f"{path}: scans with different angle layouts {sorted(layouts)}")
    return _Scans(stamps, ranges, starts, layouts, range_max, a0, inc)


def _read_odometry(reader, conns, path: Path) -> tuple[list[float], list[tuple]]:
    """The stamps and poses ``(x, y, yaw)`` of the odometry topic ``conns``; no odometry, or
    a pose no robot can have, is a :class:`BagFormatError`."""
    odo_t, odo = [], []
    for k, conn, m in _messages(reader, conns, "odometry message", path):
        odo_t.append(_stamp(m))
        pose = m.pose.pose
        problem = _pose_problem(pose.position, pose.orientation)
        if problem is not None:
            raise BagFormatError(f"{path}: odometry message {k} of topic {conn.topic!r}: {problem}")
        odo.append((pose.position.x, pose.position.y, _yaw(pose.orientation)))
    if not odo_t:
        raise BagFormatError(f"{path}: topic {conns[0].topic!r} holds no odometry")
    return odo_t, odo


def _laser_offset(reader, path: Path) -> NDArray[np.float64]:
    """``base_link`` → laser from ``/tf_static`` (zero when the bag has none)."""
    for conn in reader.connections:
        if conn.msgtype != "tf2_msgs/msg/TFMessage" or "static" not in conn.topic:
            continue
        for k, _c, m in _messages(reader, [conn], "message", path):
            for tr in m.transforms:
                if "laser" in tr.child_frame_id:
                    v, q = tr.transform.translation, tr.transform.rotation
                    problem = _pose_problem(v, q)
                    if problem is not None:
                        raise BagFormatError(
                            f"{path}: message {k} of topic {conn.topic!r}, the laser mount "
                            f"{tr.child_frame_id!r}: {problem}"
                        )
                    return np.array([v.x, v.y, _yaw(q)])
    return np.zeros(3)


def _messages(reader, conns, what: str, path: Path) -> Iterator[tuple[int, Any, Any]]:
    """``(k, connection, message)`` for the messages of ``conns`` (one topic) in the bag's
    order, ``k`` counting from 0, each deserialized. Data that cannot be read (a chunk that
    does not decompress, a record header or a message that does not parse) is a
    :class:`BagFormatError` naming the message, and in a ROS 1 bag the chunk and its bytes in
    the file: the messages of a damaged chunk are lost together (hundreds of scans in a
    compressed bag), so the bag is refused rather than read with a hole."""
    topic = conns[0].topic
    messages = reader.messages(connections=conns)
    k = 0
    while True:
        try:
            conn, _t, raw = next(messages)
        except StopIteration:
            return
        except Exception as e:  # rosbags and its decompressors raise many types
            raise BagFormatError(
                f"{path}: {what} {k} of topic {topic!r}: damaged data{_chunk_of(reader, conns, k)}"
                f", the bag cannot be read past it ({_reason(e)})"
            ) from e
        try:
            m = reader.deserialize(raw, conn.msgtype)
        except Exception as e:  # as above: the message's bytes are damaged
            raise BagFormatError(
                f"{path}: {what} {k} of topic {topic!r}: damaged data"
                f"{_chunk_of(reader, conns, k)}, not a {conn.msgtype} ({_reason(e)})"
            ) from e
        yield k, conn, m
        k += 1


def _reason(e: BaseException) -> str:
    """An exception as a few words: its type and its message, on one line."""
    text = " ".join(str(e).split())
    return f"{type(e).__name__}: {text}" if text else type(e).__name__


def _chunk_of(reader, conns, k: int) -> str:
    """Where in a ROS 1 bag the ``k``-th message of ``conns`` lies: ``" in chunk 4 of 17
    (bytes 344123-398000 of the file)"``; ``""`` where that is not known (a ROS 2 bag)."""
    try:
        (bag,) = reader.readers
        entries = heapq.merge(*(bag.indexes[c.id] for c in conns))
        entry = next(itertools.islice(entries, k, None))
        starts = sorted(bag.chunks)
        chunk = bag.chunks[entry.chunk_pos]
        return (
            f" in chunk {starts.index(entry.chunk_pos) + 1} of {len(starts)} (bytes "
            f"{chunk.datapos}-{chunk.datapos + chunk.datasize} of the file)"
        )
    except Exception:  # only a detail of the message: left out if unknown
        return ""


ROS1_OPS = {2: "a message data", 3: "the bag header", 4: "an index data", 5: "a chunk",
            6: "a chunk info", 7: "a connection"}  # fmt: skip
"""The record types of a ROS 1 bag (its ``op`` header field)."""

MAX_RECORD_HEADER = 1 << 20
"""Longest record header taken for one, bytes (a ROS 1 bag's are tens to hundreds)."""


def _record_damage(path: Path) -> str:
    """Where the records of a ROS 1 bag first break, for the message of a bag that cannot be
    opened: ``"; its records break at byte 688663 (record 34, after 8 chunks): ..."``, or
    ``""`` where they do not (or the file is no ROS 1 bag). A record is a header (its length,
    then ``name=value`` fields, ``op`` among them) and data (its length, then the bytes)."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            if f.read(13) != b"#ROSBAG V2.0\n":
                return ""
            pos, k, chunks = 13, 0, 0
            while pos < size:
                op, n, m, why = _record_at(f, pos, size)
                if why is not None:
                    where = f"byte {pos} (record {k}, after {chunks} chunks)"
                    return f"; its records break at {where}: {why}"
                chunks += op == 5
                pos += 8 + n + m
                f.seek(pos)
                k += 1
    except OSError:
        return ""
    return ""


def _record_at(f, pos: int, size: int) -> tuple[int, int, int, str | None]:
    """The record at ``pos`` of an open bag of ``size`` bytes: its ``op``, the lengths of its
    header and its data, and why it is damaged (``None``: it is not)."""
    head = f.read(4)
    if len(head) < 4:
        return 0, 0, 0, "the file ends inside a record's header length"
    n = int.from_bytes(head, "little")
    if n > min(size - pos - 4, MAX_RECORD_HEADER):
        return 0, n, 0, f"a record header of {n} bytes, in a file of {size}"
    op, why = _record_op(f.read(n))
    if why is not None:
        return op, n, 0, why
    data = f.read(4)
    if len(data) < 4:
        return op, n, 0, f"the file ends inside the data length of {ROS1_OPS[op]} record"
    m = int.from_bytes(data, "little")
    if pos + 8 + n + m > size:
        return (
            op,
            n,
            m,
            (
                f"{ROS1_OPS[op]} record of {m} bytes of data runs past the end of the file "
                f"({size} bytes; cut short?)"
            ),
        )
    return op, n, m, None


def _record_op(header: bytes) -> tuple[int, str | None]:
    """A record header's ``op`` code, and why the header is damaged (``None``: it is not)."""
    fields, i = {}, 0
    while i < len(header):
        n = int.from_bytes(header[i : i + 4], "little")
        field = header[i + 4 : i + 4 + n]
        if i + 4 + n > len(header) or b"=" not in field:
            return 0, f"a damaged field in a record header at byte {i} of its {len(header)}"
        name, _, value = field.partition(b"=")
        fields[name] = value
        i += 4 + n
    op = fields.get(b"op", b"")
    if len(op) != 1 or op[0] not in ROS1_OPS:
        return 0, f"a record header without a known record type (op {op!r})"
    return op[0], None


def _interpolate_poses(t_src, poses, t_query, path) -> NDArray[np.float64]:
    """Odometry poses at the scan stamps: linear in x, y and in the unwrapped heading."""
    order = np.argsort(t_src, kind="stable")
    t_src, poses = t_src[order], poses[order]
    late = t_query[t_query > t_src[-1] + 1.0]
    early = t_query[t_query < t_src[0] - 1.0]
    if len(late) or len(early):
        raise BagFormatError(
            f"{path}: odometry covers {t_src[0]:.3f}-{t_src[-1]:.3f} s but "
            f"{len(late) + len(early)} scans lie more than 1 s outside it"
        )
    heading = np.unwrap(poses[:, 2])
    out = np.column_stack(
        [np.interp(t_query, t_src, poses[:, 0]), np.interp(t_query, t_src, poses[:, 1]),
         np.interp(t_query, t_src, heading)]
    )  # fmt: skip
    out[:, 2] = wrap_angle(out[:, 2])
    return out
