"""How a results file proves it is intact: checksums on its data and its text, and the rows that read back whole.

The store writes every dataset with HDF5's Fletcher32 checksum filter (a chunk
whose bytes changed fails to read), in the HDF5 1.8 file format, whose object
headers (attributes, dataset shapes) carry checksums of their own. A text
attribute ``name`` (JSON, the model text, the status) is a fixed-length UTF-8
string, kept in the checksummed header (a variable-length one lives in a heap
without checksums, where one flipped byte made HDF5 loop for ever in a test),
and has its CRC-32 in ``name_crc32`` (a text over 64 KiB lives outside the
header). The 1.10 format would checksum the chunk indexes too, but it marks a
file open for writing in its superblock and refuses to open it after a kill.
The reader (:mod:`srdda.io.results_reader`) uses the functions here to find
what is damaged and how many leading rows of each dataset read back whole.
Files written before the checksums still read: they are checked for order and
lengths only.
"""
from __future__ import annotations

import io
import json
import os
import zlib
from dataclasses import dataclass
from typing import Any

import h5py
import numpy as np

__all__ = ["LIBVER", "checksummed", "write_text", "read_attr", "read_text", "read_json", "read_intact",
           "ordered_prefix", "DamagedError", "CutShortFile", "describe_error", "Rows"]

LIBVER = ("v108", "v108")  # checksummed object headers; readable by HDF5 1.8 (2008) and later
CRC_SUFFIX = "_crc32"


class DamagedError(ValueError):
    """A part of a results file does not read back as it was written; the message names it."""


class CutShortFile(io.RawIOBase):
    """A file cut short (a copy that stopped, a full disk), read as if zeros followed its end.

    HDF5 refuses a file shorter than its superblock says; read through this,
    it opens, and whatever lay beyond the cut fails its checksum (found as
    damage) instead of the whole file being lost. ``size`` is where it was cut.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self._fh = open(path, "rb")
        self.size = os.fstat(self._fh.fileno()).st_size
        self._pos = 0

    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def seek(self, offset: int, whence: int = io.SEEK_SET) -> int:
        end = self.size + (1 << 40)  # far beyond any end the superblock may give
        self._pos = offset if whence == io.SEEK_SET else self._pos + offset if whence == io.SEEK_CUR else end + offset
        return self._pos

    def tell(self) -> int:
        return self._pos

    def readinto(self, buffer: Any) -> int:
        view = memoryview(buffer).cast("B")
        self._fh.seek(self._pos)
        data = self._fh.read(max(0, min(len(view), self.size - self._pos)))
        view[:len(data)] = data
        view[len(data):] = bytes(len(view) - len(data))
        self._pos += len(view)
        return len(view)

    def close(self) -> None:
        self._fh.close()
        super().close()


def describe_error(exc: BaseException) -> str:
    """An h5py error in a few words: the reason HDF5 gives (in parentheses at the end), else the first line."""
    text = (str(exc).strip("'\"").splitlines() or [type(exc).__name__])[0]  # a KeyError's text comes quoted
    if "(" in text and text.endswith(")"):
        reason = text[text.rindex("(") + 1:-1]
        return {"incorrect metadata checksum after all read attempts": "its metadata fails its checksum",
                "data error detected by Fletcher32 checksum": "its checksum fails"}.get(reason, reason)
    return text


def checksummed(value: np.ndarray) -> dict[str, Any]:
    """Dataset-creation keywords that add the Fletcher32 filter (not for empty or scalar arrays: nothing to chunk)."""
    return {"fletcher32": True} if value.ndim and value.size else {}


def write_text(obj: h5py.HLObject, name: str, text: str) -> None:
    """Set the text attribute ``name`` of ``obj`` and its CRC-32."""
    data = text.encode("utf-8")
    obj.attrs.create(name, np.array(data, dtype=f"S{max(1, len(data))}"))
    obj.attrs[name + CRC_SUFFIX] = np.uint32(zlib.crc32(data))


def read_attr(obj: h5py.HLObject, name: str, default: Any = DamagedError) -> Any:
    """The attribute ``name`` of ``obj`` (``default`` when it has none, if given); :class:`DamagedError` if it
    cannot be read (a damaged header) or is missing."""
    try:
        if name not in obj.attrs:
            if default is DamagedError:
                raise DamagedError(f"the attribute {name!r} of {obj.name} is missing")
            return default
        return obj.attrs[name]
    except (KeyError, OSError, RuntimeError, ValueError, TypeError) as exc:
        raise DamagedError(f"the attribute {name!r} of {obj.name} cannot be read ({describe_error(exc)})") from None


def read_text(obj: h5py.HLObject, name: str) -> str:
    """The text attribute ``name`` of ``obj``; :class:`DamagedError` if it is missing, unreadable or changed."""
    where = f"the attribute {name!r} of {obj.name}"
    value = read_attr(obj, name)
    crc = read_attr(obj, name + CRC_SUFFIX, None)
    if isinstance(value, bytes):
        try:
            value = value.decode("utf-8")
        except UnicodeDecodeError:
            raise DamagedError(f"{where} is not text") from None
    if not isinstance(value, str):
        raise DamagedError(f"{where} is not text")
    if crc is not None and int(crc) != zlib.crc32(value.encode("utf-8", "surrogateescape")):
        raise DamagedError(f"{where} does not match its checksum")
    return value


def read_json(obj: h5py.HLObject, name: str, kind: type | tuple[type, ...]) -> Any:
    """The JSON attribute ``name`` of ``obj``, which must decode to ``kind``; :class:`DamagedError` if not."""
    text = read_text(obj, name)
    try:
        value = json.loads(text)
    except (ValueError, RecursionError):
        raise DamagedError(f"the attribute {name!r} of {obj.name} is not JSON") from None
    if not isinstance(value, kind):
        raise DamagedError(f"the attribute {name!r} of {obj.name} is not a JSON {getattr(kind, '__name__', kind)}")
    return value


@dataclass(frozen=True)
class Rows:
    """What of a dataset reads back: its ``length`` rows, of which the first ``good`` (``data``, when kept).

    ``damaged``: the first rows of the chunks that fail (each ``chunk`` rows
    long); ``problem``: what is damaged, in words (None when nothing is).
    """

    data: np.ndarray
    good: int
    length: int = 0
    problem: str | None = None
    damaged: tuple[int, ...] = ()
    chunk: int = 1

    def intact(self, start: int, stop: int) -> bool:
        """True if rows ``start:stop`` read back whole."""
        return stop <= self.length and not any(first < stop and start < first + self.chunk for first in self.damaged)


def read_intact(group: h5py.Group, name: str, keep: bool = True) -> Rows:
    """Read dataset ``name`` chunk by chunk where it fails, and say which rows read back whole.

    The rows up to the first failing chunk are returned (``keep=False``: none,
    the rows are only checked). A chunk fails when its checksum does not match,
    when HDF5 cannot read its storage, or when its index entry is damaged
    (:func:`_zero_chunks_not_found`, :func:`_unindexed_rows`).
    """
    where = f"{group.name.rstrip('/')}/{name}"
    try:
        ds = group[name]
        n = ds.shape[0]
        row_bytes = max(1, ds.dtype.itemsize * int(np.prod(ds.shape[1:], dtype=np.int64)))
    except (OSError, RuntimeError, ValueError, KeyError, IndexError, TypeError) as exc:
        return Rows(np.zeros(0), 0, 0, f"{where} cannot be read ({describe_error(exc)})")
    chunk = ds.chunks[0] if ds.chunks else max(n, 1)
    block = chunk * max(1, (64 << 20) // (row_bytes * chunk))  # read ~64 MiB at a time, whole chunks
    parts: list[np.ndarray] = []
    checksum: list[int] = []
    index: list[int] = []
    for start in range(0, n, block):
        stop = min(n, start + block)
        try:
            pieces = [(start, ds[start:stop])]
        except (OSError, RuntimeError, ValueError):
            pieces = []
            for first in range(start, stop, chunk):  # find the chunks that fail
                try:
                    pieces.append((first, ds[first:min(stop, first + chunk)]))
                except (OSError, RuntimeError, ValueError):
                    checksum.append(first)
        for first, rows in pieces:
            index += _zero_chunks_not_found(ds, rows, first, chunk)
            if keep and not checksum and not index:  # the rows before the first damage
                parts.append(rows)
            elif keep:
                first_damage = min(checksum + index)
                parts += [rows[: max(0, first_damage - first)]] if first < first_damage else []
    index = sorted(set(index) | set(_unindexed_rows(ds, n)))
    damaged = tuple(sorted(set(checksum) | set(index)))
    good = damaged[0] if damaged else n
    kept = np.concatenate(parts)[:good] if parts else np.zeros((0, *ds.shape[1:]), dtype=ds.dtype)
    if not damaged:
        return Rows(kept, n, n)
    why = "its checksum fails" if good in checksum else "its chunk index is damaged"
    return Rows(kept, good, n, f"{where} from row {good} ({why})", damaged, chunk)


def _zero_chunks_not_found(ds: h5py.Dataset, rows: np.ndarray, start: int, chunk: int) -> list[int]:
    """The first rows of the chunks that read as all zeros because HDF5's lookup no longer finds them.

    A damaged key of HDF5 1.8's chunk index (it has no checksum) can hide a
    chunk from the lookup: its rows then read as the fill value, zeros, with no
    error. Chunks that read as zeros are looked up once more, raw.
    """
    if not ds.chunks or ds.chunks[1:] != tuple(max(d, 1) for d in ds.shape[1:]) or rows.size == 0:
        return []  # the check needs chunks of whole rows
    nonzero = np.logical_or.reduceat(rows.reshape(len(rows), -1).any(axis=1), np.arange(0, len(rows), chunk))
    lost = []
    for k in np.flatnonzero(~nonzero):
        first = start + int(k) * chunk
        try:
            ds.id.read_direct_chunk((first, *(0,) * (ds.ndim - 1)))
        except (OSError, RuntimeError, ValueError, KeyError):
            lost.append(first)
    return lost


def _unindexed_rows(ds: h5py.Dataset, n: int) -> list[int]:
    """The first rows of the chunks that the dataset's chunk index lacks or misplaces.

    HDF5 1.8's chunk index has no checksum: a damaged key hides a chunk, whose
    rows then read as the fill value without an error, or shows it at another
    place. Every row the store wrote has a chunk, so the chunks' first rows must
    be exactly 0, c, 2c, ... below ``n`` (c: rows per chunk).
    """
    if not ds.chunks or ds.size == 0:
        return []
    starts: list[int] = []
    try:
        ds.id.chunk_iter(lambda info: starts.append(int(info.chunk_offset[0])))
    except (OSError, RuntimeError, ValueError, AttributeError):
        return [0]
    expected = np.arange(0, n, ds.chunks[0])
    # chunks across a row: more than one where the chunking splits the other axes (h5py's own choice for a
    # large model array, e.g. the 3D blocks' 6 x 6 compliance)
    across = int(np.prod([-(-size // step) for size, step in zip(ds.shape[1:], ds.chunks[1:])]))
    found, counts = np.unique([s for s in starts if s < n], return_counts=True)
    wrong = set(np.setxor1d(expected, found).tolist()) | set(found[counts != across].tolist())
    return sorted(int(w) for w in wrong)


def ordered_prefix(values: np.ndarray, largest_step: int | None = None, allow_equal: bool = False
                   ) -> tuple[int, bool]:
    """Rows of ``values`` (steps, offsets) in order, and whether what follows them is damage.

    In order: each value above the previous one (or equal, ``allow_equal``:
    offsets of empty records), by at most ``largest_step`` where given
    (recorded steps follow each other by at most ``record_every``). Rows after
    the first one out of order are the zeros of a write that a kill or a full
    disk cut short (not damage) or, when any of them is not zero, damage.
    """
    if len(values) < 2:
        return len(values), False
    diff = np.diff(values)
    bad = diff < 0 if allow_equal else diff <= 0
    if largest_step is not None:
        bad |= diff > largest_step
    broken = np.flatnonzero(bad)
    if not len(broken):
        return len(values), False
    end = int(broken[0]) + 1
    return end, bool(np.any(values[end:] != 0))
