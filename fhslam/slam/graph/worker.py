"""The default SLAM's back-end machinery: the thread it runs on and its cache of loop targets.

:class:`InOrder` runs the back end's calls (adding keyframes to the pose graph, closing loops,
optimising) on a thread of its own, one after another in the order given, so that on two
cores the front end tracks the next scans meanwhile; the compiled kernels release the GIL.
The back end gets the same calls in the same order either way, so the results are the same
bit for bit as running them in turn.

:class:`LoopTargetCache` keeps loop candidates' targets (clouds and point maps) between
keyframes, keyed by the exact bytes of their poses: a cached target is used only where
building it again would give the same bits.
"""

from __future__ import annotations

import contextlib
import queue
import threading
import weakref
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fhslam.scanmatch import PointMap

__all__ = ["InOrder", "LoopTargetCache"]


@dataclass(eq=False)
class _LoopTarget:
    """A loop candidate's target: the points and normals of its keyframes in its frame, and
    (built when first needed) their :class:`fhslam.scanmatch.PointMap`."""

    key: tuple
    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    point_map: PointMap | None = None

    @property
    def nbytes(self) -> int:
        m = self.point_map
        extra = 0 if m is None else sum(a.nbytes for a in (m.points, m.normals, m.starts, m.order))
        return self.points.nbytes + self.normals.nbytes + extra


class LoopTargetCache:
    """Loop candidates' targets (:class:`_LoopTarget`) kept between keyframes, least
    recently used first out beyond ``max_bytes``.

    A target is found again only under the same key: its keyframes' range and the exact
    bytes of their poses in the graph, so a cached target is used only where building it
    again would give the same bits. Keyframes old enough to be candidates get no more
    points (scans attach to the newest keyframe), so their poses are all a target depends
    on. :meth:`drop_moved` forgets the targets whose keyframes an optimisation moved.
    """

    def __init__(self, max_bytes: int = 8 << 20):
        self.max_bytes = max_bytes
        self.nbytes = 0
        self.hits = self.misses = 0
        self._targets: OrderedDict[tuple, _LoopTarget] = OrderedDict()

    def __len__(self) -> int:
        return len(self._targets)

    @staticmethod
    def key(poses: NDArray[np.float64], members: range) -> tuple:
        return members.start, members.stop, poses[members.start : members.stop].tobytes()

    def get(self, poses: NDArray[np.float64], members: range, build) -> _LoopTarget:
        """The target of keyframes ``members`` at ``poses``: cached, else from ``build()``
        (its points and normals)."""
        key = self.key(poses, members)
        target = self._targets.get(key)
        if target is not None:
            self.hits += 1
            self._targets.move_to_end(key)
            return target
        self.misses += 1
        target = self._targets[key] = _LoopTarget(key, *build())
        self.nbytes += target.nbytes
        self._evict()
        return target

    def point_map(self, target: _LoopTarget) -> PointMap:
        """``target``'s point map, built once."""
        if target.point_map is None:
            before = target.nbytes
            target.point_map = PointMap.build(target.points, target.normals)
            if self._targets.get(target.key) is target:
                self.nbytes += target.nbytes - before
                self._evict()
        return target.point_map

    def drop_moved(self, poses: NDArray[np.float64]) -> None:
        """Forget the targets whose keyframes are no longer at their key's poses."""
        for key in [k for k in self._targets if self.key(poses, range(k[0], k[1])) != k]:
            self.nbytes -= self._targets.pop(key).nbytes

    def _evict(self) -> None:
        while self.nbytes > self.max_bytes and self._targets:
            self.nbytes -= self._targets.popitem(last=False)[1].nbytes


class InOrder:
    """A thread that runs the calls given to it one after another, in the order given: the
    back end of :class:`~fhslam.slam.GraphFastHoughSLAM` (why that changes no bit: the module
    docs; a keyframe's cloud is complete before the back end reads it).

    A call that raises stops the rest; :meth:`wait` raises it. ``max_queued`` calls at most
    wait their turn (:meth:`submit` blocks beyond): the back end cannot fall far behind.
    The thread holds no reference to the calls it has run, and ends when :meth:`close` is
    called or this object is collected.
    """

    def __init__(self, max_queued: int = 256):
        self._queue: queue.Queue = queue.Queue(max_queued)
        self._failed: list[BaseException] = []
        thread = threading.Thread(
            target=InOrder._serve, args=(self._queue, self._failed), daemon=True
        )
        thread.start()
        weakref.finalize(self, InOrder._stop, self._queue)

    @staticmethod
    def _stop(jobs: queue.Queue) -> None:
        # Never blocks: at interpreter exit (Ctrl-C while the back end is behind) the queue
        # may be full, and the thread is a daemon then anyway.
        with contextlib.suppress(queue.Full):
            jobs.put_nowait(None)

    @staticmethod
    def _serve(jobs: queue.Queue, failed: list[BaseException]) -> None:
        while (job := jobs.get()) is not None:
            try:
                if not failed:
                    job[0](*job[1])
            except BaseException as e:  # re-raised by wait() in the caller's thread
                failed.append(e)
            finally:
                del job
                jobs.task_done()
        jobs.task_done()

    def submit(self, fn, *args) -> None:
        """Queue ``fn(*args)``; raises what an earlier call raised."""
        self._raise()
        self._queue.put((fn, args))

    def wait(self) -> None:
        """Block until every call given so far has run; raise what one raised."""
        self._queue.join()
        self._raise()

    def close(self) -> None:
        """Let the thread end once the calls given so far have run."""
        InOrder._stop(self._queue)

    def _raise(self) -> None:
        if self._failed:
            raise self._failed[0]
