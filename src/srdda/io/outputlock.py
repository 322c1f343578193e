"""Holding an output: an OS lock on ``<output>.lock`` that names the run holding it (results files, ensembles).

The lock is advisory and the OS drops it when its holder dies, even by
SIGKILL, so a killed run never leaves a stale lock: its lock file may stay
(empty of meaning) and the next run takes it over. The holder writes into the
file who it is (pid, host, start time, command), which a refused run quotes.
"""
from __future__ import annotations

import datetime
import os
import socket
import sys
from pathlib import Path
from typing import IO

__all__ = ["ResultsWriteError", "OutputInUseError", "take_lock", "release_lock", "lock_holder"]


class ResultsWriteError(OSError):
    """An output cannot be written (folder not writable, disk full, ...); the message says what is kept.

    ``cut_short``: a flush failed half-way, so HDF5 may crash when Python exits
    (a program should end without running exit handlers: ``os._exit``).
    """

    cut_short: bool = False


class OutputInUseError(ResultsWriteError):
    """Another run is writing the output; the message names it (pid, host, start time, command)."""


try:  # an advisory lock the OS drops when its holder dies, even by SIGKILL: no stale locks
    import fcntl

    def _try_lock(fh: IO[str]) -> bool:
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True
except ImportError:  # Windows
    import msvcrt

    def _try_lock(fh: IO[str]) -> bool:
        fh.seek(0)  # every run locks the same (first) byte
        try:
            msvcrt.locking(fh.fileno(), msvcrt.LK_NBLCK, 1)  # type: ignore[attr-defined]  # typeshed: Windows only
        except OSError:
            return False
        return True


def take_lock(lock: Path, output: str) -> IO[str]:
    """Hold ``lock`` (an OS lock) and write who holds it; :class:`OutputInUseError` if another run does.

    ``output`` names what the lock guards, for the messages.
    """
    while True:
        try:
            fh = open(lock, "a+", encoding="utf-8")
        except OSError as exc:
            raise ResultsWriteError(f"{output}: cannot write in {lock.parent} ({exc.strerror})") from None
        try:
            locked = _try_lock(fh)
        except OSError as exc:  # a file system without locks (some network mounts)
            fh.close()
            raise ResultsWriteError(f"{output}: cannot lock {lock} ({exc.strerror}); write to a local disk") from None
        if not locked:
            fh.seek(0)
            holder = fh.read().strip() or "a run that has not said who it is yet"
            fh.close()
            raise OutputInUseError(f"{output} is being written by another run ({holder}); wait for it to end or "
                                   "write to another output")
        try:  # the previous holder may have removed the lock file between our open and our lock: retry
            if os.fstat(fh.fileno()).st_ino == os.stat(lock).st_ino:
                break
        except FileNotFoundError:
            pass
        fh.close()
    started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    fh.seek(0)
    fh.truncate()
    fh.write(f"pid {os.getpid()} on {socket.gethostname()}, started {started}, command: {' '.join(sys.argv)}\n")
    fh.flush()
    return fh


def release_lock(lock: Path, fh: IO[str]) -> None:
    """Remove ``lock`` while still holding it, then drop the lock.

    A lock file that cannot be removed (its folder was made read-only) is
    emptied: it names no holder, and the next run takes it over.
    """
    try:
        os.remove(lock)
    except OSError:
        try:
            fh.seek(0)
            fh.truncate()
        except OSError:
            pass
    fh.close()


def lock_holder(lock: Path) -> str | None:
    """Who holds ``lock`` now (its text), or None when no run does."""
    try:
        fh = open(lock, "r+", encoding="utf-8")
    except OSError:
        return None
    with fh:  # closing drops the lock this test may take
        try:
            if _try_lock(fh):
                return None
        except OSError:
            return None
        fh.seek(0)
        return fh.read().strip() or "a run that has not said who it is yet"
