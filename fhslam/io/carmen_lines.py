"""Reading a CARMEN text log as a stream of text lines (:func:`_text_lines`).

The file is read as UTF-8 text lines (``\\n``, ``\\r\\n`` or ``\\r`` ending a line), in
pieces of at most :data:`MAX_LINE` characters, so that memory follows the scans kept, not
the size of the file; a byte-order mark at its start is skipped. A line that is not text --
holding NUL bytes or bytes that are not UTF-8, or longer than :data:`MAX_LINE` (a stretch of
binary data; the NUL bytes a crash leaves at the end of a file) -- is not yielded but
recorded (:class:`_Unreadable`: its line, its bytes and why), for the reader's one
:class:`~fhslam.io.carmen_format.CarmenWarning` (or, in a file without a laser message, its
:class:`~fhslam.io.carmen_format.CarmenFormatError`: not a CARMEN text log). A file that
starts with gzip's magic bytes (``fr101.carmen.log.gz``) is decompressed as a stream;
damaged or cut compressed data is a :class:`~fhslam.io.carmen_format.CarmenFormatError`
naming the file and how far it was read.
"""

from __future__ import annotations

import codecs
import gzip
import io
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from fhslam.io.carmen_format import CarmenFormatError

MAX_LINE = 1 << 20
"""The longest line read, in characters (1 MiB of text; a laser line of 100,000 beams is
about 400 kB). A longer stretch without a line break is not a CARMEN line: it is skipped as
unreadable, read in pieces of this size, so that no more of it is ever held in memory."""


@dataclass
class _Unreadable:
    """The lines of a file that are not text (see :func:`_text_lines`), for one warning."""

    lines: int = 0
    nbytes: int = 0
    first_line: int = 0
    start: int = 0  # byte offset of the first unreadable line
    last_line: int = 0
    end: int = 0  # byte offset just past the last one
    reasons: set[str] = field(default_factory=set)
    size: int = 0  # bytes read in all
    gzip: bool = False  # the file starts with gzip's magic bytes

    def add(self, lineno: int, start: int, end: int, reason: str) -> None:
        if self.last_line != lineno:
            self.lines += 1
        if not self.first_line:
            self.first_line, self.start = lineno, start
        self.last_line, self.end = lineno, end
        self.nbytes += end - start
        self.reasons.add(reason)

    def describe(self) -> str:
        """``"N bytes that are not text (why) from byte X (line A) to ..."``."""
        why = ", ".join(sorted(self.reasons))
        end = "the end of the file" if self.end == self.size else f"byte {self.end}"
        if self.lines == 1:
            where = f"from byte {self.start} (line {self.first_line}) to {end}"
        else:
            where = (
                f"in {self.lines} lines from byte {self.start} (line {self.first_line}) to "
                f"{end} (line {self.last_line})"
            )
        return f"{self.nbytes} bytes that are not text ({why}) {where}"


class _Gunzipped(gzip.GzipFile):
    """A gzip-compressed file read as its text: damaged or cut compressed data is a
    :class:`CarmenFormatError` naming the file and how far it was read."""

    def __init__(self, raw: IO[bytes], path: Path) -> None:
        super().__init__(fileobj=raw, mode="rb")
        self._path, self._raw = path, raw

    def read(self, size: int = -1) -> bytes:
        return self._named(super().read, size)

    def read1(self, size: int = -1) -> bytes:
        return self._named(super().read1, size)

    def _named(self, read, size: int) -> bytes:
        try:
            return read(size)
        except (EOFError, OSError, zlib.error) as e:
            raise CarmenFormatError(
                f"{self._path}: damaged gzip data at about byte {self._raw.tell()} of the "
                f"compressed file ({e}); the log cannot be read past it"
            ) from None


def _text_lines(path: Path, junk: _Unreadable) -> Iterator[tuple[int, str]]:
    """The lines of the file ``path`` that are text, as ``(line number, line)``: decoded as
    UTF-8 (after gzip's decompression where the file starts with its magic bytes; byte
    offsets are then those of the decompressed text), a byte-order mark at the start
    skipped, any line break (``\\n``, ``\\r\\n``, ``\\r``) ending a line, as a text file
    is read. A line holding NUL bytes or bytes that are
    not UTF-8, or longer than :data:`MAX_LINE`, is not yielded but recorded in ``junk``. The
    file is read in pieces of at most :data:`MAX_LINE` characters."""
    with path.open("rb") as raw:
        junk.gzip = raw.read(2) == b"\x1f\x8b"
        raw.seek(0)
        f = _Gunzipped(raw, path) if junk.gzip else raw
        head = f.read(3)
        offset = 3 if head == codecs.BOM_UTF8 else 0
        f.seek(offset)
        text = io.TextIOWrapper(f, encoding="utf-8", errors="surrogateescape", newline="")
        with text:
            readline = text.readline
            lineno = 0
            long_line = False  # the last piece was cut at MAX_LINE: this one continues it
            while piece := readline(MAX_LINE):
                start = offset
                if piece.isascii():
                    offset += len(piece)
                    reason = "NUL bytes" if "\x00" in piece else None
                else:
                    try:
                        offset += len(piece.encode("utf-8"))
                        reason = "NUL bytes" if "\x00" in piece else None
                    except UnicodeEncodeError:  # a byte that is not UTF-8, as a surrogate
                        offset += len(piece.encode("utf-8", "surrogateescape"))
                        reason = "bytes that are not UTF-8"
                if not long_line:
                    lineno += 1
                cut = len(piece) == MAX_LINE and piece[-1] not in "\r\n"
                if long_line or cut:
                    reason = reason or f"a line of more than {MAX_LINE} characters"
                long_line = cut
                if reason is None:
                    yield lineno, piece
                else:
                    junk.add(lineno, start, offset, reason)
    junk.size = offset
