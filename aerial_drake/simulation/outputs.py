"""Writing a run's files so that no result is ever lost, partial or mixed with another run's.

- :func:`prepare_folder` checks, before anything is simulated, that the run folder can be
  created and written (not a file, not read-only) and takes its lock.
- :class:`FolderLock`: one run at a time per folder. An exclusive ``fcntl`` lock on
  ``.lock`` in the folder, released by the system when the process ends (even by SIGKILL,
  so a lock is never stale); a second run into a locked folder stops before simulating.
- :func:`write_atomically`: each file is written to a temporary name in the same folder and
  renamed into place (a rename is atomic on POSIX), so a reader sees the old file or the new
  one, never half of one.
- The set: the old ``metrics.json`` is removed first and the new one is renamed in last, so a
  folder holding ``metrics.json`` holds a complete set of one run; a write that fails (a full
  disk) removes what this run had put in place, leaving no result set rather than a mixed one.
- :func:`strict_json`: JSON with no NaN or Infinity (``allow_nan=False``): a non-finite
  figure is written as null.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from pathlib import Path
from typing import IO, Any, Callable

import numpy as np

try:
    import fcntl
except ImportError:  # not POSIX: no lock (documented)
    fcntl = None  # type: ignore[assignment]


class OutputError(OSError):
    """The output folder cannot be used (found before anything is simulated)."""


class ResultsNotWritten(OutputError):
    """A result file could not be written (a full disk); none of the run's files was left."""


def finite_or_none(value: Any) -> Any:
    """``value`` with every non-finite float (NaN, inf) replaced by None, recursively, numpy
    arrays as lists and complex numbers as ``[real, imag]`` (eigenvalues), ready for strict
    JSON."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, complex):
        return [finite_or_none(value.real), finite_or_none(value.imag)]
    if isinstance(value, dict):
        return {k: finite_or_none(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_or_none(v) for v in value]
    if isinstance(value, np.ndarray):
        return finite_or_none(value.tolist())
    if isinstance(value, np.generic):  # a numpy scalar
        return finite_or_none(value.item())
    return value


def strict_json(data: Any) -> str:
    """``data`` as strict JSON: NaN and infinities become null, never invalid JSON."""
    return json.dumps(finite_or_none(data), indent=2, allow_nan=False)


def write_atomically(path: Path, write: Callable[[IO[bytes]], object]) -> None:
    """Call ``write(file)`` on a temporary file beside ``path``, flush it to disk, and rename
    it to ``path``; on any failure the temporary file is removed and ``path`` is untouched."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # as open() would (mkstemp makes it private)
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_text_atomically(path: Path, text: str) -> None:
    write_atomically(path, lambda f: f.write(text.encode("utf-8")))


class FolderLock:
    """An exclusive lock on ``folder/.lock`` (module docstring); :meth:`release` or the end
    of the process frees it."""

    NAME = ".lock"

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self._file: IO[str] | None = None

    def acquire(self) -> None:
        path = self.folder / self.NAME
        try:
            f = open(path, "a+")
        except OSError as err:
            raise OutputError(f"output folder {self.folder} is not writable "
                              f"({err.strerror or err}): choose another --out") from None
        if fcntl is not None:
            try:
                fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                f.seek(0)
                holder = f.read().strip() or "another process"
                f.close()
                raise OutputError(
                    f"output folder {self.folder} is in use by another run ({holder}); "
                    "nothing was simulated or written: wait for it to finish, or give "
                    "another --out") from None
        f.seek(0)
        f.truncate()
        f.write(f"pid {os.getpid()}\n")
        f.flush()
        self._file = f

    def release(self) -> None:
        if self._file is not None:
            self._file.close()  # closing frees the flock
            self._file = None


def prepare_folder(folder: str | os.PathLike, need_mb: float = 0.0) -> FolderLock:
    """Create ``folder`` if needed, check it can be written and has ``need_mb`` MB free (the
    run's estimated files), and lock it; raises OutputError (before anything is simulated)
    naming the folder and the fix."""
    if isinstance(folder, bool) or not isinstance(folder, (str, os.PathLike)):
        raise OutputError(f"out_dir: expected a folder path, got {type(folder).__name__} "
                          f"{folder!r}")
    path = Path(folder)
    for parent in [path, *path.parents]:
        if parent.exists() and not parent.is_dir():
            raise OutputError(f"output folder {path}: {parent} is a file, not a folder: "
                              "choose another --out")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f"output folder {path} cannot be created ({err.strerror or err}): "
                          "choose another --out") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise OutputError(f"output folder {path} is not writable (permission denied): "
                          "choose another --out")
    free_mb = shutil.disk_usage(path).free / 1e6
    if free_mb < need_mb:
        raise OutputError(f"output folder {path} has {free_mb:.1f} MB free; the run's files "
                          f"need up to {need_mb:.1f} MB (estimated from duration / "
                          "log_period): free some space or choose another --out")
    lock = FolderLock(path)
    lock.acquire()
    return lock


def check_extra_names(files: Any, reserved: tuple[str, ...]) -> None:
    """Refuse (OutputError naming it, before anything is written) a name of ``files`` (``{name:
    text}``, written into a run's folder) that is not a plain file name there: empty, ``.``
    or ``..``, absolute, holding a path separator or a NUL, or one of the run's own files
    ``reserved`` (and the lock)."""
    if not isinstance(files, dict):
        raise OutputError(f"extra_files: expected a {{name: text}} dict, got "
                          f"{type(files).__name__}")
    for name, text in files.items():
        plain = (isinstance(name, str) and name not in ("", ".", "..")
                 and not any(c in name for c in ("/", "\\", os.sep, "\0"))
                 and not os.path.isabs(name))
        if not plain:
            raise OutputError(f"extra_files: {name!r} is not a plain file name in the run's "
                              "folder (no '..', no absolute path, no path separator); "
                              "nothing was written")
        if name in (*reserved, FolderLock.NAME) or name.endswith(".tmp"):
            raise OutputError(f"extra_files: {name!r} would replace the run's own file; "
                              "choose another name; nothing was written")
        if not isinstance(text, str):
            raise OutputError(f"extra_files: {name!r}: expected text (str), got "
                              f"{type(text).__name__}; nothing was written")


def write_result_set(folder: Path, files: list[tuple[str, Callable[[IO[bytes]], object]]],
                     last: tuple[str, Callable[[IO[bytes]], object]]) -> None:
    """Write ``files`` then ``last`` (the file whose presence says the set is complete) into
    ``folder``, each atomically; ``last`` of an earlier run is removed first. On a failure,
    the files this call put in place are removed too, and ResultsNotWritten is raised."""
    marker = folder / last[0]
    written: list[Path] = []
    try:
        marker.unlink(missing_ok=True)
        for name, write in [*files, last]:
            write_atomically(folder / name, write)
            written.append(folder / name)
    except OSError as err:
        for path in written:
            path.unlink(missing_ok=True)
        raise ResultsNotWritten(f"could not write the results into {folder} "
                          f"({err.strerror or err}); nothing of this run was left there "
                          "(no partial result set)") from None
